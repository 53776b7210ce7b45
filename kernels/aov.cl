/* The AOV pass (`--aov`, lane width 1): for every sample of a pixel, the camera ray the beauty's sample
 * takes (sample dimensions 0, the path integrator's and BDPT's camera subpath's), followed through mirrors
 * and glass (delta BSDFs) with the BSDF choices the path integrator makes there (its BSDF dimensions), and
 * what it finds (shared/film_types.h):
 *   albedo    the material's reflectance at the first non-delta hit, times the throughput of the delta
 *             chain before it (a mirror's reflectance, glass's transmittance; refraction's radiance
 *             scaling left out), as Open Image Denoise and Cycles take it: diffuse and Oren-Nayar their
 *             reflectance (texture and vertex colours included), Phong diffuse + specular (at most 1),
 *             plastic its diffuse colour, rough metal its Fresnel reflectance at normal incidence
 *   normal    the world-space shading normal there (the front side's)
 *   depth     the distance from the camera ray's origin to its first hit
 *   position  the world position of the first hit
 *   uv        the texture coordinates of the first hit (scenes with textures keep them: 0 in others)
 *   shape_id     the first hit's shape index + 1 (the placing shape's for an instanced mesh)
 *   material_id  the first hit's material index + 1 (ids: sample 0 of the pixel alone, not averaged)
 * A ray that escapes, or a chain that ends (depth limit, a sample that fails), gives 0: the environment adds
 * nothing to the AOVs. Each work item owns one pixel and adds its samples to the pixel's sums in sample
 * order, so any split into units, any device and the beauty's lane width give the same bits; the pass
 * reads the scene and nothing the beauty's kernel writes, so the beauty's bits do not depend on it. */
#include "shared/types.h"
#include "shared/film_types.h"
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
#include "fresnel.cl"
#include "material.cl"
#include "cutout.cl"

/* Float words of the averaged AOVs in a pixel's record below (albedo 3, normal 3, depth 1, position 3,
 * uv 2); the id after them. */
#define PC_AOV_FLOATS 12u

typedef struct {
  float v[PC_AOV_FLOATS];
  uint shape_id, material_id;
} AovSample;

/* Which shape a hit belongs to: scene/device_scene.h's prim_shapes and instance_shapes. */
typedef struct {
  __global const uint* prim_shapes;
  __global const uint* instance_shapes;
} ShapeTables;

/* Where AOV a's float words start in AovSample.v. */
inline uint aov_first_float(uint a) {
  return a == PC_AOV_ALBEDO ? 0u : a == PC_AOV_NORMAL ? 3u : a == PC_AOV_DEPTH ? 6u : a == PC_AOV_POSITION ? 7u : 10u;
}
inline uint aov_words(uint a) {
  return a == PC_AOV_DEPTH || a >= PC_AOV_SHAPE_ID ? 1u : a == PC_AOV_UV ? 2u : 3u;
}

/* The reflectance the albedo AOV takes at a non-delta surface. */
inline float3 material_albedo(Material m) {
  float3 c = m.color.xyz;
  if (m.type == PC_MAT_PHONG) return fmin(c + m.specular.xyz, (float3)(1.0f));
  if (m.type == PC_MAT_ROUGH_CONDUCTOR) return fresnel_conductor(1.0f, m.specular.xyz, m.k.xyz);
  return c;
}

