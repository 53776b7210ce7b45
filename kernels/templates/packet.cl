/* packet.cl's types and functions of one width: a template, included by packet.cl once per lane width
 * PC_LANE_W (8, 16) with templates/lane_width.h's types F, I, U and V3, N the width and PC_LANE_NAME(x)
 * the name x followed by it (RayPacket8). */
#include "templates/lane_width.h"
#define N PC_LANE_W

/* W rays (lane3 origins and directions, tmin per lane, the primitive each leaves from or PC_INVALID, and
 * their cut-out seeds) and their hits: t starts at the ray's tmax and is the nearest hit's, prim and slot
 * are PC_INVALID for a miss (intersect.cl's Hit, by lane). */
typedef struct {
  V3 o, d;
  F tmin;
  U skip_prim, cutout_seed;
} PC_LANE_NAME(RayPacket);
typedef struct {
  F t, u, v;
  U slot, prim;
} PC_LANE_NAME(HitPacket);

/* The components of v on a lane's axes kx, ky, kz (ray_precompute's: kx = kz + 1, ky = kz + 2, mod 3)
 * from the three masks kz == 0, 1, 2: three masks for the six selections, where the axes' own
 * comparisons were six (and spilled mask registers in packet_leaf's loop). */
static inline PC_OVL void pc_permute_lanes(V3 v, I z_is_x, I z_is_y, I z_is_z, F* x, F* y, F* z) {
  *x = select(select(v.x, v.y, z_is_x), v.z, z_is_y);
  *y = select(select(v.x, v.y, z_is_z), v.z, z_is_x);
  *z = select(select(v.x, v.y, z_is_y), v.z, z_is_z);
}
/* How packet_leaf finds a block's vertex coordinates on each lane's axes: the masks kz == 0, 1, 2,
 * and with PC_TABLE_LOOKUP each axis's place in a block's coordinates (x 0, y 4, z 8 floats on). */
typedef struct {
  I z_is_x, z_is_y, z_is_z;
  int16 at_x, at_y, at_z;
} PC_LANE_NAME(LaneAxes);
static inline PC_OVL PC_LANE_NAME(LaneAxes) lane_axes(U kz) {
  PC_LANE_NAME(LaneAxes) a;
  a.z_is_x = kz == 0u, a.z_is_y = kz == 1u, a.z_is_z = kz == 2u;
  PC_LANE_AXES_AT
  return a;
}
/* Vertex coordinates c[0], c[4], c[8] (x, y, z of one block lane) on each lane's axes kx, ky, kz. */
static inline PC_OVL void block_vertex_on_axes(__global const float* c, const PC_LANE_NAME(LaneAxes)* a, F* x, F* y, F* z) {
  PC_BLOCK_VERTEX_ON_AXES(F)
}
/* Lane j of the packet as a single ray (its nearest hit so far as tmax), and its hit. */
static inline PC_OVL Ray packet_ray_lane(const PC_LANE_NAME(RayPacket)* r, uint j, const PC_LANE_NAME(HitPacket)* h, Hit* hit) {
  Ray ray;
  ray.o = (float3)(pc_lane(r->o.x, j), pc_lane(r->o.y, j), pc_lane(r->o.z, j));
  ray.d = (float3)(pc_lane(r->d.x, j), pc_lane(r->d.y, j), pc_lane(r->d.z, j));
  ray.tmin = pc_lane(r->tmin, j);
  ray.tmax = pc_lane(h->t, j);
  ray.skip_prim = pc_lane(r->skip_prim, j);
  ray.skip_instance = PC_INVALID;
  ray.cutout_seed = pc_lane(r->cutout_seed, j);
  hit->t = ray.tmax;
  hit->u = pc_lane(h->u, j);
  hit->v = pc_lane(h->v, j);
  hit->slot = pc_lane(h->slot, j);
  hit->prim = pc_lane(h->prim, j);
  hit->instance = PC_INVALID;
  return ray;
}
static inline PC_OVL void packet_set_hit_lane(PC_LANE_NAME(HitPacket)* h, uint j, const Hit* hit) {
  h->t = pc_with_lane(h->t, j, hit->t);
  h->u = pc_with_lane(h->u, j, hit->u);
  h->v = pc_with_lane(h->v, j, hit->v);
  h->slot = pc_with_lane(h->slot, j, hit->slot);
  h->prim = pc_with_lane(h->prim, j, hit->prim);
}
/* Lane j against one primitive with the single-ray code (spheres; intersect_prim). Returns whether
 * lane j's hit changed. */
