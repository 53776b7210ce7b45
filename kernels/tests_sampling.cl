/* Kernels that only the sampling tests build (tests/bsdf_test.cpp, tests/light_sampling_test.cpp):
 * BSDF, light and camera sampling routines run one sample per work item, and the densities they claim
 * integrated over bins of directions for the chi-square tests.
 * Directions are binned in a frame (binning[0..2]: its x, y, z axes) by theta from z in [0, theta_max] and
 * phi = atan2(y, x) in [0, 2 pi), with binning[3] = (theta_max, theta_bins, phi_bins, -); bin
 * t * phi_bins + p covers [t, t + 1) theta_max / theta_bins x [p, p + 1) 2 pi / phi_bins.
 * Random numbers: pcg4d of (item, seed, two constants), as the samplers hash. */
#include "shared/types.h"
#include "shared/light_types.h"
#include "math.cl"
#include "rng.cl"
#include "sampler.cl"
#include "sampling.cl"
#include "scene.cl"
#include "camera.cl"
#include "intersect.cl"
#include "surface.cl"
#include "bsdf.cl"
#include "environment.cl"
#include "lights.cl"
#include "emission.cl"
#include "camera_importance.cl"

static inline float4 test_random4(uint item, uint seed) {
  uint4 v = pcg4d((uint4)(item, seed, 0x9e3779b9u, 0x85ebca6bu));
  return convert_float4(v >> 8u) * 0x1.0p-24f;
}

/* Quadrature node (i, j) of bin `bin` with Gauss-Legendre nodes/weights on [0, 1]: the direction, and
 * in *w the node's weight times the Jacobian sin(theta) dtheta dphi. */
static inline float3 bin_node(__global const float4* binning, uint bin, __global const float* nodes,
                              __global const float* weights, uint i, uint j, float* w) {
  uint theta_bins = (uint)binning[3].y, phi_bins = (uint)binning[3].z;
  float dt = binning[3].x / (float)theta_bins, dp = 2.0f * PC_PI / (float)phi_bins;
  float theta = ((float)(bin / phi_bins) + nodes[i]) * dt;
  float phi = ((float)(bin % phi_bins) + nodes[j]) * dp;
  float2 c, s2 = pc_sincos((float2)(theta, phi), &c);
  float s = s2.x;
  *w = weights[i] * weights[j] * s * dt * dp;
  return s * c.y * binning[0].xyz + s * s2.y * binning[1].xyz + c.x * binning[2].xyz;
}

/* ---- BSDFs ---- */

/* One bsdf_sample per item, u from the hash (or from u_in when use_u_in). out: 12 floats per item:
 * wi (3), status (0 failed, 1 sampled, 2 sampled from a delta lobe), pdf as sampled, bsdf_pdf(wo, wi),
 * weight (3), bsdf_eval(wo, wi) (3). A failed sample writes zeros. */
__kernel void bsdf_sample_test(__global const Material* material, float4 wo4, uint seed,
                               __global const float4* u_in, uint use_u_in, __global float* out) {
  uint i = get_global_id(0);
  Material m = material[0];
  float3 wo = wo4.xyz;
  float4 u = use_u_in ? u_in[i] : test_random4(i, seed);
  BsdfSample s;
  bool ok = bsdf_sample(m, wo, u.xyz, &s);
  __global float* o = out + 12 * i;
  for (int k = 0; k < 12; ++k) o[k] = 0.0f;
  if (!ok) return;
  vstore3(s.wi, 0, o);
  o[3] = s.delta ? 2.0f : 1.0f;
  o[4] = s.pdf;
  o[5] = bsdf_pdf(m, wo, s.wi);
  vstore3(s.weight, 0, o + 6);
  vstore3(bsdf_eval(m, wo, s.wi), 0, o + 9);
}

/* Integral of bsdf_pdf(wo, .) over each listed bin by order x order Gauss-Legendre. out: 2 floats per
 * bin, the integral and 1 where the density is 0 at some nodes and not at others (an edge in the bin). */
__kernel void bsdf_pdf_bins(__global const Material* material, float4 wo4, __global const float4* binning,
                            __global const uint* bins, uint order, __global const float* nodes,
                            __global const float* weights, __global float* out) {
  uint b = get_global_id(0);
  Material m = material[0];
  float sum = 0.0f;
  uint zeros = 0;
  for (uint i = 0; i < order; ++i) {
    float row = 0.0f;
    for (uint j = 0; j < order; ++j) {
      float w;
      float3 wi = bin_node(binning, bins[b], nodes, weights, i, j, &w);
      float p = bsdf_pdf(m, wo4.xyz, wi);
      zeros += p == 0.0f;
      row += w * p;
    }
    sum += row;
  }
  out[2 * b] = sum;
  out[2 * b + 1] = zeros > 0 && zeros < order * order ? 1.0f : 0.0f;
}

/* fresnel_dielectric per (cos_i, eta) pair. */
__kernel void fresnel_dielectric_test(__global const float2* in, __global float* out) {
  uint i = get_global_id(0);
  out[i] = fresnel_dielectric(in[i].x, in[i].y);
}

