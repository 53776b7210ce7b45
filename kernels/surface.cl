/* The surface at a hit: position with its rounding-error bound, geometric and shading normals. */
#ifndef PATHCL_SURFACE_CL
#define PATHCL_SURFACE_CL

#include "math.cl"
#include "trace_lanes.cl"

typedef struct {
  float3 p;     /* hit point */
  float3 p_err; /* bound on the absolute error of p, per axis */
  float3 ng;    /* geometric normal: the front side (counter-clockwise, or outwards unless flipped) */
  float3 ns;    /* shading normal, on the same side as ng */
  uint prim;    /* scene-order primitive index */
  uint instance; /* with instances (PC_HAS_INSTANCES): the instance of prim; 0 otherwise */
} Surface;

static inline float3 triangle_normal(Primitive p) { return pc_normalize(pc_cross(p.b.xyz - p.a.xyz, p.c.xyz - p.a.xyz)); }

/* Outward normal at a point of a sphere, inward when the sphere's normals are flipped. */
static inline float3 sphere_normal(Primitive p, float3 at, uint flags) {
  float3 n = (at - p.a.xyz) / p.b.x;
  return (flags & PC_FLAG_FLIP_NORMAL) ? -n : n;
}

#ifdef PC_HAS_INSTANCES
/* A normal of the mesh's coordinates in the device's: by the inverse transpose of to_device's linear part,
 * which is the transpose of to_mesh's. It keeps the side a normal points to, also for a mirroring
 * transform, so the front stays the front. */
static inline float3 transform_normal(__global const float4* to_mesh, float3 n) {
  float4 r0 = to_mesh[0], r1 = to_mesh[1], r2 = to_mesh[2];
  return (float3)((r0.x * n.x + r1.x * n.y) + r2.x * n.z, (r0.y * n.x + r1.y * n.y) + r2.y * n.z,
                  (r0.z * n.x + r1.z * n.y) + r2.z * n.z);
}

/* A surface of an instance's mesh (in the mesh's coordinates, as scene_surface_lanes first finds it) in the device's
 * coordinates. The error bound of the transformed point is pbrt-v4's: the point's own bound carried
 * through the matrix, plus the rounding of the transform's products and sums. */
static inline void place_surface(Surface* s, __global const Instance* inst) {
  float3 p = s->p, e = s->p_err;
  __global const float4* m = inst->to_device;
  s->p = transform_point(m, p);
  float3 carried, rounded;
  carried.x = (fabs(m[0].x) * e.x + fabs(m[0].y) * e.y) + fabs(m[0].z) * e.z;
  carried.y = (fabs(m[1].x) * e.x + fabs(m[1].y) * e.y) + fabs(m[1].z) * e.z;
  carried.z = (fabs(m[2].x) * e.x + fabs(m[2].y) * e.y) + fabs(m[2].z) * e.z;
  rounded.x = ((fabs(m[0].x * p.x) + fabs(m[0].y * p.y)) + fabs(m[0].z * p.z)) + fabs(m[0].w);
  rounded.y = ((fabs(m[1].x * p.x) + fabs(m[1].y * p.y)) + fabs(m[1].z * p.z)) + fabs(m[1].w);
  rounded.z = ((fabs(m[2].x * p.x) + fabs(m[2].y * p.y)) + fabs(m[2].z * p.z)) + fabs(m[2].w);
  s->p_err = (1.0f + error_gamma(3)) * carried + error_gamma(3) * rounded;
  s->ng = pc_normalize(transform_normal(inst->to_mesh, s->ng));
  s->ns = pc_normalize(transform_normal(inst->to_mesh, s->ns));
}
#endif

/* Shadow rays stop this fraction short of their far end. */
#define PC_SHADOW_EPSILON 1e-4f

/* ---- Written once over the program's lanes (kernels/lanes.cl); the functions on Surface, Ray and Hit at
 * the end are the one-lane instances. */

/* Surface by lane (one lane is a Surface), and the PrimShading of its primitive. */
#if PC_LANES == 1
typedef Surface SurfaceLanes;
#else
typedef struct {
  Lane3 p, p_err, ng, ns;
  LaneU prim, instance;
} SurfaceLanes;
#endif

