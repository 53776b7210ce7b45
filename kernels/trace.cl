/* Traces a ray file through the renderer's own traversal (pathcl rays): the nearest hits, or with
 * any_hit the first found (shadow rays: only whether there is one is the same for every traversal). */
#include "shared/types.h"
#include "math.cl"
#include "intersect.cl"

__kernel void trace_rays(__global const WideNode* nodes, __global const LeafBlock* blocks, __global const Primitive* prims,
                         __global const RayRecord* rays, __global HitRecord* hits, uint count, uint any_hit) {
  uint i = get_global_id(0);
  if (i >= count) return;
  Ray ray = ray_from_record(rays + i);
  Hit hit;
  HitRecord out;
  if (trace_bvh(0, nodes, blocks, prims, &ray, any_hit != 0u, &hit)) {
    out.t = hit.t;
    out.prim = prim_index_of(prims[hit.slot]);
    out.u = hit.u;
    out.v = hit.v;
  } else {
    out.t = INFINITY;
    out.prim = PC_INVALID;
    out.u = 0.0f;
    out.v = 0.0f;
  }
  hits[i] = out;
}

#ifdef PC_BVH8
#include "packet.cl"

/* The same as packets (kernels/packet.cl): work item i traces rays [N i, N i + N) together; the lanes
 * past count are inactive. */
#define PC_TRACE_RAYS_PACKET(V3, F, I, U, N)                                                              \
  __kernel void trace_rays_packet##N(__global const WideNode* nodes, __global const LeafBlock* blocks,     \
                                     __global const Primitive* prims, __global const RayRecord* rays,     \
                                     __global HitRecord* hits, uint count, uint any_hit) {                \
    uint first = get_global_id(0) * N;                                                                    \
    if (first >= count) return;                                                                           \
    float o[3][N], d[3][N], tmin[N], tmax[N];                                                             \
    uint lane_in[N];                                                                                      \
    for (uint j = 0u; j < N; ++j) {                                                                       \
      Ray ray = ray_from_record(rays + min(first + j, count - 1u));                                       \
      o[0][j] = ray.o.x, o[1][j] = ray.o.y, o[2][j] = ray.o.z;                                            \
      d[0][j] = ray.d.x, d[1][j] = ray.d.y, d[2][j] = ray.d.z;                                            \
      tmin[j] = ray.tmin;                                                                                 \
      tmax[j] = ray.tmax;                                                                                 \
      lane_in[j] = first + j < count ? 0xffffffffu : 0u;                                                  \
    }                                                                                                     \
    RayPacket##N r;                                                                                       \
    r.o = lane3(vload##N(0, o[0]), vload##N(0, o[1]), vload##N(0, o[2]));                                 \
    r.d = lane3(vload##N(0, d[0]), vload##N(0, d[1]), vload##N(0, d[2]));                                 \
    r.tmin = vload##N(0, tmin);                                                                           \
    r.skip_prim = (U)(PC_INVALID);                                                                        \
    r.cutout_seed = (U)(0u);                                                                              \
    HitPacket##N h;                                                                                       \
    h.t = vload##N(0, tmax);                                                                              \
    h.u = h.v = (F)(0.0f);                                                                                \
    h.slot = h.prim = (U)(PC_INVALID);                                                                    \
    I hit = trace_packet(0, nodes, blocks, prims, 0u, &r, as_int##N(vload##N(0, lane_in)), any_hit != 0u, &h); \
    float t[N], u[N], v[N];                                                                               \
    uint slot[N];                                                                                         \
    int found[N];                                                                                         \
    vstore##N(h.t, 0, t);                                                                                 \
    vstore##N(h.u, 0, u);                                                                                 \
    vstore##N(h.v, 0, v);                                                                                 \
    vstore##N(h.slot, 0, slot);                                                                           \
    vstore##N(hit, 0, found);                                                                             \
    for (uint j = 0u; j < N && first + j < count; ++j) {                                                  \
      HitRecord out;                                                                                      \
      out.t = found[j] ? t[j] : INFINITY;                                                                 \
      out.prim = found[j] ? prim_index_of(prims[slot[j]]) : PC_INVALID;                                   \
      out.u = found[j] ? u[j] : 0.0f;                                                                     \
      out.v = found[j] ? v[j] : 0.0f;                                                                     \
      hits[first + j] = out;                                                                              \
    }                                                                                                     \
  }
PC_TRACE_RAYS_PACKET(lane3f8, float8, int8, uint8, 8)
PC_TRACE_RAYS_PACKET(lane3f16, float16, int16, uint16, 16)
#undef PC_TRACE_RAYS_PACKET
#endif