/* fresnel_conductor per cos_i, for one (eta, k). */
__kernel void fresnel_conductor_test(__global const float* cos_i, float4 eta, float4 k, __global float4* out) {
  uint i = get_global_id(0);
  out[i] = (float4)(float3_of(fresnel_conductor(cos_i[i], lane3_of(eta.xyz), lane3_of(k.xyz))), 0.0f);
}

/* ---- Lights (the scene arguments as the render kernel takes them, PC_SCENE_PARAMS of scene.cl) ---- */

/* The density with which light sampling from x produces direction d, found the way a BSDF-sampled ray
 * finds it (as the integrator's MIS does): trace the ray; an emitter hit gives light_pdf there, an
 * escape gives the environment's pdf. *le: the radiance seen along d (first channel). */
static inline float direction_light_pdf(const SceneData* sc, float3 x, float3 d, float* le) {
  Ray ray;
  ray.o = x;
  ray.d = d;
  ray.tmin = 0.0f;
  ray.tmax = INFINITY;
  ray.skip_prim = PC_INVALID;
  ray.skip_instance = PC_INVALID;
  Hit hit;
  *le = 0.0f;
  if (trace_scene(sc, 0, &ray, false, &hit)) {
    Surface s = scene_surface(sc, &ray, &hit);
    PrimShading sh = sc->shading[s.prim];
    if (sh.light == PC_INVALID) return 0.0f;
    *le = emitted_towards(sc->lights[sh.light].emission.xyz, sh.flags, s.ng, s.p, x).x;
    return light_pdf(sc, sh.light, x, s.p, s.ng);
  }
  if (sc->h->env_light == PC_INVALID) return 0.0f;
  *le = env_radiance(sc->lights[sc->h->env_light], sc->textures, sc->texels, d).x;
  return environment_light_pdf(sc, x, d);
}

/* One sample_light from x per item. out: 12 floats per item: wi (3), status (0 failed, 1 sampled,
 * 2 delta; a failed sample has only wi, 0 if none), pdf, direction_light_pdf(wi), Le (3), radiance seen along wi (first channel), distance to
 * the sampled point p, distance to the first hit along wi (+inf for none). */
__kernel void light_sample_test(PC_SCENE_PARAMS, float4 x4, uint seed, __global float* out) {
  uint i = get_global_id(0);
  SceneData sc = PC_SCENE_DATA;
  float3 x = x4.xyz;
  float4 u = test_random4(i, seed);
  LightSample ls;
  ls.wi = (float3)(0.0f);
  bool ok = sample_light(&sc, x, u.xyz, &ls);
  __global float* o = out + 12 * i;
  for (int k = 0; k < 12; ++k) o[k] = 0.0f;
  /* A failed sample keeps the direction it was drawn at, if any (an environment map's sample where the
   * radiance is 0 is one), so that tests can bin it. */
  vstore3(ls.wi, 0, o);
  if (!ok) return;
  o[3] = ls.delta ? 2.0f : 1.0f;
  o[4] = ls.pdf;
  float le;
  o[5] = ls.delta ? 0.0f : direction_light_pdf(&sc, x, ls.wi, &le);
  vstore3(ls.Le, 0, o + 6);
  o[9] = ls.delta ? 0.0f : le;
  o[10] = ls.infinite ? INFINITY : pc_length(ls.p - x);
  Ray ray;
  ray.o = x;
  ray.d = ls.wi;
  ray.tmin = 0.0f;
  ray.tmax = INFINITY;
  ray.skip_prim = PC_INVALID;
  ray.skip_instance = PC_INVALID;
  Hit hit;
  o[11] = trace_scene(&sc, 0, &ray, false, &hit) ? hit.t : INFINITY;
}

/* Integral of direction_light_pdf(x, .) over each listed bin by order x order Gauss-Legendre; out as
 * bsdf_pdf_bins writes it. */
__kernel void light_pdf_bins(PC_SCENE_PARAMS, float4 x4, __global const float4* binning, __global const uint* bins,
                             uint order, __global const float* gl_nodes, __global const float* gl_weights,
                             __global float* out) {
  uint b = get_global_id(0);
  SceneData sc = PC_SCENE_DATA;
  float sum = 0.0f;
  uint zeros = 0;
  for (uint i = 0; i < order; ++i) {
    float row = 0.0f;
    for (uint j = 0; j < order; ++j) {
      float w, le;
      float3 d = bin_node(binning, bins[b], gl_nodes, gl_weights, i, j, &w);
      float p = direction_light_pdf(&sc, x4.xyz, d, &le);
      zeros += p == 0.0f;
      row += w * p;
    }
    sum += row;
  }
  out[2 * b] = sum;
  out[2 * b + 1] = zeros > 0 && zeros < order * order ? 1.0f : 0.0f;
}

/* ---- Samplers ---- */

/* sample4(h, key, group) for samples 0 .. n - 1 of one pixel: item i is sample i. */
__kernel void sampler_points_test(__constant const SceneHeader* h, uint pixel, uint seed, uint group,
                                  __global float4* out) {
  uint i = get_global_id(0);
  SampleKey key = {pixel, i, seed};
  out[i] = sample4(h, key, group);
}

