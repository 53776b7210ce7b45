/* The surface at a hit: position with its rounding-error bound, geometric and shading normals. */
#ifndef PATHCL_SURFACE_CL
#define PATHCL_SURFACE_CL

typedef struct {
  float3 p;     /* hit point */
  float3 p_err; /* bound on the absolute error of p, per axis */
  float3 ng;    /* geometric normal: the front side (counter-clockwise, or outwards unless flipped) */
  float3 ns;    /* shading normal, on the same side as ng */
  uint prim;    /* scene-order primitive index */
} Surface;

inline float3 triangle_normal(Primitive p) { return pc_normalize(pc_cross(p.b.xyz - p.a.xyz, p.c.xyz - p.a.xyz)); }

/* Outward normal at a point of a sphere, inward when the sphere's normals are flipped. */
inline float3 sphere_normal(Primitive p, float3 at, uint flags) {
  float3 n = (at - p.a.xyz) / p.b.x;
  return (flags & PC_FLAG_FLIP_NORMAL) ? -n : n;
}

inline Surface surface_at(__global const Primitive* prims, __global const PrimShading* shading,
                          __global const float4* normals, const Ray* ray, const Hit* hit) {
  Surface s;
  Primitive p = prims[hit->slot];
  s.prim = prim_index_of(p);
#ifdef PC_HAS_SPHERES
  if (prim_kind_of(p) == PC_PRIM_SPHERE) {
    /* Re-project onto the sphere (pbrt-v4): the error is then a few ulps of the offset from the centre. */
    float3 c = p.a.xyz;
    float3 rel = ray->o + hit->t * ray->d - c;
    rel *= p.b.x / pc_length(rel);
    s.p = c + rel;
    s.p_err = error_gamma(5) * fabs(rel) + error_gamma(1) * fabs(s.p);
    s.ng = sphere_normal(p, s.p, shading[s.prim].flags);
    s.ns = s.ng;
    return s;
  }
#endif
  float b0 = 1.0f - hit->u - hit->v;
  float3 pa = b0 * p.a.xyz, pb = hit->u * p.b.xyz, pc = hit->v * p.c.xyz;
  s.p = pa + pb + pc;
  s.p_err = error_gamma(7) * (fabs(pa) + fabs(pb) + fabs(pc));
  s.ng = triangle_normal(p);
  s.ns = s.ng;
#ifdef PC_HAS_SMOOTH_NORMALS
  if (shading[s.prim].flags & PC_FLAG_SMOOTH) {
    float3 n = b0 * normals[3 * s.prim].xyz + hit->u * normals[3 * s.prim + 1].xyz +
               hit->v * normals[3 * s.prim + 2].xyz;
    float len = pc_length(n);
    if (len > 0.0f) s.ns = pc_dot(n, s.ng) < 0.0f ? -n / len : n / len;
  }
#endif
  return s;
}

/* Shadow rays stop this fraction short of their far end. */
#define PC_SHADOW_EPSILON 1e-4f

/* A shadow ray between two surface points, each moved off its surface by its error bound towards the
 * other (pbrt-v4's SpawnRayTo): neither end's own surface can block it. The direction is not unit
 * length; the ray covers [0, 1 - PC_SHADOW_EPSILON] of the way. */
inline Ray spawn_ray_to(float3 p, float3 p_err, float3 n, uint prim, float3 q, float3 q_err, float3 nq) {
  Ray r;
  r.o = offset_ray_origin(p, p_err, n, q - p);
  r.d = offset_ray_origin(q, q_err, nq, r.o - q) - r.o;
  r.tmin = 0.0f;
  r.tmax = 1.0f - PC_SHADOW_EPSILON;
  r.skip_prim = prim;
  return r;
}

#endif
