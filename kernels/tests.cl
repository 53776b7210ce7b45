/* Kernels that only the test suite builds: struct layout as the kernel compiler sees it, and the
 * intersection routines and texture lookups called one by one. */
#include "shared/types.h"
#include "shared/light_types.h"
#include "shared/film_types.h"
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
  PC_LIGHT_LAYOUT_STRUCTS(PC_WRITE_SIZE)
  PC_LIGHT_LAYOUT_FIELDS(PC_WRITE_OFFSET)
  PC_FILM_LAYOUT_STRUCTS(PC_WRITE_SIZE)
  PC_FILM_LAYOUT_FIELDS(PC_WRITE_OFFSET)
}

/* boxes: lo.xyz, hi.xyz per box (6 floats); rays as RayRecord; out: entry distance or +inf.
 * Through the traversal's four- and eight-box tests: box i goes into lane i % 4 (i % 8) and the other
 * lanes hold empty boxes, as unused node slots do; an empty lane that is not missed, or a difference
 * between the two widths, makes the output NaN. */
__kernel void ray_box_test(__global const RayRecord* rays, __global const float* boxes, __global float* out) {
  uint i = get_global_id(0);
  __global const float* r = (__global const float*)(rays + i);
  float3 d = vload3(0, r + 4);
  RayPrecomp rp = ray_precompute(d);
  float3 lo = vload3(0, boxes + 6 * i), hi = vload3(0, boxes + 6 * i + 3);
  int4 lane = (int4)(0, 1, 2, 3) == (int4)(i % 4u);
  float4 e = ray_boxes4(vload3(0, r), rp.inv_d, rp.inv_d < 0.0f, r[3], r[7], select((float4)(INFINITY), (float4)(lo.x), lane),
                        select((float4)(INFINITY), (float4)(lo.y), lane), select((float4)(INFINITY), (float4)(lo.z), lane),
                        select((float4)(-INFINITY), (float4)(hi.x), lane), select((float4)(-INFINITY), (float4)(hi.y), lane),
                        select((float4)(-INFINITY), (float4)(hi.z), lane));
  float mine = i % 4u == 0u ? e.s0 : i % 4u == 1u ? e.s1 : i % 4u == 2u ? e.s2 : e.s3;
  bool others_missed = all(select(e, (float4)(INFINITY), lane) == (float4)(INFINITY));
  int8 lane8 = (int8)(0, 1, 2, 3, 4, 5, 6, 7) == (int8)(i % 8u);
  float8 enter8;
  int8 hit8 = ray_boxes_hit8(vload3(0, r), rp.inv_d, rp.inv_d < 0.0f, r[3], r[7],
                             select((float8)(INFINITY), (float8)(lo.x), lane8), select((float8)(INFINITY), (float8)(lo.y), lane8),
                             select((float8)(INFINITY), (float8)(lo.z), lane8), select((float8)(-INFINITY), (float8)(hi.x), lane8),
                             select((float8)(-INFINITY), (float8)(hi.y), lane8), select((float8)(-INFINITY), (float8)(hi.z), lane8),
                             &enter8);
  float8 e8 = select((float8)(INFINITY), enter8, hit8);
  float all8[8];
  vstore8(e8, 0, all8);
  bool others_missed8 = all(select(e8, (float8)(INFINITY), lane8) == (float8)(INFINITY));
  bool same = all8[i % 8u] == mine || (isnan(all8[i % 8u]) && isnan(mine));
  out[i] = others_missed && others_missed8 && same ? mine : NAN;
}

#ifdef PC_BVH_WIDE
/* The same rays and boxes (box i in lane i % W) through the W = 8- or 16-wide node tests of the program's
 * layout: bit 0 of out, entered by ray_boxes_hit8 or 16; bit 1, by the traversal's test
 * (ray_boxes_hit_wide_fused where the ray's FusedSlabs are usable, else the former; nodes: room for one node
 * per ray, where the box is put for it); bit 2, the fused test ran; bit 3, it is compiled in
 * (PC_FUSED_SLABS). */
