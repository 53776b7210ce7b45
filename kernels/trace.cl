/* Traces a ray file through the renderer's own traversal (pathcl rays). */
#include "shared/types.h"
#include "math.cl"
#include "intersect.cl"

__kernel void trace_rays(__global const WideNode* nodes, __global const LeafBlock* blocks, __global const Primitive* prims,
                         __global const RayRecord* rays, __global HitRecord* hits, uint count) {
  uint i = get_global_id(0);
  if (i >= count) return;
  Ray ray = ray_from_record(rays + i);
  Hit hit;
  HitRecord out;
  if (trace_bvh(0, nodes, blocks, prims, &ray, false, &hit)) {
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
