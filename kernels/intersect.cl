/* Ray/box, ray/triangle and ray/sphere tests and BVH traversal (closest hit and any hit).
 * FP_CONTRACT is off for every program (runtime/kernel_program.cpp puts the pragma on its first line): a
 * fused multiply-add would round the two triangles of a shared edge differently and let rays slip
 * through the edge. */
#ifndef PATHCL_INTERSECT_CL
#define PATHCL_INTERSECT_CL

#define PC_BVH_STACK 64 /* = kBvhMaxDepth of scene/bvh_build.h */

/* Unconditional includes: runtime/kernel_program.cpp expands each file once, where it is first named,
 * whatever #if surrounds that place (cutout.cl's code is under PC_HAS_CUTOUTS itself). */
#include "scene.cl"
#include "cutout.cl"
#include "lanes.cl"

/* The BVH layout of this device (runtime/device.h, bvh_width): PC_BVH_WIDE = 8 or 16 for the CPU trees
 * (nodes of 8 or 16 children followed by their leaves' blocks, in bvh8 or bvh16; kernels/shared/types.h),
 * undefined for the 4-wide tree. WideF and WideI hold one value per child of a wide node. */
#define PC_CAT_(a, b) a##b
#define PC_CAT(a, b) PC_CAT_(a, b)
#if PC_BVH_WIDE == 16
typedef Bvh16Node WideNode;
typedef float16 WideF;
typedef int16 WideI;
#elif PC_BVH_WIDE == 8
typedef Bvh8Node WideNode;
typedef float8 WideF;
typedef int8 WideI;
#elif defined(PC_BVH_WIDE)
#error "PC_BVH_WIDE: 8 or 16"
#else
typedef Bvh4Node WideNode;
#endif
#ifdef PC_BVH_WIDE
#define wide_load(p) PC_CAT(vload, PC_BVH_WIDE)(0, p)
#define wide_store(v, p) PC_CAT(vstore, PC_BVH_WIDE)(v, 0, p)
#endif

typedef struct {
  float3 o, d;
  float tmin, tmax;
  uint skip_prim; /* scene-order primitive the ray leaves from, or PC_INVALID */
  uint skip_instance; /* with instances (PC_HAS_INSTANCES): the instance of skip_prim */
  uint cutout_seed; /* with cut-outs: the ray's own random dimension (kernels/cutout.cl) */
} Ray;

typedef struct {
  float t;
  uint slot; /* index into the leaf-ordered primitive array, PC_INVALID for a miss */
  uint prim; /* its scene-order primitive index, PC_INVALID for a miss */
  float u, v; /* barycentrics of vertices b and c */
  uint instance; /* with instances (PC_HAS_INSTANCES): the instance hit, PC_INVALID for a miss */
} Hit;

/* A ray of a ray file (pathcl rays). */
static inline Ray ray_from_record(__global const RayRecord* record) {
  __global const float* r = (__global const float*)record;
  Ray ray;
  ray.o = vload3(0, r);
  ray.tmin = r[3];
  ray.d = vload3(0, r + 4);
  ray.tmax = r[7];
  ray.skip_prim = PC_INVALID;
  ray.skip_instance = PC_INVALID;
  ray.cutout_seed = 0u;
  return ray;
}

/* Per-ray constants of the watertight triangle test (Woop, Benthin, Wald 2013) and the slab test.
 * kz is the dominant axis of the direction, kx and ky the next two. The test does not swap kx and ky
 * for a negative d[kz] as the paper does: that only flips the sign of all three edge functions, and
 * both signs count as a hit here. */
typedef struct {
  float3 inv_d;
  float sx, sy, sz; /* shear: -d[kx] / d[kz], -d[ky] / d[kz], 1 / d[kz] */
  uint kz;
} RayPrecomp;

static inline float axis_component(float3 v, uint k) { return k == 0u ? v.x : k == 1u ? v.y : v.z; }

static inline RayPrecomp ray_precompute(float3 d) {
  RayPrecomp p;
  p.inv_d = 1.0f / d; /* +-inf for axis-parallel rays; ray_box handles the NaNs that may follow */
  float3 ad = fabs(d);
  p.kz = ad.x > ad.y ? (ad.x > ad.z ? 0u : 2u) : (ad.y > ad.z ? 1u : 2u);
  uint kx = p.kz == 2u ? 0u : p.kz + 1u, ky = kx == 2u ? 0u : kx + 1u;
  float dz = axis_component(d, p.kz);
  p.sx = -axis_component(d, kx) / dz;
  p.sy = -axis_component(d, ky) / dz;
  p.sz = 1.0f / dz;
  return p;
}

/* Robust slab test (pbrt-v4) of four, eight or sixteen boxes at once (ray_boxes_hit4, 8, 16), given by
 * coordinate (lo_x holds the boxes' lower x): the far distance is widened by 1 + 2 gamma(3) to cover
 * rounding. The near and far planes are chosen by the sign of inv_d (`negative`), not by comparing
 * distances, so that the NaN of an axis-parallel ray starting exactly on a slab plane (0 * inf) is
 * skipped: comparisons rather than fmin/fmax, as a NaN compares false (and they compile to plain min/max
 * instructions). That axis then does not limit the interval, and a ray lying in a box face counts as
 * inside. An empty box (lo = +inf, hi = -inf) is always missed. */