/* The unscrambled Sobol points of index[i] in dimensions 1, 2 and 3, bit-reversed, at one, 8 and 16 lanes:
 * out[9 i + 3 w + d - 1] for width w (0: one lane, 1: 8, 2: 16). At 8 and 16 lanes index[i] is lane i % N
 * of a vector whose other lanes hold its neighbours' indices (n of them in all). */
#define PC_SOBOL_BITS_TEST(U, N, LOAD, STORE)                                                              \
  static inline void sobol_bits_test_##N(__global const uint* index, uint n, uint i, __global uint* out) { \
    uint in[N], x[3][N];                                                                                   \
    for (uint j = 0u; j < N; ++j) in[j] = index[(i - i % N + j) % n];                                      \
    U v = LOAD(0, in), x2, x3;                                                                             \
    sobol23_reversed(v, &x2, &x3);                                                                         \
    STORE(sobol1_reversed(v), 0, x[0]), STORE(x2, 0, x[1]), STORE(x3, 0, x[2]);                            \
    for (uint d = 0u; d < 3u; ++d) out[d] = x[d][i % N];                                                   \
  }
PC_SOBOL_BITS_TEST(uint8, 8, vload8, vstore8)
PC_SOBOL_BITS_TEST(uint16, 16, vload16, vstore16)
#undef PC_SOBOL_BITS_TEST
__kernel void sobol_bits_test(__global const uint* index, uint n, __global uint* out) {
  uint i = get_global_id(0), x2, x3;
  sobol23_reversed(index[i], &x2, &x3);
  out[9u * i] = sobol1_reversed(index[i]), out[9u * i + 1u] = x2, out[9u * i + 2u] = x3;
  sobol_bits_test_8(index, n, i, out + 9u * i + 3u);
  sobol_bits_test_16(index, n, i, out + 9u * i + 6u);
}

/* Camera rays and warps over 16 and 8 lanes against one lane (camera.cl, sampling.cl): item i takes the 16
 * lanes px/py[16 i + lane], u[4 (16 i + lane) ..]; per lane and width w (0: 16 lanes, 1: 8, 2: one) it
 * writes 16 results as bits at out[((3 i + w) 16 + lane) 16 + k]: ray origin (3) and direction (3) for
 * (px, py, u), and from (u.x, u.y) the disk point (2), cosine (3) and sphere (3) directions and
 * triangle barycentrics (2). */
#define PC_CAMERA_LANES_TEST(F, U, V3, N, LOAD, STORE)                                                   \
  static inline void camera_lanes_write_##N(__constant const SceneHeader* h, U px, U py, F u0, F u1, F u2, F u3, \
                                            __global uint* o) {                                           \
    V3 ro, rd;                                                                                            \
    camera_ray_lanes(h, px, py, u0, u1, u2, u3, &ro, &rd);                                                \
    F r[16];                                                                                              \
    r[0] = ro.x, r[1] = ro.y, r[2] = ro.z, r[3] = rd.x, r[4] = rd.y, r[5] = rd.z;                         \
    sample_concentric_disk_lanes(u0, u1, &r[6], &r[7]);                                                   \
    sample_cosine_hemisphere_lanes(u0, u1, &r[8], &r[9], &r[10]);                                         \
    sample_uniform_sphere_lanes(u0, u1, &r[11], &r[12], &r[13]);                                          \
    sample_uniform_triangle_lanes(u0, u1, &r[14], &r[15]);                                                \
    for (uint k = 0u; k < 16u; ++k) {                                                                     \
      float v[N];                                                                                         \
      STORE(r[k], v);                                                                                     \
      for (uint lane = 0u; lane < N; ++lane) o[16u * lane + k] = as_uint(v[lane]);                        \
    }                                                                                                     \
  }
#define PC_STORE_LANES_1(x, p) (p)[0] = (x)
#define PC_STORE_LANES_8(x, p) vstore8(x, 0, p)
#define PC_STORE_LANES_16(x, p) vstore16(x, 0, p)
/* Results r[0 .. COUNT) of N lanes written as bits, lane j's at o[COUNT j ..]. */
#define PC_WRITE_LANE_RESULTS(r, COUNT, N, STORE, o)                                                      \
  for (uint k = 0u; k < COUNT; ++k) {                                                                     \
    float x[N];                                                                                           \
    STORE(r[k], x);                                                                                       \
    for (uint j = 0u; j < N; ++j) o[COUNT * j + k] = as_uint(x[j]);                                       \
  }
PC_CAMERA_LANES_TEST(float, uint, lane3f, 1, , PC_STORE_LANES_1)
PC_CAMERA_LANES_TEST(float8, uint8, lane3f8, 8, , PC_STORE_LANES_8)
PC_CAMERA_LANES_TEST(float16, uint16, lane3f16, 16, , PC_STORE_LANES_16)