static inline PC_OVL bool packet_prim_lane(const SceneData* cut, __global const Primitive* prims, uint slot,
                                           const PC_LANE_NAME(RayPacket)* r, uint j, PC_LANE_NAME(HitPacket)* h) {
  Hit hit;
  Ray ray = packet_ray_lane(r, j, h, &hit);
  RayPrecomp rp = ray_precompute(ray.d);
  if (!intersect_prim(cut, prims, slot, &ray, &rp, rp.kz, hit.t, &hit)) return false;
  packet_set_hit_lane(h, j, &hit);
  return true;
}
/* The packet's rays lane by lane for the single-ray traversal of packet_subtrees_by_lane: each lane's
 * ray and its ray_precompute (the packet's own per-lane values: the same operations, the same bits),
 * stored once a traversal first needs them. */
typedef struct {
  float ox[N], oy[N], oz[N], dx[N], dy[N], dz[N], tmin[N], ix[N], iy[N], iz[N], sx[N], sy[N], sz[N];
  uint skip_prim[N], cutout_seed[N], kz[N];
} PC_LANE_NAME(PacketByLane);
static inline PC_OVL void packet_by_lane(const PC_LANE_NAME(RayPacket)* r, V3 inv_d, U kz, F sx, F sy, F sz,
                                         PC_LANE_NAME(PacketByLane)* l) {
  PC_LANE_NAME(vstore)(r->o.x, 0, l->ox), PC_LANE_NAME(vstore)(r->o.y, 0, l->oy), PC_LANE_NAME(vstore)(r->o.z, 0, l->oz);
  PC_LANE_NAME(vstore)(r->d.x, 0, l->dx), PC_LANE_NAME(vstore)(r->d.y, 0, l->dy), PC_LANE_NAME(vstore)(r->d.z, 0, l->dz);
  PC_LANE_NAME(vstore)(r->tmin, 0, l->tmin), PC_LANE_NAME(vstore)(r->skip_prim, 0, l->skip_prim);
  PC_LANE_NAME(vstore)(r->cutout_seed, 0, l->cutout_seed);
  PC_LANE_NAME(vstore)(inv_d.x, 0, l->ix), PC_LANE_NAME(vstore)(inv_d.y, 0, l->iy), PC_LANE_NAME(vstore)(inv_d.z, 0, l->iz);
  PC_LANE_NAME(vstore)(sx, 0, l->sx), PC_LANE_NAME(vstore)(sy, 0, l->sy), PC_LANE_NAME(vstore)(sz, 0, l->sz), PC_LANE_NAME(vstore)(kz, 0, l->kz);
}
/* Each lane in bits alone through the subtree at node root with the single-ray traversal, for subtrees
 * few lanes entered. Returns the lanes whose hit changed. */