/* The factor 1 + 2 gamma(3) by which the slab tests widen a box's far distance. */
static inline float slab_widening(void) { return 1.0f + 2.0f * error_gamma(3); }
#define PC_DEFINE_SLAB(F, I)                                                                                    \
  /* Whether each box is hit within [tmin, tmax], from the near (nx, ny, nz) and far (fx, fy, fz) plane    \
   * distances of each axis; *enter_out: its entry distance (of a missed box: any value). Also the packet  \
   * traversal's, per lane (kernels/packet.cl). */                                                          \
  static inline PC_OVL I slab_hits(F nx, F fx, F ny, F fy, F nz, F fz, F tmin, F tmax, F* enter_out) {      \
    F enter = tmin, exit = tmax;                                                                                     \
    enter = select(enter, nx, nx > enter);                                                                           \
    enter = select(enter, ny, ny > enter);                                                                           \
    enter = select(enter, nz, nz > enter);                                                                           \
    exit = select(exit, fx, fx < exit);                                                                              \
    exit = select(exit, fy, fy < exit);                                                                              \
    exit = select(exit, fz, fz < exit);                                                                              \
    *enter_out = enter;                                                                                              \
    return enter <= exit * slab_widening();                                                                          \
  }
PC_DEFINE_SLAB(float4, int4)
PC_DEFINE_SLAB(float8, int8)
PC_DEFINE_SLAB(float16, int16)
#undef PC_DEFINE_SLAB
#define PC_DEFINE_RAY_BOXES(N)                                                                                  \
  /* Whether each box is hit; *enter: its entry distance (of a missed box: any value). */                   \
  static inline int##N ray_boxes_hit##N(float3 o, float3 inv_d, int3 negative, float tmin, float tmax, float##N lo_x, \
                                        float##N lo_y, float##N lo_z, float##N hi_x, float##N hi_y, float##N hi_z,  \
                                        float##N* enter) {                                                           \
    float##N lx = (lo_x - o.x) * inv_d.x, hx = (hi_x - o.x) * inv_d.x;                                               \
    float##N ly = (lo_y - o.y) * inv_d.y, hy = (hi_y - o.y) * inv_d.y;                                               \
    float##N lz = (lo_z - o.z) * inv_d.z, hz = (hi_z - o.z) * inv_d.z;                                               \
    return slab_hits(negative.x ? hx : lx, negative.x ? lx : hx, negative.y ? hy : ly, negative.y ? ly : hy,         \
                     negative.z ? hz : lz, negative.z ? lz : hz, (float##N)(tmin), (float##N)(tmax), enter);         \
  }
PC_DEFINE_RAY_BOXES(4)
PC_DEFINE_RAY_BOXES(8)
PC_DEFINE_RAY_BOXES(16)
#undef PC_DEFINE_RAY_BOXES

#ifdef PC_BVH_WIDE
/* Where fma() is an instruction: the 8- or 16-wide single-ray node test of a ray with finite FusedSlabs takes each
 * slab plane distance in one fused multiply-add, fma(plane, inv, off), instead of a subtraction and a
 * multiplication; no NaN can arise there, so the interval's ends are maxima and minima taken pairwise (two
 * levels instead of three), and the far planes are widened through inv_far, so no multiplication follows
 * their minimum. A shorter dependency chain a node: bounce rays on the benchmark terrain +4 %, camera rays
 * +3 % (docs/benchmarks-notes.md). Like ray_boxes_hit8 and 16 it enters every box the ray reaches within
 * [tmin, tmax] (the bound is at fused_slabs; tests/intersect_test.cpp); boxes missed by less than the
 * rounding may be entered by one test and not the other, which changes which nodes are visited, and in
 * which order, never the hits. Packets keep slab_hits: there the fused test measured 0.99x. Elsewhere
 * (PC_FUSED_SLABS undefined) no ray's FusedSlabs are usable, and ray_boxes_hit8 or 16 tests every node. */
#if defined(__FMA__) || defined(FP_FAST_FMAF)
#define PC_FUSED_SLABS
#endif
typedef struct {
  float3 inv_near, off_near; /* near planes: t = fma(plane, inv_near, off_near) */
  float3 inv_far, off_far;   /* far planes, widened by 1 + 2 gamma(3) as slab_hits widens its exit */
  /* Where a WideNode's near and far planes of each axis start, in floats from lo_x: lo or hi by the sign
   * of the direction. Loads from these offsets instead of a branch on each sign: bounce rays +2 %, as
   * their first nodes mispredict those branches; camera rays, which predict them, -3 %. */
  int3 near_at, far_at;
  bool usable; /* PC_FUSED_SLABS, and all finite: the ray is not parallel to an axis (and not subnormal) */
} FusedSlabs;

/* The bound: q = fl(o inv) is within u |q| of the exact o inv (u = 2^-24, the unit roundoff), and
 * off = fl(-q -+ 4u |q|) rounds once more, so that off_near <= -o inv_d and off_far >= -o inv_far exactly.
 * Then fl(plane inv_d + off_near) <= fl((plane - o) inv_d) and fl(plane inv_far + off_far) >=
 * fl((plane - o) inv_far): a near plane's distance is at most t (1 + u)^2 for the exact t = (plane - o) / d,
 * a far plane's at least t (1 + 2 gamma(3)) (1 - u)^3, with inv_far = fl(inv_d (1 + 2 gamma(3))), which
 * bound the true interval more tightly than pbrt's t (1 + gamma(3)) and t (1 - gamma(3)) (1 + 2 gamma(3))
 * that slab_hits relies on. (4u |q| is exact, a power of two times q, unless q is subnormal.) */
static inline FusedSlabs fused_slabs(float3 o, float3 inv_d) {
  FusedSlabs f;
  f.inv_near = inv_d;
  f.inv_far = inv_d * slab_widening();
  float3 q_near = o * f.inv_near, q_far = o * f.inv_far;
  f.off_near = -q_near - fabs(q_near) * 0x1p-22f;
  f.off_far = -q_far + fabs(q_far) * 0x1p-22f;
  /* lo_x .. hi_z at 0, W, .. 5 W floats, W the node's width (pinned by static asserts in
   * kernels/shared/types.h) */
  int w = PC_BVH_WIDE;
  int3 negative = inv_d < 0.0f, lo_at = (int3)(0, w, 2 * w), hi_at = (int3)(3 * w, 4 * w, 5 * w);
  f.near_at = select(lo_at, hi_at, negative);
  f.far_at = select(hi_at, lo_at, negative);
#ifdef PC_FUSED_SLABS
  f.usable = all(isfinite(f.inv_far)) && all(isfinite(f.off_near)) && all(isfinite(f.off_far));
#else
  f.usable = false;
#endif
  return f;
}

/* ray_boxes_hit8 or 16 by FusedSlabs (f->usable), the boxes of node n; tmax_far: tmax * (1 + 2 gamma(3)). */
static inline WideI ray_boxes_hit_wide_fused(const FusedSlabs* f, float tmin, float tmax_far, __global const WideNode* n,
                                             WideF* enter_out) {
  __global const float* planes = n->lo_x;
  WideF nx = fma(wide_load(planes + f->near_at.x), (WideF)(f->inv_near.x), (WideF)(f->off_near.x));
  WideF ny = fma(wide_load(planes + f->near_at.y), (WideF)(f->inv_near.y), (WideF)(f->off_near.y));
  WideF nz = fma(wide_load(planes + f->near_at.z), (WideF)(f->inv_near.z), (WideF)(f->off_near.z));
  WideF fx = fma(wide_load(planes + f->far_at.x), (WideF)(f->inv_far.x), (WideF)(f->off_far.x));
  WideF fy = fma(wide_load(planes + f->far_at.y), (WideF)(f->inv_far.y), (WideF)(f->off_far.y));
  WideF fz = fma(wide_load(planes + f->far_at.z), (WideF)(f->inv_far.z), (WideF)(f->off_far.z));
  WideF t0 = (WideF)(tmin), t1 = (WideF)(tmax_far);
  WideF nxy = select(ny, nx, nx > ny), nzt = select(t0, nz, nz > t0);
  WideF fxy = select(fy, fx, fx < fy), fzt = select(t1, fz, fz < t1);
  WideF enter = select(nzt, nxy, nxy > nzt), exit = select(fzt, fxy, fxy < fzt);
  *enter_out = enter;
  return enter <= exit;
}
#endif /* PC_BVH_WIDE */

/* Each of four boxes' entry distance, or INFINITY when it is missed within [tmin, tmax]. */
static inline float4 ray_boxes4(float3 o, float3 inv_d, int3 negative, float tmin, float tmax, float4 lo_x, float4 lo_y,
                                float4 lo_z, float4 hi_x, float4 hi_y, float4 hi_z) {
  float4 enter;
  int4 hit = ray_boxes_hit4(o, inv_d, negative, tmin, tmax, lo_x, lo_y, lo_z, hi_x, hi_y, hi_z, &enter);
  return select((float4)(INFINITY), enter, hit);
}

/* Watertight ray/triangle test. Edge functions of a shared edge are computed from the same sheared
 * vertex coordinates in both triangles, so a ray through the edge hits at least one of them. */
static __attribute__((always_inline)) inline bool ray_triangle(float3 o, const RayPrecomp* rp, uint kz, float tmin, float tmax, float3 a, float3 b,
                         float3 c, float* t_out, float* u_out, float* v_out) {
  uint kx = kz == 2u ? 0u : kz + 1u, ky = kx == 2u ? 0u : kx + 1u;
  float3 A = a - o, B = b - o, C = c - o;
  float Akz = axis_component(A, kz), Bkz = axis_component(B, kz), Ckz = axis_component(C, kz);
  float Ax = axis_component(A, kx) + rp->sx * Akz, Ay = axis_component(A, ky) + rp->sy * Akz;
  float Bx = axis_component(B, kx) + rp->sx * Bkz, By = axis_component(B, ky) + rp->sy * Bkz;
  float Cx = axis_component(C, kx) + rp->sx * Ckz, Cy = axis_component(C, ky) + rp->sy * Ckz;
  float U = Cx * By - Cy * Bx;
  float V = Ax * Cy - Ay * Cx;
  float W = Bx * Ay - By * Ax;
  if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return false;
  float det = U + V + W;
  if (det == 0.0f) return false;
  float Az = rp->sz * Akz, Bz = rp->sz * Bkz, Cz = rp->sz * Ckz;
  float T = U * Az + V * Bz + W * Cz;
  if (det < 0.0f ? T >= tmin * det : T <= tmin * det) return false;
  float inv_det = 1.0f / det;
  float t = T * inv_det;
  /* tmax (the nearest hit so far) is compared with t itself, not as T against tmax * det: that product
   * rounds, so the same triangle could pass against one tmax and fail against an equal t found first in
   * another traversal order. The order of the hits must not depend on the layout (intersect_prim). */
  if (!(t <= tmax)) return false;
  /* No pbrt-style "t certainly > 0" bound here: for a triangle seen nearly edge-on its error bound grows
   * like 1 / det and rejected genuine hits at shared vertices, making the mesh leak (tests/
   * robustness_test.cpp). Spawned rays cannot re-hit their surface anyway: their origins are offset
   * by the hit point's error bound and they skip the primitive they leave. */
  *t_out = t;
  *u_out = V * inv_det;
  *v_out = W * inv_det;
  return true;
}

/* Ray/sphere with pbrt-v4's accurate discriminant. A ray leaving the sphere itself (from_surface) can
 * only meet it again at the far root, and only when it points inwards. */
static inline bool ray_sphere(float3 o, float3 d, float tmin, float tmax, float3 center, float radius,
                              bool from_surface, float* t_out) {
  float3 oc = o - center;
  float a = pc_dot(d, d);
  float b = 2.0f * pc_dot(d, oc);
  float c = pc_dot(oc, oc) - radius * radius;
  float3 v = oc - (b / (2.0f * a)) * d;
  float len = pc_length(v);
  float discrim = 4.0f * a * (radius + len) * (radius - len);
  if (discrim < 0.0f) return false;
  float root = sqrt(discrim);
  float q = b < 0.0f ? -0.5f * (b - root) : -0.5f * (b + root);
  float t0 = q / a, t1 = q != 0.0f ? c / q : t0;
  if (t0 > t1) {
    float t = t0;
    t0 = t1;
    t1 = t;
  }
  if (from_surface) {
    if (pc_dot(d, oc) >= 0.0f) return false;
    t0 = t1;
  }
  float t = t0 > tmin ? t0 : t1;
  if (!(t > tmin && t <= tmax)) return false;
  *t_out = t;
  return true;
}

static inline uint prim_index_of(Primitive p) { return as_uint(p.a.w); }
static inline uint prim_kind_of(Primitive p) { return as_uint(p.b.w); }

/* Intersects one primitive; updates *hit when closer. Hits at equal t (a shared edge, coplanar faces)
 * go to the lower primitive index, so the nearest hit is one total order's minimum and the same whatever
 * the order the traversal meets the primitives in: the 4-, 8- and 16-wide layouts (and with them a CPU and
 * a GPU in one render) give the same hit records. */
static __attribute__((always_inline)) inline bool intersect_prim(const SceneData* cut, __global const Primitive* prims, uint slot,
                                                          const Ray* ray, const RayPrecomp* rp, uint kz, float tmax, Hit* hit) {
  Primitive p = prims[slot];
  bool from_surface = prim_index_of(p) == ray->skip_prim;
  float t, u = 0.0f, v = 0.0f;
#ifdef PC_HAS_SPHERES
  if (prim_kind_of(p) == PC_PRIM_SPHERE) {
    if (!ray_sphere(ray->o, ray->d, ray->tmin, tmax, p.a.xyz, p.b.x, from_surface, &t)) return false;
  } else
#endif
  {
    if (from_surface) return false; /* a flat triangle cannot occlude a ray that leaves it */
    if (!ray_triangle(ray->o, rp, kz, ray->tmin, tmax, p.a.xyz, p.b.xyz, p.c.xyz, &t, &u, &v)) return false;
  }
  uint prim = prim_index_of(p);
  if (t == tmax && prim >= hit->prim) return false;
#ifdef PC_HAS_CUTOUTS
  if (!cutout_stops(cut, prim, u, v, ray->cutout_seed)) return false;
#endif
  hit->t = t;
  hit->slot = slot;
  hit->prim = prim;
  hit->u = u;
  hit->v = v;
  return true;
}

/* The leaf reference's primitives; with any_hit, true at the first hit. */
static __attribute__((always_inline)) inline bool intersect_leaf(const SceneData* cut, __global const Primitive* prims, uint ref, const Ray* ray,
                                                          const RayPrecomp* rp, bool any_hit, Hit* hit, uint kz) {
  uint first = PC_LEAF_FIRST(ref), count = PC_LEAF_COUNT(ref);
  for (uint i = 0; i < count; ++i) {
    if (intersect_prim(cut, prims, first + i, ray, rp, kz, hit->t, hit) && any_hit) return true;
  }
  return false;
}

/* Entry distances of a wide node's four children (INFINITY for a miss or an unused slot). */
static inline float4 node_entries(__global const Bvh4Node* n, float3 o, float3 inv_d, int3 negative, float tmin, float tmax) {
  return ray_boxes4(o, inv_d, negative, tmin, tmax, n->lo_x, n->lo_y, n->lo_z, n->hi_x, n->hi_y, n->hi_z);
}

/* No hit yet: the nearest so far is the ray's far end. */
static inline void hit_init(Hit* hit, const Ray* ray) {
  hit->t = ray->tmax;
  hit->slot = PC_INVALID;
  hit->prim = PC_INVALID;
  hit->instance = PC_INVALID;
}

/* Pops the next subtree of a traversal stack that can still hold a hit nearer than the nearest hit so far
 * into *ref; false when none is left. t_far: that hit's t widened by slab_widening(), as the node tests
 * widen it. Against t itself a box whose entry distance rounds a few ulps beyond the t of a triangle on
 * its face was dropped once that t was found in another box: two triangles of a shared edge, hit at the
 * same t in two leaves whose entries both round above it (the floor and a wall of the Cornell box), then
 * gave the triangle of whichever leaf came first, not the lower primitive index, so the hit depended on
 * the traversal order (a packet's is not its single ray's: kernels/packet.cl). Every subtree the node
 * test would enter at the current t is entered, and the hit is the minimum of the one total order
 * (intersect_prim) whenever each triangle's t is within that widening of its boxes' entries. */
static __attribute__((always_inline)) inline bool pop_subtree(const uint* stack, const float* stack_entry, int* sp, float t_far,
                                                       uint* ref) {
  while (*sp > 0) {
    --*sp;
    if (stack_entry[*sp] <= t_far) {
      *ref = stack[*sp];
      return true;
    }
  }
  return false;
}

/* Orders two (distance, reference) pairs, nearer first, without branches. */
static inline void order_pair(float* da, uint* ra, float* db, uint* rb) {
  bool swap = *db < *da;
  float d = *da;
  uint r = *ra;
  *da = swap ? *db : d;
  *ra = swap ? *rb : r;
  *db = swap ? d : *db;
  *rb = swap ? r : *rb;
}

/* Traversal of the 4-wide BVH from node root, nearest child first, updating *hit (hit_init, or the
 * nearest hit of other instances). With any_hit it returns at the first hit (shadow rays); otherwise
 * whether *hit holds one. kz is passed as a literal by trace_tree, so each copy's triangle test has
 * constant axis indices. The stack holds at most 3 entries per level of the tree, whose depth is at
 * most kBvhMaxDepth. */
static __attribute__((always_inline)) inline bool trace_bvh4_axis(const SceneData* cut, __global const Bvh4Node* nodes,
                                                          __global const Primitive* prims, uint root, const Ray* ray,
                                                          const RayPrecomp* rp, bool any_hit, Hit* hit, uint kz) {
  uint stack[3 * PC_BVH_STACK];
  float stack_entry[3 * PC_BVH_STACK];
  int sp = 0;
  int3 negative = rp->inv_d < 0.0f;
  uint ref = root;
  for (;;) {
    if (ref & PC_BVH4_LEAF) {
      if (intersect_leaf(cut, prims, ref, ray, rp, any_hit, hit, kz)) return true;
    } else {
      __global const Bvh4Node* n = nodes + ref;
      float4 entry = node_entries(n, ray->o, rp->inv_d, negative, ray->tmin, hit->t);
      /* Sort the four children by entry distance (a five-comparison network; misses are INFINITY and
       * end up last), then push the hit ones far to near and go on with the nearest. */
      float d0 = entry.s0, d1 = entry.s1, d2 = entry.s2, d3 = entry.s3;
      uint r0 = n->child[0], r1 = n->child[1], r2 = n->child[2], r3 = n->child[3];
      order_pair(&d0, &r0, &d1, &r1);
      order_pair(&d2, &r2, &d3, &r3);
      order_pair(&d0, &r0, &d2, &r2);
      order_pair(&d1, &r1, &d3, &r3);
      order_pair(&d1, &r1, &d2, &r2);
      stack[sp] = r3;
      stack_entry[sp] = d3;
      sp += d3 != INFINITY ? 1 : 0;
      stack[sp] = r2;
      stack_entry[sp] = d2;
      sp += d2 != INFINITY ? 1 : 0;
      stack[sp] = r1;
      stack_entry[sp] = d1;
      sp += d1 != INFINITY ? 1 : 0;
      if (d0 != INFINITY) {
        ref = r0;
        continue;
      }
    }
    if (!pop_subtree(stack, stack_entry, &sp, hit->t * slab_widening(), &ref)) return hit->slot != PC_INVALID;
  }
}

/* A LeafBlock's spheres (bit i: primitive i is one): none in a program for a scene without spheres, so
 * that its triangle loops test no bits. */
#ifdef PC_HAS_SPHERES
#define pc_block_spheres(b) ((b)->sphere_mask)
#else
#define pc_block_spheres(b) 0u
#endif

/* A LeafBlock's vertex coordinate by vertex (0 a, 1 b, 2 c) and axis, for literal indices. */
static inline float4 block_coord(__global const LeafBlock* b, uint vertex, uint axis) {
  if (vertex == 0u) return axis == 0u ? b->ax : axis == 1u ? b->ay : b->az;
  if (vertex == 1u) return axis == 0u ? b->bx : axis == 1u ? b->by : b->bz;
  return axis == 0u ? b->cx : axis == 1u ? b->cy : b->cz;
}

/* The watertight test of ray_triangle on a block's four triangles at once: per lane the same IEEE
 * operations in the same order, so the same t, u, v bits. Then the hits update *hit lane by lane by
 * intersect_prim's rule (nearest by t, then lower primitive index), spheres through intersect_prim. */
static __attribute__((always_inline)) inline bool intersect_block(const SceneData* cut, __global const LeafBlock* b, __global const Primitive* prims,
                                                           const Ray* ray, const RayPrecomp* rp, bool any_hit, Hit* hit,
                                                           uint kz) {
  uint kx = kz == 2u ? 0u : kz + 1u, ky = kx == 2u ? 0u : kx + 1u;
  float ox = axis_component(ray->o, kx), oy = axis_component(ray->o, ky), oz = axis_component(ray->o, kz);
  float4 Akz = block_coord(b, 0u, kz) - oz, Bkz = block_coord(b, 1u, kz) - oz, Ckz = block_coord(b, 2u, kz) - oz;
  float4 Ax = (block_coord(b, 0u, kx) - ox) + rp->sx * Akz, Ay = (block_coord(b, 0u, ky) - oy) + rp->sy * Akz;
  float4 Bx = (block_coord(b, 1u, kx) - ox) + rp->sx * Bkz, By = (block_coord(b, 1u, ky) - oy) + rp->sy * Bkz;
  float4 Cx = (block_coord(b, 2u, kx) - ox) + rp->sx * Ckz, Cy = (block_coord(b, 2u, ky) - oy) + rp->sy * Ckz;
  float4 U = Cx * By - Cy * Bx;
  float4 V = Ax * Cy - Ay * Cx;
  float4 W = Bx * Ay - By * Ax;
  int4 outside = ((U < 0.0f) | (V < 0.0f) | (W < 0.0f)) & ((U > 0.0f) | (V > 0.0f) | (W > 0.0f));
  float4 det = U + V + W;
  uint4 prim = vload4(0, b->prim);
  int4 crossed = ~outside & (det != 0.0f) & ((int4)(0, 1, 2, 3) < (int4)((int)b->count)) &
                 (prim != (uint4)(ray->skip_prim));
  bool any_sphere = pc_block_spheres(b) != 0u;
  /* Most blocks: the ray crosses none of the triangles, and needs no distance (nor its division). */
  if (!pc_any_(crossed) && !any_sphere) return false;
  float4 Az = rp->sz * Akz, Bz = rp->sz * Bkz, Cz = rp->sz * Ckz;
  float4 T = U * Az + V * Bz + W * Cz;
  int4 before_tmin = select(T <= ray->tmin * det, T >= ray->tmin * det, det < 0.0f);
  float4 inv_det = 1.0f / det;
  float4 t = T * inv_det;
  int4 candidate = crossed & ~before_tmin & (t <= (float4)(hit->t));
  if (!pc_any_(candidate) && !any_sphere) return false;
  float ts[4], us[4], vs[4];
  int ok[4];
  uint ps[4];
  vstore4(t, 0, ts);
  vstore4(V * inv_det, 0, us);
  vstore4(W * inv_det, 0, vs);
  vstore4(candidate, 0, ok);
  vstore4(prim, 0, ps);
  bool found = false;
  for (uint i = 0; i < b->count; ++i) {
    if (pc_block_spheres(b) & (1u << i)) {
      found |= intersect_prim(cut, prims, b->first_slot + i, ray, rp, kz, hit->t, hit);
      continue;
    }
    if (!ok[i] || ts[i] > hit->t || (ts[i] == hit->t && ps[i] >= hit->prim)) continue;
#ifdef PC_HAS_CUTOUTS
    if (!cutout_stops(cut, ps[i], us[i], vs[i], ray->cutout_seed)) continue;
#endif
    hit->t = ts[i];
    hit->slot = b->first_slot + i;
    hit->prim = ps[i];
    hit->u = us[i];
    hit->v = vs[i];
    found = true;
  }
  return found && any_hit;
}

#ifdef PC_BVH_WIDE
/* The 8- or 16-wide BVH's node at interior reference ref, and the first block of leaf reference ref: both
 * in bvh8 or bvh16, references in 8-byte words (kernels/shared/types.h), so the address is one scaled
 * addition. */
static inline __global const WideNode* wide_node(__global const WideNode* wide, uint ref) {
  return (__global const WideNode*)((__global const ulong*)wide + ref);
}
static inline __global const LeafBlock* wide_leaf(__global const LeafBlock* wide, uint ref) {
  return (__global const LeafBlock*)((__global const ulong*)wide + (ref & ~PC_BVH4_LEAF));
}

/* The leaf reference's blocks (kernels/shared/types.h); with any_hit, true at the first hit. */
static __attribute__((always_inline)) inline bool intersect_blocks(const SceneData* cut, __global const LeafBlock* blocks,
                                                            __global const Primitive* prims, uint ref, const Ray* ray,
                                                            const RayPrecomp* rp, bool any_hit, Hit* hit, uint kz) {
  for (__global const LeafBlock* b = wide_leaf(blocks, ref);; ++b) {
    if (intersect_block(cut, b, prims, ray, rp, any_hit, hit, kz)) return true;
    if (b->last) return false;
  }
}

/* Asks the cache for the node (all its lines) or the leaf blocks (four lines) of reference ref, which
 * traversal has pushed and will pop after the subtree it goes on with: on PoCL's x86 targets (clang's
 * prefetch instruction; OpenCL's prefetch() is empty there), nothing elsewhere. Bounce rays on the
 * benchmark terrain +8 %, camera rays +8 % (docs/benchmarks-notes.md). */
static inline void prefetch_subtree(__global const WideNode* nodes, __global const LeafBlock* blocks, uint ref) {
#if defined(__clang__) && defined(__x86_64__)
  __global const char* p = (ref & PC_BVH4_LEAF) ? (__global const char*)wide_leaf(blocks, ref)
                                                : (__global const char*)wide_node(nodes, ref);
  __builtin_prefetch(p);
  __builtin_prefetch(p + 64);
  __builtin_prefetch(p + 128);
  __builtin_prefetch(p + 192);
#if PC_BVH_WIDE == 16
  if (!(ref & PC_BVH4_LEAF)) {
    __builtin_prefetch(p + 256);
    __builtin_prefetch(p + 320);
    __builtin_prefetch(p + 384);
  }
#endif
#endif
}

/* Traversal of the 8- or 16-wide BVH (CPU devices) from node root, as trace_bvh4_axis: one float8 or
 * float16 slab test per node. As in Embree, one hit child is entered at once, of two the nearer is entered
 * and the other pushed, more are insertion-sorted onto the stack by entry distance, nearest on top, and
 * the nearest is popped. The stack holds at most PC_BVH_WIDE - 1 entries per level. */
static __attribute__((always_inline)) inline bool trace_wide_axis(const SceneData* cut, __global const WideNode* nodes,
                                                           __global const LeafBlock* blocks,
                                                           __global const Primitive* prims, uint root, const Ray* ray,
                                                           const RayPrecomp* rp, bool any_hit, Hit* hit, uint kz) {
  uint stack[(PC_BVH_WIDE - 1) * PC_BVH_STACK];
  float stack_entry[(PC_BVH_WIDE - 1) * PC_BVH_STACK];
  int sp = 0;
  int3 negative = rp->inv_d < 0.0f;
  uint ref = root;
  float nearest = hit->t; /* hit->t, kept in a register */
  FusedSlabs fused = fused_slabs(ray->o, rp->inv_d);
  float nearest_far = nearest * slab_widening();
  for (;;) {
    if (ref & PC_BVH4_LEAF) {
      if (intersect_blocks(cut, blocks, prims, ref, ray, rp, any_hit, hit, kz)) return true;
      nearest = hit->t;
      nearest_far = nearest * slab_widening();
    } else {
      __global const WideNode* n = wide_node(nodes, ref);
      WideF entry;
      /* Bit i of mask: child i is hit. */
      uint mask = pc_lane_bits(fused.usable ? ray_boxes_hit_wide_fused(&fused, ray->tmin, nearest_far, n, &entry)
                                            : PC_CAT(ray_boxes_hit, PC_BVH_WIDE)(
                                                  ray->o, rp->inv_d, negative, ray->tmin, nearest, wide_load(n->lo_x),
                                                  wide_load(n->lo_y), wide_load(n->lo_z), wide_load(n->hi_x),
                                                  wide_load(n->hi_y), wide_load(n->hi_z), &entry));
      if (mask != 0u) {
        uint i = pc_lowest_bit(mask);
        mask &= mask - 1u;
        uint near_ref = n->child[i];
        float near_d = pc_lane(entry, i);
        if (mask == 0u) {
          ref = near_ref;
          continue;
        }
        i = pc_lowest_bit(mask);
        mask &= mask - 1u;
        uint far_ref = n->child[i];
        float far_d = pc_lane(entry, i);
        order_pair(&near_d, &near_ref, &far_d, &far_ref);
        if (mask == 0u) {
          prefetch_subtree(nodes, blocks, far_ref);
          stack[sp] = far_ref;
          stack_entry[sp] = far_d;
          ++sp;
          ref = near_ref;
          continue;
        }
        /* Three or more: all onto the stack, kept sorted far to near from where this node's entries start. */
        int base = sp;
        prefetch_subtree(nodes, blocks, far_ref);
        stack[sp] = far_ref;
        stack_entry[sp] = far_d;
        stack[sp + 1] = near_ref;
        stack_entry[sp + 1] = near_d;
        sp += 2;
        while (mask != 0u) {
          i = pc_lowest_bit(mask);
          mask &= mask - 1u;
          float di = pc_lane(entry, i);
          uint ri = n->child[i];
          prefetch_subtree(nodes, blocks, ri);
          int j = sp;
          while (j > base && stack_entry[j - 1] < di) {
            stack[j] = stack[j - 1];
            stack_entry[j] = stack_entry[j - 1];
            --j;
          }
          stack[j] = ri;
          stack_entry[j] = di;
          ++sp;
        }
        ref = stack[--sp];
        continue;
      }
    }
    if (!pop_subtree(stack, stack_entry, &sp, nearest_far, &ref)) return hit->slot != PC_INVALID;
  }
}
#endif /* PC_BVH_WIDE */

/* The tree of the device's layout from node root, updating *hit as trace_bvh4_axis does, with the ray's
 * ray_precompute rp; kz as a literal, so each copy's triangle test has constant axis indices. cut: the
 * scene whose cut-outs apply (kernels/cutout.cl), or 0 for none. */
PC_OUT_OF_LINE bool trace_tree_precomputed(const SceneData* cut, __global const WideNode* nodes, __global const LeafBlock* blocks,
                                           __global const Primitive* prims, uint root, const Ray* ray, const RayPrecomp* rp,
                                           bool any_hit, Hit* hit) {
#ifdef PC_BVH_WIDE
#define PC_TRACE_AXIS(kz) trace_wide_axis(cut, nodes, blocks, prims, root, ray, rp, any_hit, hit, kz)
#else
#define PC_TRACE_AXIS(kz) trace_bvh4_axis(cut, nodes, prims, root, ray, rp, any_hit, hit, kz)
#endif
  if (rp->kz == 0u) return PC_TRACE_AXIS(0u);
  if (rp->kz == 1u) return PC_TRACE_AXIS(1u);
  return PC_TRACE_AXIS(2u);
#undef PC_TRACE_AXIS
}

static inline bool trace_tree(const SceneData* cut, __global const WideNode* nodes, __global const LeafBlock* blocks,
                              __global const Primitive* prims, uint root, const Ray* ray, bool any_hit, Hit* hit) {
  RayPrecomp rp = ray_precompute(ray->d);
  return trace_tree_precomputed(cut, nodes, blocks, prims, root, ray, &rp, any_hit, hit);
}

/* The nearest hit (or with any_hit, any hit) in one tree whose root is node 0: the whole scene without
 * instances, and the geometry that ray files and the test kernels trace. */
static inline bool trace_bvh(const SceneData* cut, __global const WideNode* nodes, __global const LeafBlock* blocks, __global const Primitive* prims,
                             const Ray* ray, bool any_hit, Hit* hit) {
  hit_init(hit, ray);
  return trace_tree(cut, nodes, blocks, prims, 0u, ray, any_hit, hit);
}

#ifdef PC_HAS_INSTANCES
/* An affine transform given as three rows (x, y, z, translation) applied to a point or a direction, each
 * coordinate summed in this order (no contraction: the same bits everywhere). */
static inline float3 transform_point(__global const float4* rows, float3 p) {
  float4 r0 = rows[0], r1 = rows[1], r2 = rows[2];
  return (float3)(((r0.x * p.x + r0.y * p.y) + r0.z * p.z) + r0.w, ((r1.x * p.x + r1.y * p.y) + r1.z * p.z) + r1.w,
                  ((r2.x * p.x + r2.y * p.y) + r2.z * p.z) + r2.w);
}
static inline float3 transform_vector(__global const float4* rows, float3 v) {
  float4 r0 = rows[0], r1 = rows[1], r2 = rows[2];
  return (float3)((r0.x * v.x + r0.y * v.y) + r0.z * v.z, (r1.x * v.x + r1.y * v.y) + r1.z * v.z,
                  (r2.x * v.x + r2.y * v.y) + r2.z * v.z);
}

/* Instance k's tree with the ray taken into the mesh's coordinates (the direction is not normalized, so
 * t is the same parameter as in the device's). A hit of it replaces *hit when nearer, or at an equal t
 * when k is the lower instance: hits are ordered by (t, instance, primitive), whatever order the instance
 * BVH visits the instances in. */
static inline bool trace_instance(const SceneData* sc, const SceneData* cut, uint k, const Ray* ray, bool any_hit, Hit* hit) {
  __global const Instance* inst = sc->instances + k;
  Ray mesh_ray = *ray;
  if (!(inst->flags & PC_INSTANCE_IDENTITY)) {
    mesh_ray.o = transform_point(inst->to_mesh, ray->o);
    mesh_ray.d = transform_vector(inst->to_mesh, ray->d);
  }
  mesh_ray.skip_prim = ray->skip_instance == k ? ray->skip_prim : PC_INVALID;
#ifdef PC_HAS_CUTOUTS
  /* The copies of a cut-out surface along one ray decide independently; the rest of the scene keeps the
   * ray's own seed, as without instances. */
  if (!(inst->flags & PC_INSTANCE_IDENTITY)) mesh_ray.cutout_seed = hash4(ray->cutout_seed, k, 0x510e527fu, 0x9b05688cu);
#endif
  Hit h;
  h.t = hit->t;
  h.slot = PC_INVALID;
  /* Equal-t hits of this instance win against a higher instance's (prim PC_INVALID: any primitive
   * index is lower) and lose against a lower one's (prim 0: none is lower). */
  h.prim = hit->instance == k ? hit->prim : hit->instance < k ? 0u : PC_INVALID;
#if PC_BVH_WIDE == 16
  uint root = inst->root16;
#elif PC_BVH_WIDE == 8
  uint root = inst->root8;
#else
  uint root = inst->root4;
#endif
  if (!trace_tree(cut, PC_SCENE_BVH(sc), sc->prims, root, &mesh_ray, any_hit, &h)) return false;
  h.instance = k;
  *hit = h;
  return true;
}

/* The instance BVH (binary, its leaves ranges of instances), nearer child first; each instance met is
 * traced by trace_instance. */
static inline bool trace_instances(const SceneData* sc, const SceneData* cut, const Ray* ray, bool any_hit, Hit* hit) {
  hit_init(hit, ray);
  uint stack[PC_BVH_STACK];
  float stack_entry[PC_BVH_STACK];
  int sp = 0;
  float3 inv_d = 1.0f / ray->d;
  int3 negative = inv_d < 0.0f;
  uint node = 0;
  for (;;) {
    __global const BvhNode* n = sc->instance_bvh + node;
    if (n->prim_count > 0u) {
      for (uint k = n->left_first; k < n->left_first + n->prim_count; ++k)
        if (trace_instance(sc, cut, k, ray, any_hit, hit) && any_hit) return true;
    } else if (n->left_first != 0u) {
      /* Both children's boxes in one slab test (the other two lanes empty). */
      __global const BvhNode* a = n + 1;
      __global const BvhNode* b = sc->instance_bvh + n->left_first;
      float4 entry = ray_boxes4(ray->o, inv_d, negative, ray->tmin, hit->t, (float4)(a->lo[0], b->lo[0], INFINITY, INFINITY),
                                (float4)(a->lo[1], b->lo[1], INFINITY, INFINITY), (float4)(a->lo[2], b->lo[2], INFINITY, INFINITY),
                                (float4)(a->hi[0], b->hi[0], -INFINITY, -INFINITY), (float4)(a->hi[1], b->hi[1], -INFINITY, -INFINITY),
                                (float4)(a->hi[2], b->hi[2], -INFINITY, -INFINITY));
      float da = entry.s0, db = entry.s1;
      uint ra = node + 1u, rb = n->left_first;
      order_pair(&da, &ra, &db, &rb);
      if (db != INFINITY) {
        stack[sp] = rb;
        stack_entry[sp] = db;
        ++sp;
      }
      if (da != INFINITY) {
        node = ra;
        continue;
      }
    }
    if (!pop_subtree(stack, stack_entry, &sp, hit->t * slab_widening(), &node)) return hit->slot != PC_INVALID;
  }
}
#endif

/* The scene's nearest hit (any hit with any_hit): its one tree, or with instances the instance BVH over
 * the instances' trees. cut: as for trace_tree. */
static inline bool trace_scene(const SceneData* sc, const SceneData* cut, const Ray* ray, bool any_hit, Hit* hit) {
#ifdef PC_HAS_INSTANCES
  return trace_instances(sc, cut, ray, any_hit, hit);
#else
  return trace_bvh(cut, PC_SCENE_BVH(sc), sc->prims, ray, any_hit, hit);
#endif
}

#endif
