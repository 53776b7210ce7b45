/* The light-tracing integrator (`light`, lane width 1: one work item traces one light path at a time,
 * scalar code like the path megakernel). Light path `index` of sample s is keyed by (index, s): sample
 * s holds width x height light paths, so a light render of N spp traces as many paths as a path render
 * of N spp. Each path starts on a light chosen by power (emission.cl), and at every non-delta vertex it
 * is connected to the camera (camera_importance.cl), shadow-tested and splatted into the pixels its
 * image position lands in (splat_film.cl), weighted by the pixel filter.
 *
 * Importance transport (Veach's thesis, ch. 5; pbrt-v4): the BSDF is evaluated with wo the direction to
 * the camera (or the next vertex) and wi the direction back along the light path; refraction does not
 * scale by (n_t / n_i)^2 (the radiance scaling the BSDF applies is undone: BsdfSample.eta2), and with
 * shading normals each vertex takes the adjoint BSDF's factor |w_l . n_s| |w_o . n_g| / (|w_l . n_g| |w_o . n_s|)
 * (w_l towards the light, w_o outgoing), at connections too, so that light and path tracing estimate the
 * same pixel values.
 *
 * What light tracing cannot see: light reaching the camera directly from an emitter (the emitter's own
 * vertex is not connected), and anything seen through a specular (delta) surface, since a connection to
 * a pinhole through a mirror or glass has probability zero. Those pixels stay black (docs/light-transport.md). */
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
#include "texture.cl"
#include "bsdf.cl"
#include "environment.cl"
#include "lights.cl"
#include "material.cl"
#include "counters.cl"
#include "emission.cl"
#include "camera_importance.cl"
#include "splat_film.cl"

/* Sample dimensions (groups of four, sampler.cl). Light subpaths take groups from PC_LT_GROUP_BASE on, so
 * that a camera subpath of the same key (BDPT) keeps groups below it. */
#define PC_LT_GROUP_BASE 64u
#define PC_LT_EMIT_POS (PC_LT_GROUP_BASE + 0u)  /* x: light choice, yz: point, w: side */
#define PC_LT_EMIT_DIR (PC_LT_GROUP_BASE + 1u)  /* xy: direction */
#define PC_LT_CONNECT(v) (PC_LT_GROUP_BASE + 2u + 2u * (v)) /* xy: lens point, z: roulette, at vertex v */
#define PC_LT_BSDF(v) (PC_LT_GROUP_BASE + 3u + 2u * (v))    /* xyz: BSDF sample at vertex v */

/* Cut-out ray numbers of a light path: 0 the first ray, then 2 v + 1 the camera connection of vertex v and
 * 2 v + 2 the ray leaving it; offset from the path integrator's by this (their keys coincide). */
#define PC_LT_CUTOUT_BASE 0x40000000u

typedef struct {
  uint rays, nan_splats, inf_splats, negative_splats, overflows;
} SplatCounts;

/* The adjoint BSDF's shading-normal factor at a vertex (see the top of the file). */
inline float shading_normal_factor(float3 w_light, float3 w_out, float3 ns, float3 ng) {
  float num = fabs(pc_dot(w_light, ns)) * fabs(pc_dot(w_out, ng));
  float den = fabs(pc_dot(w_light, ng)) * fabs(pc_dot(w_out, ns));
  return den > 0.0f ? num / den : 0.0f;
}

