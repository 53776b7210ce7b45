/* Lights: choosing one from a shading point (light_tree.cl), sampling it, and the matching pdf for
 * multiple importance sampling.
 * Area lights: triangles sampled uniformly by area, spheres by the cone of directions they subtend (by
 * area from inside). Point, spot and directional lights are deltas: sampled deterministically, never
 * hit. The environment is sampled by environment.cl. */
#ifndef PATHCL_LIGHTS_CL
#define PATHCL_LIGHTS_CL

#include "light_tree.cl"

typedef struct {
  float3 p;      /* point on the light (positional lights) */
  float3 p_err;  /* bound on the rounding error of p */
  float3 n;      /* the light's geometric normal at p (area lights) */
  float3 wi;     /* unit direction from the shading point towards the light */
  float3 Le;     /* radiance arriving along wi; for delta lights the irradiance on a surface facing wi */
  float pdf;     /* solid-angle density at the shading point, light choice included; for a delta light
                    the probability of having chosen it */
  bool delta;    /* point, spot, directional: no MIS, never hit by BSDF rays */
  bool infinite; /* directional, environment: the shadow ray runs to infinity */
  uint light;    /* index into lights */
} LightSample;

/* The geometry of light sampling written once over lanes (V3 lane3f/lane3f8/lane3f16, F, I their float and
 * int types; issue 15): the light's parameters per lane, branches per-lane selects; the functions on
 * Light and Primitive below are the one-lane instances (tests/light_sampling_test.cpp,
 * LightGeometryGivesTheOneLaneBits). */