typedef struct {
  LaneU material, light, flags;
} ShadingLanes;

/* A vertex attribute of 3 float4 per primitive (smooth normals, vertex colours) at barycentric (b0, u, v)
 * of each lane's primitive: (a b0 + b u) + c v. */
static inline Lane3 vertex_blend_lanes(__global const float4* vertices, LaneU prim, LaneF b0, LaneF u, LaneF v) {
  Lane3 a, b, c;
  LaneF unused;
  lane_gather4(vertices, 3u, prim, &a, &unused);
  lane_gather4(vertices + 1, 3u, prim, &b, &unused);
  lane_gather4(vertices + 2, 3u, prim, &c, &unused);
  return lane3_add(lane3_add(lane3_scale(a, b0), lane3_scale(b, u)), lane3_scale(c, v));
}

/* The surfaces at the hits of trace_scene (trace_lanes) of the lanes in m (the others get the first such
 * lane's), in the device's coordinates. A point on a sphere is re-projected onto it (pbrt-v4): its error is
 * then a few ulps of the offset from the centre. */
PC_OUT_OF_LINE SurfaceLanes scene_surface_lanes(const SceneData* sc, const RayLanes* ray, const HitLanes* hit, LaneI m,
                                                ShadingLanes* shading) {
  LaneU slot = lane_safe_index(hit->slot, m);
  Lane3 a, b, c;
  LaneF a_w, b_w, c_w;
  lane_gather4(PC_FIELD_F4(sc->prims, a), slot, &a, &a_w);
  lane_gather4(PC_FIELD_F4(sc->prims, b), slot, &b, &b_w);
  lane_gather4(PC_FIELD_F4(sc->prims, c), slot, &c, &c_w);
  SurfaceLanes s;
  s.prim = pc_bits_(a_w); /* prim_index_of: the bits of a.w */
  shading->material = lane_gather_uint(PC_FIELD_U(sc->shading, material), s.prim);
  shading->light = lane_gather_uint(PC_FIELD_U(sc->shading, light), s.prim);
  shading->flags = lane_gather_uint(PC_FIELD_U(sc->shading, flags), s.prim);
  s.instance = (LaneU)(0u);
  s.p = s.p_err = s.ng = s.ns = lane3_splat((float3)(0.0f));
  LaneF b0 = 1.0f - hit->u - hit->v;
  LaneI sphere = (LaneI)(0);
#ifdef PC_HAS_SPHERES
  sphere = m & (pc_bits_(b_w) == PC_PRIM_SPHERE); /* prim_kind_of: the bits of b.w */
#endif
  if (pc_any_(m & !sphere)) {
    Lane3 pa = lane3_scale(a, b0), pb = lane3_scale(b, hit->u), pc = lane3_scale(c, hit->v);
    s.p = lane3_add(lane3_add(pa, pb), pc);
    s.p_err = lane3_scale(lane3_add(lane3_add(lane3_abs(pa), lane3_abs(pb)), lane3_abs(pc)), error_gamma(7));
    s.ng = pc_normalize(pc_cross(lane3_sub(b, a), lane3_sub(c, a)));
    s.ns = s.ng;
  }
#ifdef PC_HAS_SPHERES
  if (pc_any_(sphere)) {
    /* the hit point re-projected onto the sphere (centre a, radius b.x) */
    Lane3 rel = lane3_sub(lane3_add(ray->o, lane3_scale(ray->d, hit->t)), a);
    rel = lane3_scale(rel, b.x / pc_length(rel));
    Lane3 p = lane3_add(a, rel);
    s.p = lane3_select(s.p, p, sphere);
    s.p_err = lane3_select(
        s.p_err, lane3_add(lane3_scale(lane3_abs(rel), error_gamma(5)), lane3_scale(lane3_abs(p), error_gamma(1))), sphere);
    Lane3 n = lane3_div(lane3_sub(p, a), b.x);
    n = lane3_select(n, lane3_neg(n), (shading->flags & PC_FLAG_FLIP_NORMAL) != 0u);
    s.ng = lane3_select(s.ng, n, sphere);
    s.ns = s.ng;
  }
#endif
#ifdef PC_HAS_SMOOTH_NORMALS
  LaneI smooth = m & !sphere & ((shading->flags & PC_FLAG_SMOOTH) != 0u);
  if (pc_any_(smooth)) {
    Lane3 n = vertex_blend_lanes(sc->normals, lane_safe_index(s.prim, smooth), b0, hit->u, hit->v);
    LaneF len = pc_length(n);
    Lane3 unit = lane3_div(lane3_select(n, lane3_neg(n), pc_dot(n, s.ng) < 0.0f), len);
    s.ns = lane3_select(s.ns, unit, smooth & (len > 0.0f));
  }
#endif
#ifdef PC_HAS_INSTANCES
  s.instance = hit->instance;
  PC_EACH_LANE(j, pc_lane_bits(m)) {
    uint k = pc_lane(hit->instance, j);
    if (sc->instances[k].flags & PC_INSTANCE_IDENTITY) continue;
    Surface one;
    one.p = lane3_at(s.p, j);
    one.p_err = lane3_at(s.p_err, j);
    one.ng = lane3_at(s.ng, j);
    one.ns = lane3_at(s.ns, j);
    place_surface(&one, sc->instances + k);
    s.p = lane3_with(s.p, j, one.p);
    s.p_err = lane3_with(s.p_err, j, one.p_err);
    s.ng = lane3_with(s.ng, j, one.ng);
    s.ns = lane3_with(s.ns, j, one.ns);
  }
#endif
  return s;
}