__kernel void camera_lanes_test(__constant const SceneHeader* h, __global const uint* px, __global const uint* py,
                                __global const float* u, __global uint* out) {
  uint i = get_global_id(0);
  __global uint* o = out + i * 3u * 256u;
  float uc[4][16];
  for (uint lane = 0u; lane < 16u; ++lane)
    for (uint k = 0u; k < 4u; ++k) uc[k][lane] = u[4u * (16u * i + lane) + k];
  float16 a = vload16(0, uc[0]), b = vload16(0, uc[1]), c = vload16(0, uc[2]), d = vload16(0, uc[3]);
  uint16 x = vload16(i, px), y = vload16(i, py);
  camera_lanes_write_16(h, x, y, a, b, c, d, o);
  camera_lanes_write_8(h, x.lo, y.lo, a.lo, b.lo, c.lo, d.lo, o + 256u);
  camera_lanes_write_8(h, x.hi, y.hi, a.hi, b.hi, c.hi, d.hi, o + 256u + 128u);
  for (uint lane = 0u; lane < 16u; ++lane)
    camera_lanes_write_1(h, px[16u * i + lane], py[16u * i + lane], uc[0][lane], uc[1][lane], uc[2][lane], uc[3][lane],
                         o + 512u + 16u * lane);
}

/* make_frame, offset_ray_origin, power_heuristic and its rounding step over 16, 8 and one lane (math.cl): lane
 * j of item i reads 15 floats at in[15 (16 i + j)]: n (3), err (3), p (3), w (3), pdf_a, pdf_b, x, and writes
 * 13 results as bits at out[((3 i + width) 16 + j) 13 + k] (width 0: 16 lanes, 1: 8, 2: one): t, b, the
 * offset origin (3 each), the weight, and pc_offset_component_ of x with offsets 2^-149, -2^-149 and 0. */
#define PC_MATH_LANES_TEST(V3, F, N, LOAD, STORE)                                                         \
  static inline void math_lanes_write_##N(float in[15][16], uint first, __global uint* o) {             \
    F v[15];                                                                                              \
    for (uint k = 0u; k < 15u; ++k) v[k] = LOAD(in[k] + first);                                           \
    V3 t, b;                                                                                              \
    make_frame(lane3(v[0], v[1], v[2]), &t, &b);                                                          \
    V3 po = offset_ray_origin(lane3(v[6], v[7], v[8]), lane3(v[3], v[4], v[5]), lane3(v[0], v[1], v[2]),   \
                              lane3(v[9], v[10], v[11]));                                                 \
    F r[13] = {t.x, t.y, t.z, b.x, b.y, b.z, po.x, po.y, po.z, power_heuristic(v[12], v[13]),            \
               pc_offset_component_(v[14], (F)(0x1p-149f)), pc_offset_component_(v[14], (F)(-0x1p-149f)),   \
               pc_offset_component_(v[14], (F)(0.0f))};                                                   \
    PC_WRITE_LANE_RESULTS(r, 13u, N, STORE, o);                                                           \
  }
#define PC_LOAD_LANES_1(p) (p)[0]
#define PC_LOAD_LANES_8(p) vload8(0, p)
#define PC_LOAD_LANES_16(p) vload16(0, p)
PC_MATH_LANES_TEST(lane3f, float, 1, PC_LOAD_LANES_1, PC_STORE_LANES_1)
PC_MATH_LANES_TEST(lane3f8, float8, 8, PC_LOAD_LANES_8, PC_STORE_LANES_8)
PC_MATH_LANES_TEST(lane3f16, float16, 16, PC_LOAD_LANES_16, PC_STORE_LANES_16)

/* The diffuse, Oren-Nayar and Phong lobes over 16, 8 and one lane (bsdf_diffuse.cl, bsdf_oren_nayar.cl,
 * bsdf_phong.cl): lane j of item i reads 17 floats at in[17 (16 i + j)]: the colour (3), sigma, wo (3), wi
 * (3), u (3), the specular colour (3) and exponent, and writes 36 results as bits at
 * out[((3 i + width) 16 + j) 36 + k] (width 0: 16 lanes, 1: 8, 2: one): per lobe eval (3), pdf, the
 * sample's wi (3), pdf, weight (3) and validity (1 or 0). */