#define PC_LIGHTS_LANES(V3, F, I)                                                                         \
  /* Radiance from light point y with normal ny towards x: emission on the front side (both sides where  \
   * two_sided). */                                                                                       \
  inline PC_OVL V3 emitted_towards(V3 emission, I two_sided, V3 ny, V3 y, V3 x) {                         \
    I lit = two_sided | (pc_dot(ny, lane3(x.x - y.x, x.y - y.y, x.z - y.z)) > 0.0f);                      \
    return lane3(select((F)(0.0f), emission.x, lit), select((F)(0.0f), emission.y, lit),                 \
                 select((F)(0.0f), emission.z, lit));                                                     \
  }                                                                                                       \
  /* From inside (or on) a sphere every point is visible and area sampling is used. The tolerance keeps   \
   * points on the surface itself on the inside branch in both sampling and pdf evaluation. */           \
  inline PC_OVL I sphere_sampled_by_area(V3 x, V3 c, F r) {                                               \
    V3 d = lane3(x.x - c.x, x.y - c.y, x.z - c.z);                                                        \
    return pc_dot(d, d) <= r * r * 1.0001f;                                                               \
  }                                                                                                       \
  /* 1 - cos(theta_max) of the cone a sphere subtends, accurate for small cones. */                       \
  inline PC_OVL F sphere_cone_one_minus_cos(F sin2_max) {                                                 \
    return select(1.0f - sqrt(fmax(0.0f, 1.0f - sin2_max)), 0.5f * sin2_max, sin2_max < 0.00068523f);     \
  }                                                                                                       \
  inline PC_OVL F area_to_solid_angle(V3 x, V3 y, V3 ny, F area_pdf) {                                    \
    V3 d = lane3(y.x - x.x, y.y - x.y, y.z - x.z);                                                        \
    F dist2 = pc_dot(d, d);                                                                               \
    F cos_y = fabs(pc_dot(ny, d)) / sqrt(dist2);                                                          \
    return select((F)(0.0f), area_pdf * dist2 / cos_y, cos_y > 0.0f);                                     \
  }                                                                                                       \
  /* A sphere's (centre c, radius r) solid-angle density from x of point y with normal ny. */            \
  inline PC_OVL F sphere_light_pdf(V3 c, F r, V3 x, V3 y, V3 ny) {                                        \
    V3 d = lane3(c.x - x.x, c.y - x.y, c.z - x.z);                                                        \
    F cone = 1.0f / (2.0f * PC_PI * sphere_cone_one_minus_cos(r * r / pc_dot(d, d)));                     \
    return select(cone, area_to_solid_angle(x, y, ny, 1.0f / (4.0f * PC_PI * r * r)), sphere_sampled_by_area(x, c, r)); \
  }                                                                                                       \
  /* A point on the sphere seen from x inside the cone it subtends (pbrt-v4's construction). */          \
  inline PC_OVL V3 sample_sphere_cone(V3 c, F r, V3 x, F u0, F u1, F* pdf) {                              \
    V3 d = lane3(x.x - c.x, x.y - c.y, x.z - c.z);                                                        \
    F dc2 = pc_dot(d, d), dc = sqrt(dc2);                                                                 \
    F sin2_max = r * r / dc2;                                                                             \
    F one_minus_cos_max = sphere_cone_one_minus_cos(sin2_max);                                            \
    F cos_theta = 1.0f - u0 * one_minus_cos_max;                                                          \
    F sin2_theta = 1.0f - cos_theta * cos_theta;                                                          \
    I small = sin2_max < 0.00068523f; /* small cone: avoid cancellation */                                \
    F small_sin2 = sin2_max * u0;                                                                         \
    cos_theta = select(cos_theta, sqrt(1.0f - small_sin2), small);                                        \
    sin2_theta = select(sin2_theta, small_sin2, small);                                                   \
    /* Angle alpha at the centre between the direction to x and the sampled point. */                    \
    F cos_alpha = sin2_theta / sqrt(sin2_max) + cos_theta * sqrt(fmax(0.0f, 1.0f - sin2_theta / sin2_max)); \
    F sin_alpha = sqrt(fmax(0.0f, 1.0f - cos_alpha * cos_alpha));                                         \
    F phi = 2.0f * PC_PI * u1;                                                                            \
    V3 w = lane3(d.x / dc, d.y / dc, d.z / dc), t, b;                                                     \
    make_frame(w, &t, &b);                                                                                \
    *pdf = 1.0f / (2.0f * PC_PI * one_minus_cos_max);                                                     \
    F cos_phi, sin_phi = pc_sincos(phi, &cos_phi);                                                        \
    return lane3(c.x + r * (cos_alpha * w.x + sin_alpha * (cos_phi * t.x + sin_phi * b.x)),               \
                 c.y + r * (cos_alpha * w.y + sin_alpha * (cos_phi * t.y + sin_phi * b.y)),               \
                 c.z + r * (cos_alpha * w.z + sin_alpha * (cos_phi * t.z + sin_phi * b.z)));              \
  }                                                                                                       \
  /* A point of an area light seen from x: a triangle (a, b, c) by area, or where sphere is set a sphere  \
   * (centre a, radius b.x; flip: its normals point inwards) by its cone or, from inside, by area.        \
   * inv_area: 1 / the triangle's area. *pdf: solid-angle density, light choice not included. */          \
  inline PC_OVL void sample_area_light_lanes(I sphere, V3 a, V3 b, V3 c, F inv_area, I flip, V3 x, F u0,   \
                                             F u1, V3* p, V3* p_err, V3* n, F* pdf) {                     \
    if (pc_any_(!sphere)) {                                                                               \
      F ba, bb;                                                                                           \
      sample_uniform_triangle_lanes(u0, u1, &ba, &bb);                                                    \
      F bc = 1.0f - ba - bb;                                                                              \
      V3 pa = lane3(ba * a.x, ba * a.y, ba * a.z), pb = lane3(bb * b.x, bb * b.y, bb * b.z);              \
      V3 pc = lane3(bc * c.x, bc * c.y, bc * c.z);                                                        \
      *p = lane3(pa.x + pb.x + pc.x, pa.y + pb.y + pc.y, pa.z + pb.z + pc.z);                             \
      F g7 = error_gamma(7);                                                                              \
      *p_err = lane3(g7 * (fabs(pa.x) + fabs(pb.x) + fabs(pc.x)), g7 * (fabs(pa.y) + fabs(pb.y) + fabs(pc.y)), \
                     g7 * (fabs(pa.z) + fabs(pb.z) + fabs(pc.z)));                                        \
      *n = pc_normalize(pc_cross(lane3(b.x - a.x, b.y - a.y, b.z - a.z), lane3(c.x - a.x, c.y - a.y, c.z - a.z))); \
      *pdf = area_to_solid_angle(x, *p, *n, inv_area);                                                    \
    }                                                                                                     \
    if (pc_any_(sphere)) {                                                                                \
      F r = b.x, cone_pdf, sx, sy, sz;                                                                    \
      I by_area = sphere_sampled_by_area(x, a, r);                                                        \
      sample_uniform_sphere_lanes(u0, u1, &sx, &sy, &sz);                                                 \
      V3 q = sample_sphere_cone(a, r, x, u0, u1, &cone_pdf);                                              \
      q = lane3(select(q.x, a.x + r * sx, by_area), select(q.y, a.y + r * sy, by_area),                   \
                select(q.z, a.z + r * sz, by_area));                                                      \
      /* sphere_normal */                                                                                 \
      V3 m = lane3((q.x - a.x) / r, (q.y - a.y) / r, (q.z - a.z) / r);                                    \
      m = lane3(select(m.x, -m.x, flip), select(m.y, -m.y, flip), select(m.z, -m.z, flip));               \
      F q_pdf = select(cone_pdf, area_to_solid_angle(x, q, m, 1.0f / (4.0f * PC_PI * r * r)), by_area);   \
      F g5 = error_gamma(5), g1 = error_gamma(1);                                                         \
      V3 q_err = lane3(g5 * fabs(q.x - a.x) + g1 * fabs(q.x), g5 * fabs(q.y - a.y) + g1 * fabs(q.y),      \
                       g5 * fabs(q.z - a.z) + g1 * fabs(q.z));                                            \
      *p = lane3(select(p->x, q.x, sphere), select(p->y, q.y, sphere), select(p->z, q.z, sphere));        \
      *p_err = lane3(select(p_err->x, q_err.x, sphere), select(p_err->y, q_err.y, sphere),                \
                     select(p_err->z, q_err.z, sphere));                                                  \
      *n = lane3(select(n->x, m.x, sphere), select(n->y, m.y, sphere), select(n->z, m.z, sphere));        \
      *pdf = select(*pdf, q_pdf, sphere);                                                                 \
    }                                                                                                     \
  }                                                                                                       \
  /* Spot falloff: 1 inside the inner cone, 0 outside the outer one, smoothstep between (pbrt-v4). */    \
  inline PC_OVL F spot_falloff(V3 direction, F cos_inner, F cos_outer, V3 from_light) {                   \
    F c = pc_dot(direction, from_light);                                                                  \
    F t = (c - cos_outer) / (cos_inner - cos_outer);                                                      \
    return select(select(t * t * (3.0f - 2.0f * t), (F)(0.0f), c <= cos_outer), (F)(1.0f), c >= cos_inner); \
  }                                                                                                       \
  /* A point or (where spot) spot light at position seen from x: the direction to it and the irradiance  \
   * on a surface facing it; the mask: where x is not the light's position. */                           \
  inline PC_OVL I sample_point_light_lanes(V3 position, V3 emission, I spot, V3 direction, F cos_inner,    \
                                           F cos_outer, V3 x, V3* wi, V3* le) {                           \
    V3 d = lane3(position.x - x.x, position.y - x.y, position.z - x.z);                                   \
    F dist2 = pc_dot(d, d), dist = sqrt(dist2);                                                           \
    *wi = lane3(d.x / dist, d.y / dist, d.z / dist);                                                      \
    *le = lane3(emission.x / dist2, emission.y / dist2, emission.z / dist2);                              \
    if (pc_any_(spot)) {                                                                                  \
      F f = spot_falloff(direction, cos_inner, cos_outer, lane3(-wi->x, -wi->y, -wi->z));                 \
      *le = lane3(select(le->x, le->x * f, spot), select(le->y, le->y * f, spot), select(le->z, le->z * f, spot)); \
    }                                                                                                     \
    return dist2 > 0.0f;                                                                                  \
  }
