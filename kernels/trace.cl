/* Traces a ray file through the renderer's own traversal (pathcl rays): the nearest hits, or with
 * any_hit the first found (shadow rays: only whether there is one is the same for every traversal). */
#include "shared/types.h"
#include "math.cl"
#include "intersect.cl"

/* A ray's record: its hit, or t = INFINITY and no primitive. The hit's own scene-order index, not
 * prims[hit->slot]'s: that load is a cache miss per ray on a large scene (a tenth of the kernel's time on
 * the terrain's bounce rays). */
static inline HitRecord hit_record(bool found, const Hit* hit) {
  HitRecord out;
  out.t = found ? hit->t : INFINITY;
  out.prim = found ? hit->prim : PC_INVALID;
  out.u = found ? hit->u : 0.0f;
  out.v = found ? hit->v : 0.0f;
  return out;
}

__kernel void trace_rays(__global const WideNode* nodes, __global const LeafBlock* blocks, __global const Primitive* prims,
                         __global const RayRecord* rays, __global HitRecord* hits, uint count, uint any_hit) {
  uint i = get_global_id(0);
  if (i >= count) return;
  Ray ray = ray_from_record(rays + i);
  Hit hit;
  bool found = trace_bvh(0, nodes, blocks, prims, &ray, any_hit != 0u, &hit);
  hits[i] = hit_record(found, &hit);
}

#ifdef PC_BVH_WIDE
#include "packet.cl"

/* The same as packets (kernels/packet.cl): work item i traces rays [N i, N i + N) together; the lanes
 * past count are inactive. */
#define PC_TRACE_RAYS_PACKET(N)                                                                           \
  __kernel void trace_rays_packet##N(__global const WideNode* nodes, __global const LeafBlock* blocks,     \
                                     __global const Primitive* prims, __global const RayRecord* rays,     \
                                     __global HitRecord* hits, uint count, uint any_hit) {                \
    uint first = get_global_id(0) * N;                                                                    \
    if (first >= count) return;                                                                           \
    Ray r[N];                                                                                             \
    Hit h[N];                                                                                             \
    bool found[N];                                                                                        \
    uint bits = 0u;                                                                                       \
    for (uint j = 0u; j < N; ++j) {                                                                       \
      r[j] = ray_from_record(rays + min(first + j, count - 1u));                                          \
      if (first + j < count) bits |= 1u << j;                                                             \
    }                                                                                                     \
    trace_rays_as_packet##N(0, nodes, blocks, prims, r, bits, any_hit != 0u, h, found);                   \
    for (uint j = 0u; j < N && first + j < count; ++j) hits[first + j] = hit_record(found[j], h + j); \
  }
PC_TRACE_RAYS_PACKET(8)
PC_TRACE_RAYS_PACKET(16)
#undef PC_TRACE_RAYS_PACKET
#endif
