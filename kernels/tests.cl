/* Kernels that only the test suite builds: struct layout as the kernel compiler sees it, and the
 * intersection routines called one by one. */
#include "shared/types.h"
#include "math.cl"
#include "rng.cl"
#include "sampling.cl"
#include "intersect.cl"

#ifndef offsetof
#define offsetof(S, F) __builtin_offsetof(S, F)
#endif
#define PC_WRITE_SIZE(S) out[n++] = (uint)sizeof(S);
#define PC_WRITE_OFFSET(S, F) out[n++] = (uint)offsetof(S, F);
__kernel void layout_report(__global uint* out) {
  uint n = 0;
  PC_LAYOUT_STRUCTS(PC_WRITE_SIZE)
  PC_LAYOUT_FIELDS(PC_WRITE_OFFSET)
}

/* boxes: lo.xyz, hi.xyz per box (6 floats); rays as RayRecord; out: entry distance or +inf. */
__kernel void ray_box_test(__global const RayRecord* rays, __global const float* boxes, __global float* out) {
  uint i = get_global_id(0);
  __global const float* r = (__global const float*)(rays + i);
  float3 d = vload3(0, r + 4);
  RayPrecomp rp = ray_precompute(d);
  out[i] = ray_box(vload3(0, r), rp.inv_d, r[3], r[7], vload3(0, boxes + 6 * i), vload3(0, boxes + 6 * i + 3));
}

/* One triangle (9 floats) per ray; out as HitRecord with prim 0 for a hit. */
__kernel void ray_triangle_test(__global const RayRecord* rays, __global const float* tris, __global HitRecord* out) {
  uint i = get_global_id(0);
  __global const float* r = (__global const float*)(rays + i);
  float3 o = vload3(0, r), d = vload3(0, r + 4);
  RayPrecomp rp = ray_precompute(d);
  HitRecord h;
  h.t = INFINITY;
  h.prim = PC_INVALID;
  h.u = h.v = 0.0f;
  float t, u, v;
  if (ray_triangle(o, &rp, rp.kz, r[3], r[7], vload3(0, tris + 9 * i), vload3(0, tris + 9 * i + 3),
                   vload3(0, tris + 9 * i + 6), &t, &u, &v)) {
    h.t = t;
    h.prim = 0u;
    h.u = u;
    h.v = v;
  }
  out[i] = h;
}

/* Nearest hit by testing every primitive: the reference for BVH traversal. */
__kernel void brute_force_trace(__global const Primitive* prims, uint prim_count, __global const RayRecord* rays,
                                __global HitRecord* hits) {
  uint i = get_global_id(0);
  __global const float* r = (__global const float*)(rays + i);
  Ray ray;
  ray.o = vload3(0, r);
  ray.tmin = r[3];
  ray.d = vload3(0, r + 4);
  ray.tmax = r[7];
  ray.skip_prim = PC_INVALID;
  RayPrecomp rp = ray_precompute(ray.d);
  Hit hit;
  hit.t = ray.tmax;
  hit.slot = PC_INVALID;
  for (uint p = 0; p < prim_count; ++p) intersect_prim(prims, p, &ray, &rp, rp.kz, hit.t, &hit);
  HitRecord out;
  out.t = hit.slot == PC_INVALID ? INFINITY : hit.t;
  out.prim = hit.slot == PC_INVALID ? PC_INVALID : prim_index_of(prims[hit.slot]);
  out.u = hit.u;
  out.v = hit.v;
  hits[i] = out;
}