/* Splats colour c landing at image position `raster` into every pixel the filter reaches, weighted by it. */
inline void splat_filtered(__global uint* film, __constant const SceneHeader* h, __constant const LightTransportHeader* lt,
                           float2 raster, uint parity, float3 c, SplatCounts* n) {
  if (isnan(c.x) || isnan(c.y) || isnan(c.z)) {
    ++n->nan_splats;
    return;
  }
  if (isinf(c.x) || isinf(c.y) || isinf(c.z)) {
    ++n->inf_splats;
    return;
  }
  if (c.x < 0.0f || c.y < 0.0f || c.z < 0.0f) {
    ++n->negative_splats;
    return;
  }
  float r = h->filter_radius;
  int x0 = max(0, (int)floor(raster.x - r)), x1 = min((int)h->width - 1, (int)floor(raster.x + r));
  int y0 = max(0, (int)floor(raster.y - r)), y1 = min((int)h->height - 1, (int)floor(raster.y + r));
  for (int y = y0; y <= y1; ++y) {
    float wy = filter_density_1d(h, raster.y - ((float)y + 0.5f));
    if (!(wy > 0.0f)) continue;
    for (int x = x0; x <= x1; ++x) {
      float w = wy * filter_density_1d(h, raster.x - ((float)x + 0.5f));
      if (w > 0.0f) n->overflows += splat_pixel(film, lt, (uint)y * h->width + (uint)x, parity, c * w);
    }
  }
}

inline void trace_light_path(const SceneData* sc, __constant const LightTransportHeader* lt,
                             __global const float* emission_cdf, __global uint* film, SampleKey key, SplatCounts* n) {
  __constant const SceneHeader* h = sc->h;
  if (h->max_depth == 0u) return; /* no scattering: only directly seen lights, which light tracing cannot see */
  float4 u_pos = sample4(h, key, PC_LT_EMIT_POS), u_dir = sample4(h, key, PC_LT_EMIT_DIR);
  EmissionSample e;
  if (!sample_emission(sc, lt, emission_cdf, u_pos.x, u_pos.yzw, u_dir.xy, &e)) return;
  float3 beta = emission_weight(&e);
  float beta0 = max_component(beta);
  uint parity = key.sample & 1u;
  Ray ray;
  ray.o = e.prim != PC_INVALID ? offset_ray_origin(e.p, e.p_err, e.n, e.d) : e.p;
  ray.d = e.d;
  ray.tmin = 0.0f;
  ray.tmax = INFINITY;
  ray.skip_prim = e.prim;
  ray.skip_instance = 0u;
#ifdef PC_HAS_CUTOUTS
  ray.cutout_seed = cutout_seed(key, PC_LT_CUTOUT_BASE);
#endif
  for (uint v = 0;; ++v) { /* v + 1 scattering events at the vertex found now */
    Hit hit;
    ++n->rays;
    if (!trace_scene(sc, sc, &ray, false, &hit)) break;
    Surface s = scene_surface(sc, &ray, &hit);
    PrimShading sh = sc->shading[s.prim];
    Material m = material_at(sc, sh.material, &s, &hit);
    float3 t, b;
    make_frame(s.ns, &t, &b);
    float3 w_light = -ray.d; /* back along the light path */
    float3 wl_local = (float3)(pc_dot(w_light, t), pc_dot(w_light, b), pc_dot(w_light, s.ns));
    float wl_ng = pc_dot(w_light, s.ng);
    float4 u_connect = sample4(h, key, PC_LT_CONNECT(v));

    /* Connection to the camera. */
    CameraWiSample cs;
    if (!bsdf_is_delta(m) && camera_sample_wi(h, s.p, u_connect.xy, &cs)) {
      float3 wc_local = (float3)(pc_dot(cs.wi, t), pc_dot(cs.wi, b), pc_dot(cs.wi, s.ns));
      float3 f = bsdf_eval(m, wc_local, wl_local);
      /* Reflection only (no non-delta material transmits): the camera on the light's side of the surface. */
      if (pc_dot(cs.wi, s.ng) * wl_ng > 0.0f && (f.x > 0.0f || f.y > 0.0f || f.z > 0.0f)) {
        Ray shadow;
        shadow.o = offset_ray_origin(s.p, s.p_err, s.ng, cs.wi);
        shadow.d = cs.p - shadow.o;
        shadow.tmin = 0.0f;
        shadow.tmax = 1.0f - PC_SHADOW_EPSILON;
        shadow.skip_prim = s.prim;
        shadow.skip_instance = s.instance;
#ifdef PC_HAS_CUTOUTS
        shadow.cutout_seed = cutout_seed(key, PC_LT_CUTOUT_BASE + 2u * v + 1u);
#endif
        Hit blocker;
        ++n->rays;
        if (!trace_scene(sc, sc, &shadow, true, &blocker)) {
          float g = fabs(wc_local.z) * shading_normal_factor(w_light, cs.wi, s.ns, s.ng);
          /* over the width x height paths of a sample: the film sums to the pixel mean times spp */
          float per_path = g * cs.We / (cs.pdf * (float)(h->width * h->height));
          splat_filtered(film, h, lt, cs.raster, parity, beta * f * per_path, n);
        }
      }
    }
    if (v + 1u >= h->max_depth) break;

    /* The next vertex. */
    float4 u_bsdf = sample4(h, key, PC_LT_BSDF(v));
    BsdfSample bs;
    if (!bsdf_sample(m, wl_local, u_bsdf.xyz, &bs)) break;
    float3 wi = bs.wi.x * t + bs.wi.y * b + bs.wi.z * s.ns;
    bool transmitted = bs.wi.z * wl_local.z < 0.0f;
    if ((pc_dot(wi, s.ng) * wl_ng > 0.0f) == transmitted) break;
    /* Importance is not scaled by refraction: undo the radiance scaling (bs.eta2) the sample applied. */
    beta *= bs.weight * (bs.eta2 * shading_normal_factor(w_light, wi, s.ns, s.ng));
    if (v + 1u > h->rr_depth) {
      /* Russian roulette on the throughput relative to the emitted one (light paths start at power scale). */
      float q = fmin(1.0f, max_component(beta) / beta0);
      if (u_connect.z >= q) break;
      beta /= q;
    }
    ray.o = offset_ray_origin(s.p, s.p_err, s.ng, wi);
    ray.d = wi;
    ray.tmin = 0.0f;
    ray.tmax = INFINITY;
    ray.skip_prim = s.prim;
    ray.skip_instance = s.instance;
#ifdef PC_HAS_CUTOUTS
    ray.cutout_seed = cutout_seed(key, PC_LT_CUTOUT_BASE + 2u * v + 2u);
#endif
  }
}