PC_LIGHTS_LANES(lane3f, float, int)
PC_LIGHTS_LANES(lane3f8, float8, int8)
PC_LIGHTS_LANES(lane3f16, float16, int16)
#undef PC_LIGHTS_LANES

inline PC_OVL float3 emitted_towards(float3 emission, uint flags, float3 ny, float3 y, float3 x) {
  return float3_of(emitted_towards(lane3_of(emission), (flags & PC_FLAG_TWO_SIDED) != 0u, lane3_of(ny), lane3_of(y),
                                   lane3_of(x)));
}

inline PC_OVL float area_to_solid_angle(float3 x, float3 y, float3 ny, float area_pdf) {
  return area_to_solid_angle(lane3_of(x), lane3_of(y), lane3_of(ny), area_pdf);
}

inline float triangle_light_pdf(Light light, float3 x, float3 y, float3 ny) {
  return area_to_solid_angle(x, y, ny, 1.0f / light.area);
}

inline PC_OVL float sphere_light_pdf(Primitive sp, float3 x, float3 y, float3 ny) {
  return sphere_light_pdf(lane3_of(sp.a.xyz), sp.b.x, lane3_of(x), lane3_of(y), lane3_of(ny));
}

inline PC_OVL float spot_falloff(Light light, float3 from_light) {
  return spot_falloff(lane3_of(light.direction.xyz), light.cos_inner, light.cos_outer, lane3_of(from_light));
}