static inline PC_OVL uint packet_subtrees_by_lane(const SceneData* cut, __global const WideNode* nodes,
                                                  __global const LeafBlock* blocks, __global const Primitive* prims,
                                                  uint root, const PC_LANE_NAME(PacketByLane)* l, uint bits, bool any_hit,
                                                  PC_LANE_NAME(HitPacket)* h) {
  float t[N], u[N], v[N];
  uint slot[N], prim[N], changed = 0u;
  PC_LANE_NAME(vstore)(h->t, 0, t), PC_LANE_NAME(vstore)(h->u, 0, u), PC_LANE_NAME(vstore)(h->v, 0, v);
  PC_LANE_NAME(vstore)(h->slot, 0, slot), PC_LANE_NAME(vstore)(h->prim, 0, prim);
  PC_EACH_LANE(j, bits) {
    Ray ray;
    ray.o = (float3)(l->ox[j], l->oy[j], l->oz[j]);
    ray.d = (float3)(l->dx[j], l->dy[j], l->dz[j]);
    ray.tmin = l->tmin[j];
    ray.tmax = t[j];
    ray.skip_prim = l->skip_prim[j];
    ray.skip_instance = PC_INVALID;
    ray.cutout_seed = l->cutout_seed[j];
    RayPrecomp rp;
    rp.inv_d = (float3)(l->ix[j], l->iy[j], l->iz[j]);
    rp.sx = l->sx[j], rp.sy = l->sy[j], rp.sz = l->sz[j], rp.kz = l->kz[j];
    Hit hit;
    hit.t = t[j], hit.u = u[j], hit.v = v[j], hit.slot = slot[j], hit.prim = prim[j];
    hit.instance = PC_INVALID;
    trace_tree_precomputed(cut, nodes, blocks, prims, root, &ray, &rp, any_hit, &hit);
    if (hit.t == t[j] && hit.prim == prim[j]) continue;
    t[j] = hit.t, u[j] = hit.u, v[j] = hit.v, slot[j] = hit.slot, prim[j] = hit.prim;
    changed |= 1u << j;
  }
  if (changed != 0u) {
    h->t = PC_LANE_NAME(vload)(0, t), h->u = PC_LANE_NAME(vload)(0, u), h->v = PC_LANE_NAME(vload)(0, v);
    h->slot = PC_LANE_NAME(vload)(0, slot), h->prim = PC_LANE_NAME(vload)(0, prim);
  }
  return changed;
}
/* The packet's active lanes against a leaf reference's blocks; returns the lanes whose hit changed. Out of
 * line: trace_packet calls it from two places. */
PC_OUT_OF_LINE PC_OVL I packet_leaf(const SceneData* cut, __global const LeafBlock* blocks,
                                    __global const Primitive* prims, uint ref, const PC_LANE_NAME(RayPacket)* r, U kz,
                                    F sx, F sy, F sz, I active, PC_LANE_NAME(HitPacket)* h) {
  /* Derived from kz here at every leaf: passed in from trace_packet (computed once a packet) they were
   * spilled and reloaded instead, and the Cornell box at 16 lanes ran 4.3 % slower. */
  PC_LANE_NAME(LaneAxes) axes = lane_axes(kz);
  F okx, oky, okz;
  pc_permute_lanes(r->o, axes.z_is_x, axes.z_is_y, axes.z_is_z, &okx, &oky, &okz);
  I changed = (I)(0);
  for (__global const LeafBlock* b = wide_leaf(blocks, ref);; ++b) {
    __global const float* c = (__global const float*)b; /* ax ay az bx by bz cx cy cz, 4 lanes each */
    for (uint i = 0u; i < b->count; ++i) {
      if (pc_block_spheres(b) & (1u << i)) {
        uint bits = pc_lane_bits(active), hit_bits = 0u;
        for (uint j = 0u; j < N; ++j)
          if (((bits >> j) & 1u) && packet_prim_lane(cut, prims, b->first_slot + i, r, j, h))
            hit_bits |= 1u << j;
        changed |= pc_lanes_of_bits(hit_bits, changed);
        continue;
      }
      /* The vertices' coordinates on each lane's axes: the single-ray test's (a[kx] - o[kx]) etc. */
      F akx, aky, akz, bkx, bky, bkz, ckx, cky, ckz;
      block_vertex_on_axes(c + i, &axes, &akx, &aky, &akz);
      block_vertex_on_axes(c + 12u + i, &axes, &bkx, &bky, &bkz);
      block_vertex_on_axes(c + 24u + i, &axes, &ckx, &cky, &ckz);
      F Akz = akz - okz, Bkz = bkz - okz, Ckz = ckz - okz;
      F Ax = (akx - okx) + sx * Akz, Ay = (aky - oky) + sy * Akz;
      F Bx = (bkx - okx) + sx * Bkz, By = (bky - oky) + sy * Bkz;
      F Cx = (ckx - okx) + sx * Ckz, Cy = (cky - oky) + sy * Ckz;
      F U_ = Cx * By - Cy * Bx;
      F V_ = Ax * Cy - Ay * Cx;
      F W_ = Bx * Ay - By * Ax;
      I outside = ((U_ < 0.0f) | (V_ < 0.0f) | (W_ < 0.0f)) & ((U_ > 0.0f) | (V_ > 0.0f) | (W_ > 0.0f));
      F det = U_ + V_ + W_;
      uint prim = b->prim[i];
      I inside = active & !outside & (det != 0.0f) & (r->skip_prim != (U)(prim));
      if (!pc_any_(inside)) continue; /* most tests: no lane's ray crosses the triangle */
      F Az = sz * Akz, Bz = sz * Bkz, Cz = sz * Ckz;
      F T = U_ * Az + V_ * Bz + W_ * Cz;
      I before_tmin = select(T <= r->tmin * det, T >= r->tmin * det, det < 0.0f);
      F inv_det = 1.0f / det;
      F t = T * inv_det;
      /* intersect_prim's order: nearer, or as near and a lower primitive index. */
      I accept = inside & !before_tmin & (t <= h->t) & ((t < h->t) | ((U)(prim) < h->prim));
      PC_PACKET_CUTOUTS(N)
      if (!pc_any_(accept)) continue;
      h->t = select(h->t, t, accept);
      h->u = select(h->u, V_ * inv_det, accept);
      h->v = select(h->v, W_ * inv_det, accept);
      h->slot = select(h->slot, (U)(b->first_slot + i), accept);
      h->prim = select(h->prim, (U)(prim), accept);
      changed |= accept;
    }
    if (b->last) return changed;
  }
}
/* The lanes in lanes against a leaf (packet_leaf), their hits added to *found; with any_hit those that
 * found one leave *active. Returns whether any lane is still active. */