#define PC_BSDF_LANES_TEST(V3, F, N, LOAD, STORE)                                                         \
  static inline void bsdf_lanes_write_##N(float in[17][16], uint first, __global uint* o) {             \
    F v[17];                                                                                              \
    for (uint k = 0u; k < 17u; ++k) v[k] = LOAD(in[k] + first);                                           \
    V3 c = lane3(v[0], v[1], v[2]), wo = lane3(v[4], v[5], v[6]), wi = lane3(v[7], v[8], v[9]);           \
    V3 sc = lane3(v[13], v[14], v[15]);                                                                   \
    F n = v[16];                                                                                          \
    V3 e[3] = {diffuse_eval_lanes(c, wi), oren_nayar_eval_lanes(c, v[3], wo, wi), phong_eval_lanes(c, sc, n, wo, wi)}; \
    F p[3] = {diffuse_pdf_lanes(wi), oren_nayar_pdf_lanes(wi), phong_pdf_lanes(c, sc, n, wo, wi)};        \
    V3 w[3], g[3];                                                                                        \
    F q[3], ok[3];                                                                                        \
    ok[0] = select((F)(0.0f), (F)(1.0f), diffuse_sample_lanes(c, v[10], v[11], &w[0], &q[0], &g[0]));     \
    ok[1] = select((F)(0.0f), (F)(1.0f), oren_nayar_sample_lanes(c, v[3], wo, v[10], v[11], &w[1], &q[1], &g[1])); \
    ok[2] = select((F)(0.0f), (F)(1.0f),                                                                  \
                   phong_sample_lanes(c, sc, n, wo, v[10], v[11], v[12], &w[2], &q[2], &g[2]));           \
    F r[36];                                                                                              \
    for (uint l = 0u; l < 3u; ++l) {                                                                      \
      F lobe[12] = {e[l].x, e[l].y, e[l].z, p[l], w[l].x, w[l].y, w[l].z, q[l], g[l].x, g[l].y, g[l].z, ok[l]}; \
      for (uint k = 0u; k < 12u; ++k) r[12u * l + k] = lobe[k];                                           \
    }                                                                                                     \
    PC_WRITE_LANE_RESULTS(r, 36u, N, STORE, o);                                                           \
  }
PC_BSDF_LANES_TEST(lane3f, float, 1, PC_LOAD_LANES_1, PC_STORE_LANES_1)
PC_BSDF_LANES_TEST(lane3f8, float8, 8, PC_LOAD_LANES_8, PC_STORE_LANES_8)
PC_BSDF_LANES_TEST(lane3f16, float16, 16, PC_LOAD_LANES_16, PC_STORE_LANES_16)

/* The mirror, dielectric, rough conductor and plastic lobes over 16, 8 and one lane (bsdf_mirror.cl,
 * bsdf_dielectric.cl, bsdf_rough_conductor.cl, bsdf_plastic.cl): lane j of item i reads 20 floats at
 * in[20 (16 i + j)]: the colour (3), ior, alpha, the conductor's eta (3) and k (3), wo (3), wi (3) and u
 * (3), and writes 56 results as bits at out[((3 i + width) 16 + j) 56 + k]: per lobe eval (3), pdf, the
 * sample's wi (3), pdf, weight (3), validity, delta (1 or 0) and eta2 (the delta lobes' eval and pdf,
 * and all but the dielectric's eta2, are written as 0, 0 and 1). */
#define PC_FRESNEL_LOBES_LANES_TEST(V3, F, I, N, LOAD, STORE)                                             \
  static inline void fresnel_lobes_lanes_write_##N(float in[20][16], uint first, __global uint* o) {      \
    F v[20];                                                                                              \
    for (uint k = 0u; k < 20u; ++k) v[k] = LOAD(in[k] + first);                                           \
    V3 c = lane3(v[0], v[1], v[2]), eta = lane3(v[5], v[6], v[7]), kk = lane3(v[8], v[9], v[10]);         \
    V3 wo = lane3(v[11], v[12], v[13]), wi = lane3(v[14], v[15], v[16]);                                  \
    F ior = v[3], alpha = v[4];                                                                           \
    V3 zero = lane3((F)(0.0f), (F)(0.0f), (F)(0.0f));                                                     \
    V3 e[4] = {zero, zero, rough_conductor_eval_lanes(eta, kk, alpha, wo, wi),                            \
               plastic_eval_lanes(c, ior, alpha, wo, wi)};                                                \
    F p[4] = {(F)(0.0f), (F)(0.0f), rough_conductor_pdf_lanes(alpha, wo, wi),                             \
              plastic_pdf_lanes(c, ior, alpha, wo, wi)};                                                  \
    V3 w[4], g[4];                                                                                        \
    F q[4], eta2[4] = {(F)(1.0f), (F)(1.0f), (F)(1.0f), (F)(1.0f)};                                       \
    I ok[4], delta[4] = {(I)(-1), (I)(-1), (I)(0), (I)(0)};                                               \
    ok[0] = mirror_sample_lanes(c, wo, &w[0], &q[0], &g[0]);                                              \
    ok[1] = dielectric_sample_lanes(c, ior, wo, v[19], &w[1], &q[1], &g[1], &eta2[1]);                    \
    ok[2] = rough_conductor_sample_lanes(eta, kk, alpha, wo, v[17], v[18], &w[2], &q[2], &g[2]);          \
    ok[3] = plastic_sample_lanes(c, ior, alpha, wo, v[17], v[18], v[19], &w[3], &q[3], &g[3], &delta[3]); \
    F r[56];                                                                                              \
    for (uint l = 0u; l < 4u; ++l) {                                                                      \
      F lobe[14] = {e[l].x, e[l].y, e[l].z, p[l], w[l].x, w[l].y, w[l].z, q[l], g[l].x, g[l].y, g[l].z,    \
                    select((F)(0.0f), (F)(1.0f), ok[l]), select((F)(0.0f), (F)(1.0f), delta[l]), eta2[l]}; \
      for (uint k = 0u; k < 14u; ++k) r[14u * l + k] = lobe[k];                                           \
    }                                                                                                     \
    PC_WRITE_LANE_RESULTS(r, 56u, N, STORE, o);                                                           \
  }
