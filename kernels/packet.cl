/* Packet traversal of the 8- or 16-wide BVH (issue 15): the W = 8 or 16 rays of a lane-generic work item traced
 * together, each node's boxes and each leaf's triangles tested against all W rays at once in vector
 * registers. Each lane does the operations of the single-ray code (kernels/intersect.cl: the slab test,
 * the watertight test of intersect_block, the (t, primitive) order of intersect_prim), and a lane keeps
 * every subtree that its own ray enters (up to its nearest hit widened as the node test widens it:
 * pop_subtree), so its hit is the nearest of the same total order as the single ray's, bit for bit;
 * traversal order, and the leaves a lane tests only because another lane entered them, cannot change a
 * minimum. Spheres and cut-outs are tested lane by lane with the single-ray code. */
#ifndef PATHCL_PACKET_CL
#define PATHCL_PACKET_CL

#include "intersect.cl"
#include "lanes.cl"

#ifdef PC_BVH_WIDE

/* Element index[j] of table for each lane j: one vpermps where clang targets AVX-512 (PoCL on such CPUs;
 * OpenCL's shuffle() with a variable mask is a loop over the elements there). Elsewhere packet_leaf
 * selects with masks instead: the same values, so the same bits. */
#if defined(__clang__) && defined(__AVX512F__)
#define PC_TABLE_LOOKUP
static inline float16 pc_table_lookup(float16 table, int16 index) { return __builtin_ia32_permvarsf512(table, index); }
static inline PC_OVL void pc_narrow(float16 v, float16* out) { *out = v; }
static inline PC_OVL void pc_narrow(float16 v, float8* out) { *out = v.lo; }
static inline PC_OVL int16 pc_widen(uint16 v) { return as_int16(v); }
static inline PC_OVL int16 pc_widen(uint8 v) { return as_int16((uint16)(v, v)); }
#endif

#ifdef PC_HAS_CUTOUTS
/* Accepted lanes keep a hit only where the cut-out stops the ray (kernels/cutout.cl), lane by lane. */
#define PC_PACKET_CUTOUTS(N)                                                                              \
  if (pc_any_(accept)) {                                                                                  \
    uint bits = pc_lane_bits(accept);                                                                     \
    for (uint j = 0u; j < N; ++j)                                                                         \
      if (((bits >> j) & 1u) && !cutout_stops(cut, prim, pc_lane(V_ * inv_det, j), pc_lane(W_ * inv_det, j), \
                                              pc_lane(r->cutout_seed, j)))                                \
        bits &= ~(1u << j);                                                                               \
    accept = pc_lanes_of_bits(bits, accept);                                                              \
  }
#else
#define PC_PACKET_CUTOUTS(N)
#endif
#ifdef PC_TABLE_LOOKUP
/* kx = kz + 1 and ky = kz + 2 (mod 3), as in ray_precompute */
#define PC_LANE_AXES_AT                                                                                   \
  int16 z = pc_widen(kz), x = select(z + 1, (int16)(0), z == 2), y = select(x + 1, (int16)(0), x == 2); \
  a.at_x = 4 * x, a.at_y = 4 * y, a.at_z = 4 * z;
/* Sixteen floats from c on: the lane's x, y and z at 0, 4 and 8 (LeafBlock's ax ay az, or bx .., cx ..;
 * from cx on the load runs on into the block's prim and counts, still inside it). */
#define PC_BLOCK_VERTEX_ON_AXES(F)                                                                        \
  float16 table = vload16(0, c);                                                                          \
  pc_narrow(pc_table_lookup(table, a->at_x), x);                                                          \
  pc_narrow(pc_table_lookup(table, a->at_y), y);                                                          \
  pc_narrow(pc_table_lookup(table, a->at_z), z);
#else
#define PC_LANE_AXES_AT
#define PC_BLOCK_VERTEX_ON_AXES(F) pc_permute_lanes(lane3((F)(c[0]), (F)(c[4]), (F)(c[8])), a->z_is_x, a->z_is_y, a->z_is_z, x, y, z);
#endif
#define PC_LANE_W 8
#include "templates/packet.cl"
#define PC_LANE_W 16
#include "templates/packet.cl"
#undef PC_PACKET_CUTOUTS
#undef PC_LANE_AXES_AT
#undef PC_BLOCK_VERTEX_ON_AXES

#endif /* PC_BVH_WIDE */
#endif