PC_LANE_INLINE PC_OVL bool packet_visit_leaf(const SceneData* cut, __global const LeafBlock* blocks,
                                            __global const Primitive* prims, uint ref, const PC_LANE_NAME(RayPacket)* r,
                                            U kz, F sx, F sy, F sz, I lanes, bool any_hit, I* active, I* found,
                                            PC_LANE_NAME(HitPacket)* h) {
  I changed = packet_leaf(cut, blocks, prims, ref, r, kz, sx, sy, sz, lanes, h);
  *found |= changed;
  if (any_hit) *active &= !changed;
  return pc_any_(*active);
}
/* The packet through the tree from node root (closest hit; with any_hit a lane stops at its first hit,
 * and the returned mask is of the lanes that have one). The stack holds each pushed subtree's entry
 * distance per lane (NaN where the lane's ray missed its box): when popped, a lane enters it where the
 * single ray would, where that distance is no farther than its nearest hit so far times
 * slab_widening() (pop_subtree). */
static inline PC_OVL I trace_packet(const SceneData* cut, __global const WideNode* nodes,
                                    __global const LeafBlock* blocks, __global const Primitive* prims, uint root,
                                    const PC_LANE_NAME(RayPacket)* r, I active, bool any_hit, PC_LANE_NAME(HitPacket)* h) {
  /* ray_precompute by lane */
  V3 inv_d = lane3(1.0f / r->d.x, 1.0f / r->d.y, 1.0f / r->d.z);
  I neg_x = inv_d.x < 0.0f, neg_y = inv_d.y < 0.0f, neg_z = inv_d.z < 0.0f;
  F adx = fabs(r->d.x), ady = fabs(r->d.y), adz = fabs(r->d.z);
  U kz = select(select((U)(2u), (U)(1u), ady > adz), select((U)(2u), (U)(0u), adx > adz), adx > ady);
  F dkx, dky, dz;
  pc_permute_lanes(r->d, kz == 0u, kz == 1u, kz == 2u, &dkx, &dky, &dz);
  F sx = -dkx / dz, sy = -dky / dz, sz = 1.0f / dz;
  /* Where the rays point into one octant (camera rays, shadow rays towards a light: they go on
   * together), a subtree that at most a quarter of the lanes enter is traced lane by lane (the same
   * hits); where not (bounce rays: below the top of a large tree they enter few of the same boxes, and
   * a packet does the work of all its lanes at every node), every subtree below the root but the
   * leaves: against those that at most three quarters enter, the terrain at 16 lanes +3.7 %, packets
   * of 8 bounce rays +7.4 %, the Cornell box and glass-metal (whose root's children are mostly leaves)
   * unchanged; the root lane by lane as well: the terrain +5.9 %, but the Cornell box -20 %
   * (docs/benchmarks-notes.md). Where not, too, a node's leaf children are tested as their boxes are,
   * in their slots' order, instead of pushed by distance and popped: such lanes enter nearly all of a
   * small scene's leaves whatever the order, and a leaf tested at once lowers the hits that the next
   * boxes are tested against. The Cornell box +7 % on AVX2 code and +8 % on AVX-512 code, glass-metal +3 %,
   * the terrain unchanged; one-octant packets stay in order of distance. */
  uint all = pc_lane_bits(active), bx = pc_lane_bits(active & neg_x);
  uint by = pc_lane_bits(active & neg_y), bz = pc_lane_bits(active & neg_z);
  bool one_octant = (bx == 0u || bx == all) && (by == 0u || by == all) && (bz == 0u || bz == all);
  I found = (I)(0);
  uint stack[(PC_BVH_WIDE - 1) * PC_BVH_STACK];
  float stack_key[(PC_BVH_WIDE - 1) * PC_BVH_STACK];
  F stack_entry[(PC_BVH_WIDE - 1) * PC_BVH_STACK]; /* per lane; NaN for a lane that did not enter */
  int sp = 0;
  uint ref = root;
  I lanes = active;
  PC_LANE_NAME(PacketByLane) by_lane;
  bool by_lane_ready = false;
  for (;;) {
    if (ref & PC_BVH4_LEAF) {
      if (!packet_visit_leaf(cut, blocks, prims, ref, r, kz, sx, sy, sz, lanes, any_hit, &active, &found, h)) return found;
    } else {
      __global const WideNode* n = wide_node(nodes, ref);
      int base = sp;
      for (uint c = 0u; c < PC_BVH_WIDE; ++c) {
        uint child = n->child[c];
        if (child == PC_INVALID) break; /* the used slots come first (scene/bvh_build.cpp) */
        /* ray_boxes_hit8's slab test, one box against each lane's ray. */
        F lx = (n->lo_x[c] - r->o.x) * inv_d.x, hx = (n->hi_x[c] - r->o.x) * inv_d.x;
        F ly = (n->lo_y[c] - r->o.y) * inv_d.y, hy = (n->hi_y[c] - r->o.y) * inv_d.y;
        F lz = (n->lo_z[c] - r->o.z) * inv_d.z, hz = (n->hi_z[c] - r->o.z) * inv_d.z;
        F enter;
        I in = lanes & slab_hits(select(lx, hx, neg_x), select(hx, lx, neg_x), select(ly, hy, neg_y),
                                 select(hy, ly, neg_y), select(lz, hz, neg_z), select(hz, lz, neg_z), r->tmin,
                                 h->t, &enter);
        if (!pc_any_(in)) continue;
        if ((child & PC_BVH4_LEAF) && !one_octant) {
          if (!packet_visit_leaf(cut, blocks, prims, child, r, kz, sx, sy, sz, in, any_hit, &active, &found, h))
            return found;
          lanes &= active;
          continue;
        }
        /* Onto the stack, kept sorted far to near (by the nearest lane's entry) from where this node's
         * entries start. */
        F e = select((F)(NAN), enter, in);
        float d = pc_min_lanes(select((F)(INFINITY), enter, in));
        int j = sp++;
        while (j > base && stack_key[j - 1] < d) {
          stack[j] = stack[j - 1];
          stack_key[j] = stack_key[j - 1];
          stack_entry[j] = stack_entry[j - 1];
          --j;
        }
        prefetch_subtree(nodes, blocks, child);
        stack[j] = child;
        stack_key[j] = d;
        stack_entry[j] = e;
      }
    }
    /* The next subtree some of whose lanes can still hit nearer than they have. */
    for (;;) {
      if (sp == 0) return any_hit ? found : h->slot != (U)(PC_INVALID);
      --sp;
      /* The lanes that entered it no farther than their nearest hit, widened (the single ray's test,
       * pop_subtree: against t itself the order of the leaves decided ties at a shared edge). */
      lanes = active & (stack_entry[sp] <= h->t * slab_widening());
      if (!pc_any_(lanes)) continue;
      uint bits = pc_lane_bits(lanes);
      if ((one_octant && 4u * popcount(bits) > N) || (stack[sp] & PC_BVH4_LEAF)) break;
      if (!by_lane_ready) packet_by_lane(r, inv_d, kz, sx, sy, sz, &by_lane);
      by_lane_ready = true;
      uint changed = packet_subtrees_by_lane(cut, nodes, blocks, prims, stack[sp], &by_lane, bits, any_hit, h);
      found |= pc_lanes_of_bits(changed, found);
      if (any_hit) {
        active &= !pc_lanes_of_bits(changed, active);
        if (!pc_any_(active)) return found;
      }
    }
    ref = stack[sp];
  }
}