PC_FRESNEL_LOBES_LANES_TEST(lane3f, float, int, 1, PC_LOAD_LANES_1, PC_STORE_LANES_1)
PC_FRESNEL_LOBES_LANES_TEST(lane3f8, float8, int8, 8, PC_LOAD_LANES_8, PC_STORE_LANES_8)
PC_FRESNEL_LOBES_LANES_TEST(lane3f16, float16, int16, 16, PC_LOAD_LANES_16, PC_STORE_LANES_16)

/* The kernel NAME_test of a lane test over float inputs: lane j of item i reads IN floats at
 * in[IN (16 i + j)], and NAME_write_N (N = 16, 8, 1) writes OUT results per lane at 16 lanes, at 8 (two
 * halves) and at one lane (each alone), item i's at out[3 i 16 OUT ..] in that order. */
#define PC_FLOAT_LANES_TEST_KERNEL(name, IN, OUT)                                                         \
  __kernel void name##_test(__global const float* in, __global uint* out) {                               \
    uint i = get_global_id(0);                                                                            \
    float v[IN][16];                                                                                      \
    for (uint j = 0u; j < 16u; ++j)                                                                       \
      for (uint k = 0u; k < IN; ++k) v[k][j] = in[IN * (16u * i + j) + k];                                \
    __global uint* o = out + i * 48u * OUT;                                                               \
    name##_write_16(v, 0u, o);                                                                            \
    name##_write_8(v, 0u, o + 16u * OUT);                                                                 \
    name##_write_8(v, 8u, o + 24u * OUT);                                                                 \
    for (uint j = 0u; j < 16u; ++j) name##_write_1(v, j, o + 32u * OUT + OUT * j);                        \
  }
PC_FLOAT_LANES_TEST_KERNEL(math_lanes, 15u, 13u)
PC_FLOAT_LANES_TEST_KERNEL(bsdf_lanes, 17u, 36u)
PC_FLOAT_LANES_TEST_KERNEL(fresnel_lobes_lanes, 20u, 56u)
#undef PC_FLOAT_LANES_TEST_KERNEL

/* The samplers over 16 and 8 lanes against one lane (sampler.cl, sample4_lanes): item i takes the 16 keys
 * pixel/sample/group[16 i .. 16 i + 15] and writes, per lane, its four numbers at 16 lanes, at 8 lanes
 * (two halves) and at one lane, as bits, at out[((3 i + w) 16 + lane) 4 + k] for w = 0 (16 lanes), 1 (8)
 * and 2 (one). */
__kernel void sampler_lanes_test(__constant const SceneHeader* h, __global const uint* pixel, __global const uint* sample,
                                 __global const uint* group, uint seed, __global uint* out) {
  uint i = get_global_id(0);
  uint16 p = vload16(i, pixel), s = vload16(i, sample), g = vload16(i, group);
  __global uint* o = out + i * 3u * 64u;
  float16 a[4];
  sample4_lanes(h, p, s, seed, g, &a[0], &a[1], &a[2], &a[3]);
  float8 lo[4], hi[4];
  sample4_lanes(h, p.lo, s.lo, seed, g.lo, &lo[0], &lo[1], &lo[2], &lo[3]);
  sample4_lanes(h, p.hi, s.hi, seed, g.hi, &hi[0], &hi[1], &hi[2], &hi[3]);
  for (uint k = 0u; k < 4u; ++k) {
    float v16[16], v8[16];
    vstore16(a[k], 0, v16);
    vstore8(lo[k], 0, v8);
    vstore8(hi[k], 1, v8);
    for (uint lane = 0u; lane < 16u; ++lane) {
      o[lane * 4u + k] = as_uint(v16[lane]);
      o[64u + lane * 4u + k] = as_uint(v8[lane]);
    }
  }
  for (uint lane = 0u; lane < 16u; ++lane) {
    float x, y, z, w;
    sample4_lanes(h, pixel[16u * i + lane], sample[16u * i + lane], seed, group[16u * i + lane], &x, &y, &z, &w);
    o[128u + lane * 4u] = as_uint(x);
    o[128u + lane * 4u + 1u] = as_uint(y);
    o[128u + lane * 4u + 2u] = as_uint(z);
    o[128u + lane * 4u + 3u] = as_uint(w);
  }
}

/* ---- Camera ---- */

/* sample_filter_1d per item, u from the hash. */
__kernel void filter_sample_test(__constant const SceneHeader* h, uint seed, __global float* out) {
  uint i = get_global_id(0);
  out[i] = sample_filter_1d(h, test_random4(i, seed).x);
}

/* camera_ray for pixel (px, py) with the pixel position u.xy fixed and the lens position hashed, or
 * with everything hashed when u_pixel.x < 0. out: origin (3), direction (3) per item. */
__kernel void camera_ray_test(__constant const SceneHeader* h, uint px, uint py, float2 u_pixel, uint seed,
                              __global float* out) {
  uint i = get_global_id(0);
  float4 u = test_random4(i, seed);
  if (u_pixel.x >= 0.0f) u.xy = u_pixel;
  float3 o, d;
  camera_ray(h, px, py, u, &o, &d);
  vstore3(o, 0, out + 6 * i);
  vstore3(d, 0, out + 6 * i + 3);
}