/* The ray leaving surface point p (error bound p_err, geometric normal n, primitive prim of instance) in
 * direction w (unit; a continuation, or a shadow ray towards a light at infinity): moved off the surface
 * by its error bound to w's side, its primitive skipped. Into *r, the cut-out seed left to the caller.
 * (The forced inlines of the lane code write through pointers rather than return structs: an inlined
 * struct return leaves an intrinsic, a noalias scope, that Oclgrind cannot execute.) */
PC_LANE_INLINE void spawn_ray_lanes(Lane3 p, Lane3 p_err, Lane3 n, LaneU prim, LaneU instance, Lane3 w, RayLanes* r) {
  r->o = offset_ray_origin(p, p_err, n, w);
  r->d = w;
  r->tmin = (LaneF)(0.0f);
  r->tmax = (LaneF)(INFINITY);
  r->skip_prim = prim;
  r->skip_instance = instance;
}

/* A shadow ray from that point to point q (error bound q_err, normal nq), each end moved off its surface
 * by its error bound towards the other (pbrt-v4's SpawnRayTo): neither end's own surface can block it.
 * The direction is not unit length; the ray covers [0, 1 - PC_SHADOW_EPSILON] of the way. */
PC_LANE_INLINE void spawn_ray_to_lanes(Lane3 p, Lane3 p_err, Lane3 n, LaneU prim, LaneU instance, Lane3 q,
                                       Lane3 q_err, Lane3 nq, RayLanes* r) {
  r->o = offset_ray_origin(p, p_err, n, lane3_sub(q, p));
  r->d = lane3_sub(offset_ray_origin(q, q_err, nq, lane3_sub(r->o, q)), r->o);
  r->tmin = (LaneF)(0.0f);
  r->tmax = (LaneF)(1.0f - PC_SHADOW_EPSILON);
  r->skip_prim = prim;
  r->skip_instance = instance;
}

#if PC_LANES == 1
/* The surface at a hit of the scene (trace_scene), in the device's coordinates. */
static inline Surface scene_surface(const SceneData* sc, const Ray* ray, const Hit* hit) {
  ShadingLanes shading;
  return scene_surface_lanes(sc, ray, hit, 1, &shading);
}

/* spawn_ray_lanes from surface point s; the cut-out seed is the caller's. */
static inline Ray spawn_ray(const Surface* s, float3 w) {
  Ray r;
  spawn_ray_lanes(s->p, s->p_err, s->ng, s->prim, s->instance, w, &r);
  r.cutout_seed = 0u;
  return r;
}

static inline Ray spawn_ray_to(float3 p, float3 p_err, float3 n, uint prim, uint instance, float3 q, float3 q_err, float3 nq) {
  Ray r;
  spawn_ray_to_lanes(p, p_err, n, prim, instance, q, q_err, nq, &r);
  r.cutout_seed = 0u;
  return r;
}
#endif

#endif