/* rays[0 .. N) through the tree at node 0 as one packet, the lanes set in bits only: hits[j] (instance
 * PC_INVALID) and found[j] for each of those (pathcl rays' packets, the lane kernels' rays). */
static inline void PC_LANE_NAME(trace_rays_as_packet)(const SceneData* cut, __global const WideNode* nodes,
                                    __global const LeafBlock* blocks, __global const Primitive* prims,
                                    const Ray* rays, uint bits, bool any_hit, Hit* hits, bool* found) {
  float v[8][N];
  uint w[3][N];
  for (uint j = 0u; j < N; ++j) {
    const Ray* r = rays + j;
    v[0][j] = r->o.x, v[1][j] = r->o.y, v[2][j] = r->o.z, v[3][j] = r->d.x, v[4][j] = r->d.y, v[5][j] = r->d.z;
    v[6][j] = r->tmin, v[7][j] = r->tmax;
    w[0][j] = r->skip_prim, w[1][j] = r->cutout_seed, w[2][j] = ((bits >> j) & 1u) ? 0xffffffffu : 0u;
  }
  PC_LANE_NAME(RayPacket) p;
  p.o = lane3(PC_LANE_NAME(vload)(0, v[0]), PC_LANE_NAME(vload)(0, v[1]), PC_LANE_NAME(vload)(0, v[2]));
  p.d = lane3(PC_LANE_NAME(vload)(0, v[3]), PC_LANE_NAME(vload)(0, v[4]), PC_LANE_NAME(vload)(0, v[5]));
  p.tmin = PC_LANE_NAME(vload)(0, v[6]);
  p.skip_prim = PC_LANE_NAME(vload)(0, w[0]);
  p.cutout_seed = PC_LANE_NAME(vload)(0, w[1]);
  PC_LANE_NAME(HitPacket) h;
  h.t = PC_LANE_NAME(vload)(0, v[7]);
  h.u = h.v = (F)(0.0f);
  h.slot = h.prim = (U)(PC_INVALID);
  I hit = trace_packet(cut, nodes, blocks, prims, 0u, &p, PC_LANE_NAME(as_int)(PC_LANE_NAME(vload)(0, w[2])), any_hit, &h);
  int m[N];
  PC_LANE_NAME(vstore)(hit, 0, m);
  PC_LANE_NAME(vstore)(h.t, 0, v[0]);
  PC_LANE_NAME(vstore)(h.u, 0, v[1]);
  PC_LANE_NAME(vstore)(h.v, 0, v[2]);
  PC_LANE_NAME(vstore)(h.slot, 0, w[0]);
  PC_LANE_NAME(vstore)(h.prim, 0, w[1]);
  for (uint j = 0u; j < N; ++j) {
    found[j] = m[j] != 0;
    hits[j].t = v[0][j];
    hits[j].u = v[1][j];
    hits[j].v = v[2][j];
    hits[j].slot = w[0][j];
    hits[j].prim = w[1][j];
    hits[j].instance = PC_INVALID;
  }
}

#undef N
#include "templates/lane_width_end.h"