/* The light choice from x (kernels/light_tree.cl): item i chooses with u = its first random number and
 * writes the light's index and the probability it reports; items below light_count also write
 * light_choice_pdf(x, i), so that the host can check the counts against it. */
__kernel void light_choice_test(PC_SCENE_PARAMS, float4 x4, uint seed, __global uint* chosen, __global float* p,
                                __global float* pdf_of_light) {
  uint i = get_global_id(0);
  SceneData sc = PC_SCENE_DATA;
  uint index = PC_INVALID;
  p[i] = light_choice(&sc, x4.xyz, PC_INVALID, test_random4(i, seed).x, &index);
  chosen[i] = index;
  if (i < h->light_count) pdf_of_light[i] = light_choice_pdf(&sc, x4.xyz, i);
}

/* ---- The surface a ray meets (trace_scene, scene_surface; with instances the placed surface) ---- */

/* Per ray of rays: t (+inf for a miss), p (3), ng (3), ns (3), the largest component of p_err, the
 * instance: 12 floats. No cut-outs (their stochastic choice differs between instances and copies). */
__kernel void scene_hit_test(PC_SCENE_PARAMS, __global const RayRecord* rays, __global float* out) {
  uint i = get_global_id(0);
  SceneData sc = PC_SCENE_DATA;
  Ray ray = ray_from_record(rays + i);
  __global float* o = out + 12 * i;
  for (int k = 0; k < 12; ++k) o[k] = 0.0f;
  Hit hit;
  if (!trace_scene(&sc, 0, &ray, false, &hit)) {
    o[0] = INFINITY;
    return;
  }
  Surface s = scene_surface(&sc, &ray, &hit);
  o[0] = hit.t;
  vstore3(s.p, 0, o + 1);
  vstore3(s.ng, 0, o + 4);
  vstore3(s.ns, 0, o + 7);
  o[10] = max_component(s.p_err);
  o[11] = (float)s.instance;
}

/* ---- Emission (emission.cl) and camera importance (camera_importance.cl) ---- */

/* One sample_emission per item, its six numbers from two hashes. out: 16 floats per item: p (3), n (3),
 * d (3), status (0 failed, 1 sampled), pdf_choice, pdf_pos, pdf_dir, light_emission_pdf(p, n, d) of the
 * light it chose (pos, dir), the light's index. A failed sample writes zeros. */
__kernel void emission_sample_test(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt,
                                   __global const float* emission_cdf, uint seed, __global float* out) {
  uint i = get_global_id(0);
  SceneData sc = PC_SCENE_DATA;
  float4 u = test_random4(i, seed), v = test_random4(i, seed ^ 0x5bd1e995u);
  EmissionSample e;
  bool ok = sample_emission(&sc, lt, emission_cdf, u.x, u.yzw, v.xy, &e);
  __global float* o = out + 16 * i;
  for (int k = 0; k < 16; ++k) o[k] = 0.0f;
  if (!ok) return;
  vstore3(e.p, 0, o);
  vstore3(e.n, 0, o + 3);
  vstore3(e.d, 0, o + 6);
  o[9] = 1.0f;
  o[10] = e.pdf_choice;
  o[11] = e.pdf_pos;
  o[12] = e.pdf_dir;
  float pdf_pos, pdf_dir;
  light_emission_pdf(&sc, lt, e.light, e.p, e.n, e.d, &pdf_pos, &pdf_dir);
  o[13] = pdf_pos;
  o[14] = pdf_dir;
  o[15] = (float)e.light;
}

/* Integral over each listed bin of the directional density light_emission_pdf of light `index` at point
 * p with normal n; out as bsdf_pdf_bins writes it. */
__kernel void emission_pdf_bins(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, uint index, float4 p,
                                float4 n, __global const float4* binning, __global const uint* bins, uint order,
                                __global const float* gl_nodes, __global const float* gl_weights, __global float* out) {
  uint b = get_global_id(0);
  SceneData sc = PC_SCENE_DATA;
  float sum = 0.0f;
  uint zeros = 0;
  for (uint i = 0; i < order; ++i) {
    float row = 0.0f;
    for (uint j = 0; j < order; ++j) {
      float w, pdf_pos, pdf_dir;
      float3 d = bin_node(binning, bins[b], gl_nodes, gl_weights, i, j, &w);
      light_emission_pdf(&sc, lt, index, p.xyz, n.xyz, d, &pdf_pos, &pdf_dir);
      zeros += pdf_dir == 0.0f;
      row += w * pdf_dir;
    }
    sum += row;
  }
  out[2 * b] = sum;
  out[2 * b + 1] = zeros > 0 && zeros < order * order ? 1.0f : 0.0f;
}

/* Camera rays with the image position uniform over the image (any filter: the pixel from the hash, the
 * offset through the filter) and the lens point fixed at u_lens. out: 12 floats per item: o (3), d (3),
 * the image position camera_ray drew (2, without the filter: pixel + 0.5 + offset), camera_raster of
 * (o, d) (2), camera_pdf_we's pdf_dir, camera_we (We x cos^4 x lens area / (W H) = 1 / A is its shape). */