/* One work unit: light paths [path_begin, path_begin + path_count) of samples [sample_begin, sample_begin +
 * sample_count), splatted into film (PC_SPLAT_WORDS 64-bit sums per pixel, cleared by the host per unit).
 * Which work item runs which path, and in which order splats arrive, changes no bit of the film. */
__kernel void light_pass(PC_SCENE_PARAMS, __constant const LightTransportHeader* lt, __global const float* emission_cdf,
                         __global uint* film, __global SplatStats* stats, uint path_begin, uint path_count,
                         uint sample_begin, uint sample_count) {
  SceneData sc = PC_SCENE_DATA;
  uint item = get_global_id(0);
  if (item >= path_count) return;
  SampleKey key;
  key.pixel = path_begin + item;
  key.seed = h->seed;
  SplatCounts n = {0u, 0u, 0u, 0u, 0u};
  for (uint s = sample_begin; s < sample_begin + sample_count; ++s) {
    key.sample = s;
    trace_light_path(&sc, lt, emission_cdf, film, key, &n);
  }
  volatile __global uint* counters = (volatile __global uint*)&stats->rays_lo;
  add_counter64(counters, n.rays);
  if (n.nan_splats) atomic_add(counters + 2, n.nan_splats);
  if (n.inf_splats) atomic_add(counters + 3, n.inf_splats);
  if (n.negative_splats) atomic_add(counters + 4, n.negative_splats);
  if (n.overflows) atomic_add(counters + 5, n.overflows);
}
