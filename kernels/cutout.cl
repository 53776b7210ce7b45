/* Cut-outs (PC_HAS_CUTOUTS): a material's opacity, times its opacity texture's, is the probability that
 * its surface stops a ray (leaves, chains, fences: MTL d and map_d, glTF alpha). The traversal asks at
 * every candidate hit, shadow rays included. The decision is a hash of the ray's cutout_seed (a random
 * dimension of its own, set by the integrator per path and ray) and the primitive index, so it is the
 * same whatever order the traversal meets the primitives in, on every device and with either BVH layout. */
#ifndef PATHCL_CUTOUT_CL
#define PATHCL_CUTOUT_CL

#include "shared/types.h"
#include "rng.cl"
#include "sampler.cl"
#include "scene.cl"
#include "texture.cl"

#ifdef PC_HAS_CUTOUTS

/* The cutout_seed of a path's ray_index-th ray (PC_RAY_* of sampler.cl: the camera ray, then the shadow
 * ray and the next ray of each scattering event). */
static inline uint cutout_seed(SampleKey key, uint ray_index) {
  return hash4(key.pixel, key.sample, key.seed ^ 0x3c6ef372u, ray_index);
}

/* Whether prim stops a ray with this seed at (u, v). sc == 0: no cut-outs (ray files, test kernels). */
static inline bool cutout_stops(const SceneData* sc, uint prim, float u, float v, uint seed) {
  if (sc == 0) return true;
  uint material = sc->shading[prim].material;
  float opacity = sc->materials[material].opacity;
  uint texture = sc->materials[material].opacity_texture;
  if (texture != PC_INVALID)  /* triangles only (scene/device_scene_build.cpp) */
    opacity *= texture_lookup(sc->textures, sc->texels, texture, triangle_uv(sc->uvs, prim, u, v)).x;
  if (opacity >= 1.0f) return true;
  if (!(opacity > 0.0f)) return false;
  return uint_to_unit(hash4(seed, prim, 0x6a09e667u, 0xbb67ae85u)) < opacity;
}

#endif /* PC_HAS_CUTOUTS */

#endif