__kernel void ray_box_fused_test(__global const RayRecord* rays, __global const float* boxes, __global WideNode* nodes,
                                 __global uint* out) {
  uint i = get_global_id(0), at = i % PC_BVH_WIDE;
  __global const float* r = (__global const float*)(rays + i);
  float3 o = vload3(0, r), d = vload3(0, r + 4);
  RayPrecomp rp = ray_precompute(d);
  int3 negative = rp.inv_d < 0.0f;
  float3 lo = vload3(0, boxes + 6 * i), hi = vload3(0, boxes + 6 * i + 3);
  WideI lane = pc_lanes_of_bits(1u << at, (WideI)(0));
  WideF lo_x = select((WideF)(INFINITY), (WideF)(lo.x), lane), lo_y = select((WideF)(INFINITY), (WideF)(lo.y), lane);
  WideF lo_z = select((WideF)(INFINITY), (WideF)(lo.z), lane), hi_x = select((WideF)(-INFINITY), (WideF)(hi.x), lane);
  WideF hi_y = select((WideF)(-INFINITY), (WideF)(hi.y), lane), hi_z = select((WideF)(-INFINITY), (WideF)(hi.z), lane);
  WideF enter;
  uint robust = pc_lane_bits(
      PC_CAT(ray_boxes_hit, PC_BVH_WIDE)(o, rp.inv_d, negative, r[3], r[7], lo_x, lo_y, lo_z, hi_x, hi_y, hi_z, &enter));
  uint traversal = robust, flags = 0u;
#ifdef PC_FUSED_SLABS
  flags |= 8u;
#endif
  FusedSlabs f = fused_slabs(o, rp.inv_d);
  if (f.usable) {
    flags |= 4u;
    WideNode node;
    wide_store(lo_x, node.lo_x), wide_store(lo_y, node.lo_y), wide_store(lo_z, node.lo_z);
    wide_store(hi_x, node.hi_x), wide_store(hi_y, node.hi_y), wide_store(hi_z, node.hi_z);
    nodes[i] = node;
    traversal = pc_lane_bits(ray_boxes_hit_wide_fused(&f, r[3], r[7] * slab_widening(), nodes + i, &enter));
  }
  /* An empty lane entered shows as bit 4. */
  out[i] = flags | (robust == (1u << at) ? 1u : 0u) | (traversal == (1u << at) ? 2u : 0u) |
           ((robust | traversal) & ~(1u << at) ? 16u : 0u);
}
#endif

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
  Ray ray = ray_from_record(rays + i);
  RayPrecomp rp = ray_precompute(ray.d);
  Hit hit;
  hit_init(&hit, &ray);
  for (uint p = 0; p < prim_count; ++p) intersect_prim(0, prims, p, &ray, &rp, rp.kz, hit.t, &hit);
  HitRecord out;
  out.t = hit.slot == PC_INVALID ? INFINITY : hit.t;
  out.prim = hit.slot == PC_INVALID ? PC_INVALID : prim_index_of(prims[hit.slot]);
  out.u = hit.u;
  out.v = hit.v;
  hits[i] = out;
}

#include "surface.cl"

/* Rays spawned from surface points, as the integrator spawns them (offset origin, own primitive
 * skipped). queries: 8 floats each: slot (uint bits), u, v, then either a direction (mode 0: closest
 * hit, any hit counts as a self-intersection) or, in mode 1, the slot, u, v of a second point (a
 * shadow ray to it, stopped short like the integrator's). out: scene-order primitive hit, or PC_INVALID. */
/* The surface at triangle slot q[0] (uint bits), barycentrics q[1], q[2], of a scene without placed
 * instances (instance 0 is the whole scene, untransformed). */
static inline Surface query_surface(__global const Primitive* prims, __global const PrimShading* shading,
                                    __global const float4* normals, __global const Instance* instances,
                                    __global const float* q) {
  SceneData sc; /* the arrays scene_surface reads */
  sc.prims = prims;
  sc.shading = shading;
  sc.normals = normals;
  sc.instances = instances;
  Ray unused; /* read only for spheres */
  unused.o = (float3)(0.0f);
  unused.d = (float3)(0.0f, 0.0f, 1.0f);
  unused.tmin = unused.tmax = 0.0f;
  unused.skip_prim = unused.skip_instance = unused.cutout_seed = PC_INVALID;
  Hit at;
  at.t = 0.0f;
  at.slot = as_uint(q[0]);
  at.prim = 0u;
  at.instance = 0u; /* the world instance, identity (tests/robustness_test.cpp: no placed meshes) */
  at.u = q[1];
  at.v = q[2];
  return scene_surface(&sc, &unused, &at);
}

__kernel void spawn_test(__global const WideNode* nodes, __global const LeafBlock* blocks, __global const Primitive* prims,
                         __global const PrimShading* shading, __global const float4* normals,
                         __global const Instance* instances, __global const float* queries, uint mode,
                         __global uint* out) {
  uint i = get_global_id(0);
  __global const float* q = queries + 8 * i;
  Surface s = query_surface(prims, shading, normals, instances, q);
  Ray ray;
  ray.tmin = 0.0f;
  ray.skip_prim = s.prim;
  ray.skip_instance = s.instance;
  if (mode == 0u) {
    ray.d = pc_normalize(vload3(0, q + 3));
    ray.o = offset_ray_origin(s.p, s.p_err, s.ng, ray.d);
    ray.tmax = INFINITY;
  } else {
    Surface target = query_surface(prims, shading, normals, instances, q + 3);
    ray = spawn_ray_to(s.p, s.p_err, s.ng, s.prim, s.instance, target.p, target.p_err, target.ng);
  }
  Hit hit;
  out[i] = trace_bvh(0, nodes, blocks, prims, &ray, mode == 1u, &hit) ? prim_index_of(prims[hit.slot]) : PC_INVALID;
}

#include "texture.cl"

/* Texture lookups: out[i] = texture_lookup(texture `index`, uvs[i]). */
__kernel void texture_lookup_test(__global const Texture* textures, __global const uint* texels, uint index,
                                  __global const float2* uvs, __global float4* out) {
  uint i = get_global_id(0);
  out[i] = (float4)(texture_lookup(textures, texels, index, uvs[i]), 0.0f);
}