/* Solid-angle pdf of reaching point y (normal ny) of area light light_index from x, light choice included. */
inline float light_pdf(const SceneData* sc, uint light_index, float3 x, float3 y, float3 ny) {
  Light light = sc->lights[light_index];
  float choice = light_choice_pdf(sc, x, light_index);
#ifdef PC_HAS_SPHERES
  Primitive p = sc->prims[light.slot];
  if (prim_kind_of(p) == PC_PRIM_SPHERE) return choice * sphere_light_pdf(p, x, y, ny);
#endif
  return choice * triangle_light_pdf(light, x, y, ny);
}

#ifdef PC_HAS_ENVIRONMENT
/* Solid-angle pdf of light sampling from x producing direction d towards the environment. */
inline float environment_light_pdf(const SceneData* sc, float3 x, float3 d) {
  Light env = sc->lights[sc->h->env_light];
  return light_choice_pdf(sc, x, sc->h->env_light) * env_pdf(env, sc->textures, sc->env_dist, d);
}
#endif

inline void sample_area_light(Light light, float choice, __global const Primitive* prims,
                              __global const PrimShading* shading, float3 x, float2 u, LightSample* out) {
  Primitive p = prims[light.slot];
  uint flags = shading[light.prim].flags;
  lane3f q, q_err, n;
  float pdf;
#ifdef PC_HAS_SPHERES
  int sphere = prim_kind_of(p) == PC_PRIM_SPHERE;
#else
  int sphere = 0;
#endif
  sample_area_light_lanes(sphere, lane3_of(p.a.xyz), lane3_of(p.b.xyz), lane3_of(p.c.xyz), 1.0f / light.area,
                          (flags & PC_FLAG_FLIP_NORMAL) != 0u, lane3_of(x), u.x, u.y, &q, &q_err, &n, &pdf);
  out->p = float3_of(q);
  out->p_err = float3_of(q_err);
  out->n = float3_of(n);
  out->wi = pc_normalize(out->p - x);
  out->pdf = choice * pdf;
  out->Le = emitted_towards(light.emission.xyz, flags, out->n, out->p, x);
}

/* u: x chooses the light, yz the point on it. */
inline bool sample_light(const SceneData* sc, float3 x, float3 u, LightSample* out) {
  uint index;
  float choice = light_choice(sc, x, PC_INVALID, u.x, &index);
  Light light = sc->lights[index];
  out->light = index;
  /* Every field is set: lights at infinity have no point, and a field left undefined is undefined
     behaviour that a vectorising compiler may exploit (Intel's CPU runtime did). */
  out->delta = false;
  out->infinite = false;
  out->p = x;
  out->n = (float3)(0.0f);
  out->p_err = (float3)(0.0f);
  switch (light.type) {
#ifdef PC_HAS_AREA_LIGHTS
    case PC_LIGHT_AREA:
      sample_area_light(light, choice, sc->prims, sc->shading, x, u.yz, out);
      break;
#endif
#ifdef PC_HAS_POINT_LIGHTS
    case PC_LIGHT_POINT:
    case PC_LIGHT_SPOT: {
      lane3f wi, le;
      if (!sample_point_light_lanes(lane3_of(light.position.xyz), lane3_of(light.emission.xyz), light.type == PC_LIGHT_SPOT,
                                    lane3_of(light.direction.xyz), light.cos_inner, light.cos_outer, lane3_of(x), &wi, &le))
        return false; /* the shading point is the light's position */
      out->p = light.position.xyz;
      out->wi = float3_of(wi);
      out->n = -out->wi;
      out->Le = float3_of(le);
      out->pdf = choice;
      out->delta = true;
      break;
    }
#endif
#ifdef PC_HAS_DIRECTIONAL_LIGHTS
    case PC_LIGHT_DIRECTIONAL:
      out->wi = -light.direction.xyz;
      out->Le = light.emission.xyz;
      out->pdf = choice;
      out->delta = true;
      out->infinite = true;
      break;
#endif
#ifdef PC_HAS_ENVIRONMENT
    case PC_LIGHT_ENVIRONMENT: {
      float pdf;
      out->wi = env_sample(light, sc->textures, sc->texels, sc->env_dist, u.yz, &pdf, &out->Le);
      out->pdf = choice * pdf;
      out->infinite = true;
      break;
    }
#endif
    default:
      return false;
  }
  return out->pdf > 0.0f && isfinite(out->pdf) && (out->Le.x > 0.0f || out->Le.y > 0.0f || out->Le.z > 0.0f);
}

#endif