/* Sample key.sample of pixel `pixel`; origin: the world position of the device coordinates' origin. */
inline AovSample aov_sample(const SceneData* sc, ShapeTables shapes, uint pixel, SampleKey key, float3 origin) {
  __constant const SceneHeader* h = sc->h;
  AovSample a;
  for (uint k = 0; k < PC_AOV_FLOATS; ++k) a.v[k] = 0.0f;
  a.shape_id = a.material_id = 0u;
  Ray ray;
  camera_ray(h, pixel % h->width, pixel / h->width, sample4(h, key, PC_DIM_CAMERA), &ray.o, &ray.d);
  ray.tmin = 0.0f;
  ray.tmax = INFINITY;
  ray.skip_prim = PC_INVALID;
  ray.skip_instance = PC_INVALID;
  ray.cutout_seed = 0u;
#ifdef PC_HAS_CUTOUTS
  ray.cutout_seed = cutout_seed(key, PC_RAY_CAMERA);
#endif
  float3 throughput = (float3)(1.0f);
  for (uint depth = 0;; ++depth) {
    Hit hit;
    if (!trace_scene(sc, sc, &ray, false, &hit)) break;
    Surface s = scene_surface(sc, &ray, &hit);
    PrimShading sh = sc->shading[s.prim];
    Material m = material_at(sc, sh.material, &s, &hit);
    if (depth == 0u) {
      float3 d = s.p - ray.o;
      a.v[6] = sqrt(pc_dot(d, d));
      float3 world = s.p + origin;
      a.v[7] = world.x, a.v[8] = world.y, a.v[9] = world.z;
#ifdef PC_HAS_TEXTURES
      float2 uv = surface_uv(sc, &s, &hit);
      a.v[10] = uv.x, a.v[11] = uv.y;
#endif
      a.material_id = sh.material + 1u;
      uint shape = shapes.prim_shapes[s.prim];
#ifdef PC_HAS_INSTANCES
      if (shapes.instance_shapes[s.instance] != PC_INVALID) shape = shapes.instance_shapes[s.instance];
#endif
      a.shape_id = shape + 1u;
    }
    if (!bsdf_is_delta(m)) {
      float3 albedo = throughput * material_albedo(m);
      a.v[0] = albedo.x, a.v[1] = albedo.y, a.v[2] = albedo.z;
      a.v[3] = s.ns.x, a.v[4] = s.ns.y, a.v[5] = s.ns.z;
      break;
    }
    if (depth >= h->max_depth) break;
    /* A delta surface: on along the direction the path integrator samples there. */
    float3 t, b;
    make_frame(s.ns, &t, &b);
    float3 wo = -ray.d;
    float3 wo_local = (float3)(pc_dot(wo, t), pc_dot(wo, b), pc_dot(wo, s.ns));
    BsdfSample bs;
    if (!bsdf_sample(m, wo_local, sample4(h, key, PC_DIM_BSDF(depth)).xyz, &bs)) break;
    float3 wi = bs.wi.x * t + bs.wi.y * b + bs.wi.z * s.ns;
    bool transmitted = bs.wi.z * wo_local.z < 0.0f;
    if ((pc_dot(wi, s.ng) * pc_dot(wo, s.ng) > 0.0f) == transmitted) break;
    throughput *= bs.weight * bs.eta2;
    ray = spawn_ray(&s, wi);
#ifdef PC_HAS_CUTOUTS
    ray.cutout_seed = cutout_seed(key, PC_RAY_NEXT(depth));
#endif
  }
  for (uint k = 0; k < PC_AOV_FLOATS; ++k)
    if (!isfinite(a.v[k])) a.v[k] = 0.0f;
  return a;
}

/* One work unit: samples [sample_begin, sample_begin + sample_count) of pixels pixel_begin + i * pixel_stride,
 * i < pixel_count, added to the AOV planes of film that aov->offset names (the others are not rendered). */
__kernel void aov_pass(PC_SCENE_PARAMS, __constant const AovHeader* aov, __global const uint* prim_shapes,
                       __global const uint* instance_shapes, __global uint* film, uint pixel_begin, uint pixel_count,
                       uint pixel_stride, uint sample_begin, uint sample_count) {
  SceneData sc = PC_SCENE_DATA;
  ShapeTables shapes = {prim_shapes, instance_shapes};
  uint i = get_global_id(0);
  if (i >= pixel_count) return;
  uint pixel = pixel_begin + i * pixel_stride;
  float sum[PC_AOV_FLOATS];
  for (uint a = 0; a < PC_AOV_SHAPE_ID; ++a)
    for (uint w = 0; w < aov_words(a); ++w)
      sum[aov_first_float(a) + w] = aov->offset[a] == PC_INVALID ? 0.0f : as_float(film[aov->offset[a] + aov_words(a) * pixel + w]);
  SampleKey key;
  key.pixel = pixel;
  key.seed = h->seed;
  for (uint s = sample_begin; s < sample_begin + sample_count; ++s) {
    key.sample = s;
    AovSample a = aov_sample(&sc, shapes, pixel, key, aov->origin.xyz);
    for (uint k = 0; k < PC_AOV_FLOATS; ++k) sum[k] += a.v[k];
    if (s == 0u && aov->offset[PC_AOV_SHAPE_ID] != PC_INVALID) film[aov->offset[PC_AOV_SHAPE_ID] + pixel] = a.shape_id;
    if (s == 0u && aov->offset[PC_AOV_MATERIAL_ID] != PC_INVALID) film[aov->offset[PC_AOV_MATERIAL_ID] + pixel] = a.material_id;
  }
  for (uint a = 0; a < PC_AOV_SHAPE_ID; ++a)
    if (aov->offset[a] != PC_INVALID)
      for (uint w = 0; w < aov_words(a); ++w) film[aov->offset[a] + aov_words(a) * pixel + w] = as_uint(sum[aov_first_float(a) + w]);
}
