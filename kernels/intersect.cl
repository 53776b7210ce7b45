/* Ray/box, ray/triangle and ray/sphere tests and BVH traversal (closest hit and any hit).
 * FP_CONTRACT is off: a fused multiply-add would round the two triangles of a shared edge differently
 * and let rays slip through the edge. */
#ifndef PATHCL_INTERSECT_CL
#define PATHCL_INTERSECT_CL
#pragma OPENCL FP_CONTRACT OFF

#define PC_BVH_STACK 64 /* = kBvhMaxDepth of scene/bvh_build.h */

typedef struct {
  float3 o, d;
  float tmin, tmax;
  uint skip_prim; /* scene-order primitive the ray leaves from, or PC_INVALID */
} Ray;

typedef struct {
  float t;
  uint slot; /* index into the leaf-ordered primitive array, PC_INVALID for a miss */
  float u, v; /* barycentrics of vertices b and c */
} Hit;

/* A ray of a ray file (pathcl rays). */
inline Ray ray_from_record(__global const RayRecord* record) {
  __global const float* r = (__global const float*)record;
  Ray ray;
  ray.o = vload3(0, r);
  ray.tmin = r[3];
  ray.d = vload3(0, r + 4);
  ray.tmax = r[7];
  ray.skip_prim = PC_INVALID;
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

inline float axis_component(float3 v, uint k) { return k == 0u ? v.x : k == 1u ? v.y : v.z; }

inline RayPrecomp ray_precompute(float3 d) {
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

/* Robust slab test (pbrt-v4): the far distance is widened by 1 + 2 gamma(3) to cover rounding.
 * The near and far planes are chosen by the sign of inv_d, not by comparing distances, so that the NaN
 * of an axis-parallel ray starting exactly on a slab plane (0 * inf) is ignored by fmax/fmin: that axis
 * then does not limit the interval, and a ray lying in a box face counts as inside.
 * Returns the entry distance, or INFINITY when the box is missed within [tmin, tmax]. */
inline float ray_box(float3 o, float3 inv_d, float tmin, float tmax, float3 lo, float3 hi) {
  float3 t_lo = (lo - o) * inv_d, t_hi = (hi - o) * inv_d;
  int3 negative = inv_d < 0.0f;
  float3 tn = select(t_lo, t_hi, negative), tf = select(t_hi, t_lo, negative);
  /* Comparisons rather than fmin/fmax: a NaN compares false and is skipped, and they compile to plain
   * min/max instructions. */
  float enter = tn.x > tmin ? tn.x : tmin;
  enter = tn.y > enter ? tn.y : enter;
  enter = tn.z > enter ? tn.z : enter;
  float exit = tf.x < tmax ? tf.x : tmax;
  exit = tf.y < exit ? tf.y : exit;
  exit = tf.z < exit ? tf.z : exit;
  return enter <= exit * (1.0f + 2.0f * error_gamma(3)) ? enter : INFINITY;
}

/* Watertight ray/triangle test. Edge functions of a shared edge are computed from the same sheared
 * vertex coordinates in both triangles, so a ray through the edge hits at least one of them. */
__attribute__((always_inline)) inline bool ray_triangle(float3 o, const RayPrecomp* rp, uint kz, float tmin, float tmax, float3 a, float3 b,
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
  if (det < 0.0f ? (T >= tmin * det || T < tmax * det) : (T <= tmin * det || T > tmax * det)) return false;
  float inv_det = 1.0f / det;
  float t = T * inv_det;
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
inline bool ray_sphere(float3 o, float3 d, float tmin, float tmax, float3 center, float radius,
                       bool from_surface, float* t_out) {
  float3 oc = o - center;
  float a = dot(d, d);
  float b = 2.0f * dot(d, oc);
  float c = dot(oc, oc) - radius * radius;
  float3 v = oc - (b / (2.0f * a)) * d;
  float len = length(v);
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
    if (dot(d, oc) >= 0.0f) return false;
    t0 = t1;
  }
  float t = t0 > tmin ? t0 : t1;
  if (!(t > tmin && t < tmax)) return false;
  *t_out = t;
  return true;
}

inline uint prim_index_of(Primitive p) { return as_uint(p.a.w); }
inline uint prim_kind_of(Primitive p) { return as_uint(p.b.w); }

/* Intersects one primitive; updates *hit when closer. */
__attribute__((always_inline)) inline bool intersect_prim(__global const Primitive* prims, uint slot, const Ray* ray, const RayPrecomp* rp,
                           uint kz, float tmax, Hit* hit) {
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
  hit->t = t;
  hit->slot = slot;
  hit->u = u;
  hit->v = v;
  return true;
}

inline float node_entry(__global const BvhNode* nodes, uint i, float3 o, float3 inv_d, float tmin, float tmax) {
  __global const float* f = (__global const float*)(nodes + i);
  return ray_box(o, inv_d, tmin, tmax, vload3(0, f), vload3(0, f + 4));
}

/* BVH traversal, nearer child first. With any_hit it returns at the first hit (shadow rays).
 * kz is passed as a literal by trace_bvh, so each copy's triangle test has constant axis indices. */
__attribute__((always_inline)) inline bool trace_bvh_axis(__global const BvhNode* nodes,
                                                          __global const Primitive* prims, const Ray* ray,
                                                          const RayPrecomp* rp, bool any_hit, Hit* hit, uint kz) {
  hit->t = ray->tmax;
  hit->slot = PC_INVALID;
  uint stack[PC_BVH_STACK];
  float stack_entry[PC_BVH_STACK];
  int sp = 0;
  uint node = 0;
  if (nodes[0].prim_count == 0 && nodes[0].left_first == 0) return false; /* the empty scene's root */
  if (node_entry(nodes, 0, ray->o, rp->inv_d, ray->tmin, ray->tmax) == INFINITY) return false;
  for (;;) {
    __global const BvhNode* n = nodes + node;
    uint count = n->prim_count;
    if (count > 0) {
      uint first = n->left_first;
      for (uint i = 0; i < count; ++i) {
        if (intersect_prim(prims, first + i, ray, rp, kz, hit->t, hit) && any_hit) return true;
      }
    } else {
      uint left = node + 1, right = n->left_first;
      float dl = node_entry(nodes, left, ray->o, rp->inv_d, ray->tmin, hit->t);
      float dr = node_entry(nodes, right, ray->o, rp->inv_d, ray->tmin, hit->t);
      /* Branch-free ordering and push: traversal branches are unpredictable, so only "was any child hit"
       * is a branch. The far child is always written and the stack grows only if it was hit too. */
      bool right_first = dr < dl;
      uint near = right_first ? right : left, far = right_first ? left : right;
      float d_near = right_first ? dr : dl, d_far = right_first ? dl : dr;
      stack[sp] = far;
      stack_entry[sp] = d_far;
      sp += d_far != INFINITY ? 1 : 0;
      if (d_near != INFINITY) {
        node = near;
        continue;
      }
    }
    /* Pop the next subtree that can still hold a closer hit. */
    for (;;) {
      if (sp == 0) return hit->slot != PC_INVALID;
      --sp;
      if (stack_entry[sp] <= hit->t) break;
    }
    node = stack[sp];
  }
}

inline bool trace_bvh(__global const BvhNode* nodes, __global const Primitive* prims, const Ray* ray, bool any_hit,
                      Hit* hit) {
  RayPrecomp rp = ray_precompute(ray->d);
  if (rp.kz == 0u) return trace_bvh_axis(nodes, prims, ray, &rp, any_hit, hit, 0u);
  if (rp.kz == 1u) return trace_bvh_axis(nodes, prims, ray, &rp, any_hit, hit, 1u);
  return trace_bvh_axis(nodes, prims, ray, &rp, any_hit, hit, 2u);
}

#endif