__kernel void camera_we_test(__constant const SceneHeader* h, float2 u_lens, uint seed, __global float* out) {
  uint i = get_global_id(0);
  float4 u = test_random4(i, seed), v = test_random4(i, seed ^ 0x5bd1e995u);
  uint px = min((uint)(u.x * (float)h->width), h->width - 1u), py = min((uint)(u.y * (float)h->height), h->height - 1u);
  float3 o, d;
  camera_ray(h, px, py, (float4)(v.x, v.y, u_lens.x, u_lens.y), &o, &d);
  __global float* w = out + 12 * i;
  vstore3(o, 0, w);
  vstore3(d, 0, w + 3);
  w[6] = (float)px + 0.5f + sample_filter_1d(h, v.x);
  w[7] = (float)py + 0.5f + sample_filter_1d(h, v.y);
  float2 raster;
  float pdf_pos, pdf_dir;
  w[11] = camera_we(h, o, d, &raster);
  w[8] = raster.x;
  w[9] = raster.y;
  camera_pdf_we(h, o, d, &pdf_pos, &pdf_dir);
  w[10] = pdf_dir;
}

/* Integral of camera_pdf_we's pdf_dir from lens point o over each listed bin; out as bsdf_pdf_bins. */
__kernel void camera_we_pdf_bins(__constant const SceneHeader* h, float4 o, __global const float4* binning,
                                 __global const uint* bins, uint order, __global const float* gl_nodes,
                                 __global const float* gl_weights, __global float* out) {
  uint b = get_global_id(0);
  float sum = 0.0f;
  uint zeros = 0;
  for (uint i = 0; i < order; ++i) {
    float row = 0.0f;
    for (uint j = 0; j < order; ++j) {
      float w, pdf_pos, pdf_dir;
      float3 d = bin_node(binning, bins[b], gl_nodes, gl_weights, i, j, &w);
      camera_pdf_we(h, o.xyz, d, &pdf_pos, &pdf_dir);
      zeros += pdf_dir == 0.0f;
      row += w * pdf_dir;
    }
    sum += row;
  }
  out[2 * b] = sum;
  out[2 * b + 1] = zeros > 0 && zeros < order * order ? 1.0f : 0.0f;
}

/* The solid-angle density at x of the direction d towards the lens, as camera_sample_wi claims it: the
 * lens point where the ray (x, d) meets the lens disk, its area density times dist^2 / cos at the lens;
 * 0 where the ray misses the lens. */
static inline float camera_wi_density(__constant const SceneHeader* h, float3 x, float3 d) {
  float3 fwd = h->cam_forward.xyz;
  float c = -pc_dot(d, fwd);
  if (!(c > 0.0f)) return 0.0f;
  float t = pc_dot(x - h->cam_position.xyz, fwd) / c;
  float3 p = x + t * d - h->cam_position.xyz;
  if (!(t > 0.0f) || pc_dot(p, p) > h->lens_radius * h->lens_radius) return 0.0f;
  return t * t / (c * PC_PI * h->lens_radius * h->lens_radius);
}

/* One camera_sample_wi from x per item. out: 12 floats per item: wi (3), status (0 failed, 1 sampled), pdf,
 * camera_wi_density(x, wi), We, raster (2), the lens point (3). */
__kernel void camera_wi_test(__constant const SceneHeader* h, float4 x, uint seed, __global float* out) {
  uint i = get_global_id(0);
  CameraWiSample s;
  __global float* w = out + 12 * i;
  for (int k = 0; k < 12; ++k) w[k] = 0.0f;
  if (!camera_sample_wi(h, x.xyz, test_random4(i, seed).xy, &s)) return;
  vstore3(s.wi, 0, w);
  w[3] = 1.0f;
  w[4] = s.pdf;
  w[5] = h->lens_radius > 0.0f ? camera_wi_density(h, x.xyz, s.wi) : 0.0f;
  w[6] = s.We;
  w[7] = s.raster.x;
  w[8] = s.raster.y;
  vstore3(s.p, 0, w + 9);
}

/* Integral of camera_wi_density(x, .) over each listed bin; out as bsdf_pdf_bins. */
__kernel void camera_wi_pdf_bins(__constant const SceneHeader* h, float4 x, __global const float4* binning,
                                 __global const uint* bins, uint order, __global const float* gl_nodes,
                                 __global const float* gl_weights, __global float* out) {
  uint b = get_global_id(0);
  float sum = 0.0f;
  uint zeros = 0;
  for (uint i = 0; i < order; ++i) {
    float row = 0.0f;
    for (uint j = 0; j < order; ++j) {
      float w;
      float3 d = bin_node(binning, bins[b], gl_nodes, gl_weights, i, j, &w);
      float p = camera_wi_density(h, x.xyz, d);
      zeros += p == 0.0f;
      row += w * p;
    }
    sum += row;
  }
  out[2 * b] = sum;
  out[2 * b + 1] = zeros > 0 && zeros < order * order ? 1.0f : 0.0f;
}
