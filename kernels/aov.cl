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
 * nothing to the AOVs. A work item takes PC_LANES pixels, one a lane (kernels/lanes.cl: every lane does
 * the one-lane program's operations), and adds each pixel's samples to its sums in sample order, so any
 * split into units, any device and any lane width give the same bits; the pass reads the scene and
 * nothing the beauty's kernel writes, so the beauty's bits do not depend on it. */
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
#include "lanes.cl"
#include "trace_lanes.cl"
#include "scatter.cl"

/* Float words of the averaged AOVs in a pixel's record below (albedo 3, normal 3, depth 1, position 3,
 * uv 2); the ids after them. */
#define PC_AOV_FLOATS 12u

typedef struct {
  LaneF v[PC_AOV_FLOATS];
  LaneU shape_id, material_id;
} AovLanes;

/* Which shape a hit belongs to: scene/device_scene.h's prim_shapes and instance_shapes. */
typedef struct {
  __global const uint* prim_shapes;
  __global const uint* instance_shapes;
} ShapeTables;

/* Where AOV a's float words start in AovLanes.v, and its words a pixel. */
static inline uint aov_first_float(uint a) {
  return a == PC_AOV_ALBEDO ? 0u : a == PC_AOV_NORMAL ? 3u : a == PC_AOV_DEPTH ? 6u : a == PC_AOV_POSITION ? 7u : 10u;
}
static inline uint aov_words(uint a) {
  return a == PC_AOV_DEPTH || a >= PC_AOV_SHAPE_ID ? 1u : a == PC_AOV_UV ? 2u : 3u;
}

/* The reflectance the albedo AOV takes at a non-delta surface. */
static inline Lane3 material_albedo_lanes(const MaterialLanes* m) {
  Lane3 c = m->color;
  Lane3 phong = lane3(fmin(c.x + m->specular.x, 1.0f), fmin(c.y + m->specular.y, 1.0f), fmin(c.z + m->specular.z, 1.0f));
  Lane3 metal = fresnel_conductor((LaneF)(1.0f), m->specular, m->k);
  return lane3_select(lane3_select(c, phong, m->type == PC_MAT_PHONG), metal, m->type == PC_MAT_ROUGH_CONDUCTOR);
}

/* The AOVs of sample `sample` of each lane's pixel, for the lanes in m (the others get 0); origin: the world
 * position of the device coordinates' origin. */
static inline void aov_sample_lanes(const SceneData* sc, ShapeTables shapes, LaneU pixel, LaneU sample, LaneI m, float3 origin,
                                    AovLanes* a) {
  __constant const SceneHeader* h = sc->h;
  for (uint k = 0; k < PC_AOV_FLOATS; ++k) a->v[k] = (LaneF)(0.0f);
  a->shape_id = a->material_id = (LaneU)(0u);
  LaneF u0, u1, u2, u3;
  sample4_lanes(h, pixel, sample, h->seed, (LaneU)(PC_DIM_CAMERA), &u0, &u1, &u2, &u3);
  RayLanes ray;
  camera_ray_lanes(h, pixel % h->width, pixel / h->width, u0, u1, u2, u3, &ray.o, &ray.d);
  ray.tmin = (LaneF)(0.0f);
  ray.tmax = (LaneF)(INFINITY);
  ray.skip_prim = ray.skip_instance = (LaneU)(PC_INVALID);
  ray.cutout_seed = (LaneU)(0u);
#ifdef PC_HAS_CUTOUTS
  ray.cutout_seed = cutout_seed_lanes(h, pixel, sample, (LaneU)(PC_RAY_CAMERA));
#endif
  Lane3 throughput = lane3_splat((float3)(1.0f));
  LaneI live = m;
  for (uint depth = 0;; ++depth) {
    HitLanes hit;
    live &= trace_lanes(sc, &ray, live, false, &hit);
    if (!pc_any_(live)) break;
    ShadingLanes sh;
    SurfaceLanes s = scene_surface_lanes(sc, &ray, &hit, live, &sh);
    MaterialLanes mat = material_at_lanes(sc, sh.material, &s, &sh, &hit, live);
    if (depth == 0u) {  /* the first hit */
      Lane3 d = lane3_sub(s.p, ray.o);
      a->v[6] = select((LaneF)(0.0f), sqrt(pc_dot(d, d)), live);
      Lane3 world = lane3_add(s.p, lane3_splat(origin));
      a->v[7] = select((LaneF)(0.0f), world.x, live);
      a->v[8] = select((LaneF)(0.0f), world.y, live);
      a->v[9] = select((LaneF)(0.0f), world.z, live);
      a->material_id = select((LaneU)(0u), sh.material + 1u, live);
      PC_EACH_LANE(j, pc_lane_bits(live)) {  /* per lane with the one-lane code, as material_at_lanes does */
        uint prim = pc_lane(s.prim, j), shape = shapes.prim_shapes[prim];
#ifdef PC_HAS_INSTANCES
        uint placing = shapes.instance_shapes[pc_lane(s.instance, j)];
        if (placing != PC_INVALID) shape = placing;
#endif
        a->shape_id = pc_with_lane(a->shape_id, j, shape + 1u);
#ifdef PC_HAS_TEXTURES
        Surface one;
        one.p = lane3_at(s.p, j);
        one.prim = prim;
        Hit one_hit;
        one_hit.slot = pc_lane(hit.slot, j);
        one_hit.u = pc_lane(hit.u, j);
        one_hit.v = pc_lane(hit.v, j);
        float2 uv = surface_uv(sc, &one, &one_hit);
        a->v[10] = pc_with_lane(a->v[10], j, uv.x);
        a->v[11] = pc_with_lane(a->v[11], j, uv.y);
#endif
      }
    }
    LaneI found = live & !bsdf_is_delta_lanes(mat.type);  /* the first non-delta hit: albedo and normal */
    if (pc_any_(found)) {
      Lane3 albedo = lane3_mul(throughput, material_albedo_lanes(&mat));
      a->v[0] = select(a->v[0], albedo.x, found);
      a->v[1] = select(a->v[1], albedo.y, found);
      a->v[2] = select(a->v[2], albedo.z, found);
      a->v[3] = select(a->v[3], s.ns.x, found);
      a->v[4] = select(a->v[4], s.ns.y, found);
      a->v[5] = select(a->v[5], s.ns.z, found);
    }
    live &= !found;
    if (depth >= h->max_depth || !pc_any_(live)) break;
    /* Delta surfaces: on along the direction the path integrator samples there. */
    FrameLanes frame;
    frame_about(s.ns, &frame);
    Lane3 wo = lane3_neg(ray.d);
    Lane3 wo_local = to_local(&frame, wo);
    LaneF ub0, ub1, ub2, ub3;
    sample4_lanes(h, pixel, sample, h->seed, (LaneU)(PC_DIM_BSDF(depth)), &ub0, &ub1, &ub2, &ub3);
    BsdfSampleLanes bs;
    Lane3 wi;
    live = scatter_lanes(&mat, &frame, s.ng, wo_local, pc_dot(wo, s.ng), ub0, ub1, ub2, live, &bs, &wi);
    if (!pc_any_(live)) break;
    /* Refraction's radiance scaling (bs.eta2) left out: glass's transmittance alone. */
    throughput = lane3_mul(throughput, lane3_scale(bs.weight, bs.eta2));
    RayLanes next;
    spawn_ray_lanes(s.p, s.p_err, s.ng, s.prim, s.instance, wi, &next);
    next.cutout_seed = (LaneU)(0u);
#ifdef PC_HAS_CUTOUTS
    next.cutout_seed = cutout_seed_lanes(h, pixel, sample, (LaneU)(PC_RAY_NEXT(depth)));
#endif
    ray = next;
  }
  for (uint k = 0; k < PC_AOV_FLOATS; ++k) a->v[k] = select((LaneF)(0.0f), a->v[k], isfinite(a->v[k]));
}

/* One work unit: samples [sample_begin, sample_begin + sample_count) of pixels pixel_begin + i * pixel_stride,
 * i < pixel_count, PC_LANES of them a work item, added to the AOV planes of film that aov->offset names
 * (the others are not rendered). */
PC_KERNEL_BODY void aov_pass_item(const SceneData* scene, __constant const AovHeader* aov,
                                  __global const uint* prim_shapes, __global const uint* instance_shapes,
                                  __global uint* film, uint pixel_begin, uint pixel_count, uint pixel_stride,
                                  uint sample_begin, uint sample_count, uint global_id) {
  SceneData sc = *scene;
  __constant const SceneHeader* h = sc.h;
  ShapeTables shapes = {prim_shapes, instance_shapes};
  uint first = global_id * PC_LANES;
  if (first >= pixel_count) return;
  uint lanes = min((uint)PC_LANES, pixel_count - first);
  uint pixel_of[PC_LANES];
  for (uint j = 0; j < PC_LANES; ++j) pixel_of[j] = pixel_begin + (first + min(j, lanes - 1u)) * pixel_stride;
  LaneU pixel = lane_load(pixel_of);
  LaneI m = pc_lanes_of_bits((1u << (lanes - 1u) << 1u) - 1u, (LaneI)(0));
  LaneF sum[PC_AOV_FLOATS];
  for (uint k = 0; k < PC_AOV_FLOATS; ++k) sum[k] = (LaneF)(0.0f);
  for (uint a = 0; a < PC_AOV_SHAPE_ID; ++a)
    if (aov->offset[a] != PC_INVALID)
      for (uint w = 0; w < aov_words(a); ++w)
        for (uint j = 0; j < lanes; ++j)
          sum[aov_first_float(a) + w] = pc_with_lane(sum[aov_first_float(a) + w], j,
                                                     as_float(film[aov->offset[a] + aov_words(a) * pixel_of[j] + w]));
  for (uint s = sample_begin; s < sample_begin + sample_count; ++s) {
    AovLanes a;
    aov_sample_lanes(&sc, shapes, pixel, (LaneU)(s), m, aov->origin.xyz, &a);
    for (uint k = 0; k < PC_AOV_FLOATS; ++k) sum[k] += a.v[k];
    if (s != 0u) continue;  /* the ids: sample 0's */
    for (uint j = 0; j < lanes; ++j) {
      if (aov->offset[PC_AOV_SHAPE_ID] != PC_INVALID) film[aov->offset[PC_AOV_SHAPE_ID] + pixel_of[j]] = pc_lane(a.shape_id, j);
      if (aov->offset[PC_AOV_MATERIAL_ID] != PC_INVALID) film[aov->offset[PC_AOV_MATERIAL_ID] + pixel_of[j]] = pc_lane(a.material_id, j);
    }
  }
  for (uint a = 0; a < PC_AOV_SHAPE_ID; ++a)
    if (aov->offset[a] != PC_INVALID)
      for (uint w = 0; w < aov_words(a); ++w)
        for (uint j = 0; j < lanes; ++j)
          film[aov->offset[a] + aov_words(a) * pixel_of[j] + w] = as_uint(pc_lane(sum[aov_first_float(a) + w], j));
}
__kernel void aov_pass(PC_SCENE_PARAMS, __constant const AovHeader* aov, __global const uint* prim_shapes,
                       __global const uint* instance_shapes, __global uint* film, uint pixel_begin, uint pixel_count,
                       uint pixel_stride, uint sample_begin, uint sample_count) {
  SceneData sc = PC_SCENE_DATA;
  aov_pass_item(&sc, aov, prim_shapes, instance_shapes, film, pixel_begin, pixel_count, pixel_stride, sample_begin,
                sample_count, get_global_id(0));
}
