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

/* Written once over the program's lanes (kernels/lanes.cl): each light type for the lanes that chose one,
 * all of them at once; the float3 functions at the end are the one-lane instances (W = 1 programs: the
 * light and bdpt integrators, the GPU path kernel and the test kernels). */

typedef struct {
  Lane3 p, p_err, n, wi, Le;
  LaneF pdf;
  LaneI delta, infinite;
  LaneU light;
} LightSampleLanes;

/* A Light by lane. */
typedef struct {
  Lane3 emission, position, direction;
  LaneU type, prim, slot;
  LaneF area, cos_inner, cos_outer;
} LightLanes;

/* lights[index] for the lanes in m (the others get the first such lane's). Out of line (math.cl): up to fifteen
 * gathers, and three callers in the path program. */
PC_OUT_OF_LINE void gather_lights(__global const Light* lights, LaneU index, LaneI m, LightLanes* out) {
  LaneGroups at;
  lane_groups(index, m, &at);
  out->emission = lane_group_gather3(PC_FIELD_F(lights, emission), &at);
  out->type = lane_group_gather_uint(PC_FIELD_U(lights, type), &at);
  out->prim = lane_group_gather_uint(PC_FIELD_U(lights, prim), &at);
  out->slot = lane_group_gather_uint(PC_FIELD_U(lights, slot), &at);
  out->area = lane_group_gather_float(PC_FIELD_F(lights, area), &at);
  /* The fields of point, spot and directional lights only in programs that have them (sample_light_lanes
   * reads them under the same conditions). */
#ifdef PC_HAS_POINT_LIGHTS
  out->position = lane_group_gather3(PC_FIELD_F(lights, position), &at);
  out->cos_inner = lane_group_gather_float(PC_FIELD_F(lights, cos_inner), &at);
  out->cos_outer = lane_group_gather_float(PC_FIELD_F(lights, cos_outer), &at);
#endif
#if defined(PC_HAS_POINT_LIGHTS) || defined(PC_HAS_DIRECTIONAL_LIGHTS)
  out->direction = lane_group_gather3(PC_FIELD_F(lights, direction), &at);
#endif
}

/* The primitives (vertices a, b, c; a sphere's centre a and radius b.x) at the slots of the lanes in m. */
PC_LANE_INLINE void gather_primitive_shapes(__global const Primitive* prims, LaneU slot, LaneI m, Lane3* a, Lane3* b, Lane3* c,
                                    LaneI* sphere) {
  LaneGroups at;
  lane_groups(slot, m, &at);
  *a = lane_group_gather3(PC_FIELD_F(prims, a), &at);
  *b = lane_group_gather3(PC_FIELD_F(prims, b), &at);
  *c = lane_group_gather3(PC_FIELD_F(prims, c), &at);
  *sphere = m & (lane_group_gather_uint(PC_FIELD_U_AT(prims, b, 3), &at) == PC_PRIM_SPHERE); /* prim_kind_of */
}

static inline Lane3 emitted_towards_lanes(Lane3 emission, LaneU flags, Lane3 ny, Lane3 y, Lane3 x) {
  LaneI lit = ((flags & PC_FLAG_TWO_SIDED) != 0u) | (pc_dot(ny, lane3_sub(x, y)) > 0.0f);
  return lane3_select(lane3_splat((float3)(0.0f)), emission, lit);
}

/* Spot falloff: 1 inside the inner cone, 0 outside the outer one, smoothstep between (pbrt-v4). For one
 * lane in every program (light paths start lane by lane: emission.cl), and for the program's lanes. */
#define PC_SPOT_FALLOFF(V3, F)                                                                            \
  static inline PC_OVL F spot_falloff_lanes(V3 direction, F cos_inner, F cos_outer, V3 from_light) {     \
    F c = pc_dot(direction, from_light);                                                                  \
    F t = (c - cos_outer) / (cos_inner - cos_outer);                                                      \
    return select(select(t * t * (3.0f - 2.0f * t), (F)(0.0f), c <= cos_outer), (F)(1.0f), c >= cos_inner); \
  }
PC_SPOT_FALLOFF(float3, float)
#if PC_LANES > 1
PC_SPOT_FALLOFF(Lane3, LaneF)
#endif
#undef PC_SPOT_FALLOFF

static inline float spot_falloff(Light light, float3 from_light) {
  return spot_falloff_lanes(light.direction.xyz, light.cos_inner, light.cos_outer, from_light);
}

static inline LaneF area_to_solid_angle_lanes(Lane3 x, Lane3 y, Lane3 ny, LaneF area_pdf) {
  Lane3 d = lane3_sub(y, x);
  LaneF dist2 = pc_dot(d, d);
  LaneF cos_y = fabs(pc_dot(ny, d)) / sqrt(dist2);
  return select((LaneF)(0.0f), area_pdf * dist2 / cos_y, cos_y > 0.0f);
}

static inline LaneI sphere_sampled_by_area_lanes(Lane3 x, Lane3 c, LaneF r) {
  Lane3 d = lane3_sub(x, c);
  return pc_dot(d, d) <= r * r * 1.0001f;
}

static inline LaneF sphere_cone_one_minus_cos_lanes(LaneF sin2_max) {
  return select(1.0f - sqrt(fmax(0.0f, 1.0f - sin2_max)), 0.5f * sin2_max, sin2_max < 0.00068523f);
}

static inline LaneF sphere_light_pdf_lanes(Lane3 c, LaneF r, Lane3 x, Lane3 y, Lane3 ny) {
  Lane3 d = lane3_sub(c, x);
  LaneF cone = 1.0f / (2.0f * PC_PI * sphere_cone_one_minus_cos_lanes(r * r / pc_dot(d, d)));
  return select(cone, area_to_solid_angle_lanes(x, y, ny, 1.0f / (4.0f * PC_PI * r * r)),
                sphere_sampled_by_area_lanes(x, c, r));
}

/* light_pdf by lane, for the lanes in m. */
static inline LaneF light_pdf_lanes(const SceneData* sc, LaneU light_index, Lane3 x, Lane3 y, Lane3 ny, LaneI m) {
  LaneU unused;
  LaneF choice = light_choice_lanes(sc, x, light_index, (LaneF)(0.0f), m, &unused);
  LightLanes light;
  gather_lights(sc->lights, light_index, m, &light);
  LaneF pdf = area_to_solid_angle_lanes(x, y, ny, 1.0f / light.area);
#ifdef PC_HAS_SPHERES
  Lane3 a, b, c;
  LaneI sphere;
  gather_primitive_shapes(sc->prims, light.slot, m, &a, &b, &c, &sphere);
  if (pc_any_(sphere)) pdf = select(pdf, sphere_light_pdf_lanes(a, b.x, x, y, ny), sphere);
#endif
  return choice * pdf;
}

#ifdef PC_HAS_ENVIRONMENT
static inline LaneF environment_light_pdf_lanes(const SceneData* sc, Lane3 x, Lane3 d, LaneI m) {
  LaneU unused;
  Light env = sc->lights[sc->h->env_light];
  return light_choice_lanes(sc, x, (LaneU)(sc->h->env_light), (LaneF)(0.0f), m, &unused) *
         env_pdf_lanes(env, sc->textures, sc->env_dist, d, m);
}
#endif

/* A point on the sphere (centre c, radius r) seen from x, per lane. */
static inline Lane3 sample_sphere_cone_lanes(Lane3 c, LaneF r, Lane3 x, LaneF u0, LaneF u1, LaneF* pdf) {
  Lane3 d = lane3_sub(x, c);
  LaneF dc2 = pc_dot(d, d), dc = sqrt(dc2);
  LaneF sin2_max = r * r / dc2;
  LaneF one_minus_cos_max = sphere_cone_one_minus_cos_lanes(sin2_max);
  LaneF cos_theta = 1.0f - u0 * one_minus_cos_max;
  LaneF sin2_theta = 1.0f - cos_theta * cos_theta;
  LaneI small = sin2_max < 0.00068523f; /* small cone: avoid cancellation */
  LaneF small_sin2 = sin2_max * u0;
  cos_theta = select(cos_theta, sqrt(1.0f - small_sin2), small);
  sin2_theta = select(sin2_theta, small_sin2, small);
  LaneF cos_alpha = sin2_theta / sqrt(sin2_max) + cos_theta * sqrt(fmax(0.0f, 1.0f - sin2_theta / sin2_max));
  LaneF sin_alpha = sqrt(fmax(0.0f, 1.0f - cos_alpha * cos_alpha));
  LaneF phi = 2.0f * PC_PI * u1;
  Lane3 w = lane3_div(d, dc), t, b;
  make_frame(w, &t, &b);
  *pdf = 1.0f / (2.0f * PC_PI * one_minus_cos_max);
  LaneF cos_phi, sin_phi = pc_sincos(phi, &cos_phi);
  return lane3(c.x + r * (cos_alpha * w.x + sin_alpha * (cos_phi * t.x + sin_phi * b.x)),
               c.y + r * (cos_alpha * w.y + sin_alpha * (cos_phi * t.y + sin_phi * b.y)),
               c.z + r * (cos_alpha * w.z + sin_alpha * (cos_phi * t.z + sin_phi * b.z)));
}

/* A point on the area light (a triangle or a sphere) seen from x, into the lanes m of out. */
PC_OUT_OF_LINE void sample_area_light_lanes(const SceneData* sc, const LightLanes* light, LaneF choice, Lane3 x, LaneF u0,
                                            LaneF u1, LaneI m, LightSampleLanes* out) {
  Lane3 a, b, c, p = x, p_err = x, ny = x;
  LaneI sphere;
  LaneF pdf = (LaneF)(0.0f);
  gather_primitive_shapes(sc->prims, light->slot, m, &a, &b, &c, &sphere);
  LaneU flags = lane_gather_uint(PC_FIELD_U(sc->shading, flags), lane_safe_index(light->prim, m));
  if (pc_any_(m & !sphere)) {
    LaneF ba, bb;
    sample_uniform_triangle_lanes(u0, u1, &ba, &bb);
    Lane3 pa = lane3_scale(a, ba), pb = lane3_scale(b, bb), pc = lane3_scale(c, 1.0f - ba - bb);
    p = lane3_add(lane3_add(pa, pb), pc);
    p_err = lane3_scale(lane3_add(lane3_add(lane3_abs(pa), lane3_abs(pb)), lane3_abs(pc)), error_gamma(7));
    ny = pc_normalize(pc_cross(lane3_sub(b, a), lane3_sub(c, a)));
    pdf = area_to_solid_angle_lanes(x, p, ny, 1.0f / light->area);
  }
#ifdef PC_HAS_SPHERES
  if (pc_any_(sphere)) {
    LaneF r = b.x, sphere_pdf = (LaneF)(0.0f);
    LaneI by_area = sphere_sampled_by_area_lanes(x, a, r);
    Lane3 q = x;
    if (pc_any_(sphere & !by_area)) q = sample_sphere_cone_lanes(a, r, x, u0, u1, &sphere_pdf);
    if (pc_any_(sphere & by_area)) {
      LaneF sx, sy, sz;
      sample_uniform_sphere_lanes(u0, u1, &sx, &sy, &sz);
      q = lane3_select(q, lane3_add(a, lane3_scale(lane3(sx, sy, sz), r)), by_area);
    }
    Lane3 n = lane3_div(lane3_sub(q, a), r); /* sphere_normal */
    n = lane3_select(n, lane3_neg(n), (flags & PC_FLAG_FLIP_NORMAL) != 0u);
    if (pc_any_(sphere & by_area))
      sphere_pdf = select(sphere_pdf, area_to_solid_angle_lanes(x, q, n, 1.0f / (4.0f * PC_PI * r * r)), by_area);
    p = lane3_select(p, q, sphere);
    p_err = lane3_select(
        p_err, lane3_add(lane3_scale(lane3_abs(lane3_sub(q, a)), error_gamma(5)), lane3_scale(lane3_abs(q), error_gamma(1))),
        sphere);
    ny = lane3_select(ny, n, sphere);
    pdf = select(pdf, sphere_pdf, sphere);
  }
#endif
  out->p = lane3_select(out->p, p, m);
  out->p_err = lane3_select(out->p_err, p_err, m);
  out->n = lane3_select(out->n, ny, m);
  out->wi = lane3_select(out->wi, pc_normalize(lane3_sub(p, x)), m);
  out->pdf = select(out->pdf, choice * pdf, m);
  out->Le = lane3_select(out->Le, emitted_towards_lanes(light->emission, flags, ny, p, x), m);
}

/* sample_light by lane, for the lanes in m: u0 chooses the light, u1, u2 the point on it. Returns the
 * lanes with a sample (as sample_light's result). */
PC_OUT_OF_LINE LaneI sample_light_lanes(const SceneData* sc, Lane3 x, LaneF u0, LaneF u1, LaneF u2, LaneI m,
                                        LightSampleLanes* out) {
  LaneU index;
  LaneF choice = light_choice_lanes(sc, x, (LaneU)(PC_INVALID), u0, m, &index);
  LightLanes light;
  gather_lights(sc->lights, index, m, &light);
  Lane3 zero = lane3_splat((float3)(0.0f));
  out->light = index;
  out->delta = out->infinite = (LaneI)(0);
  out->p = x;
  out->n = out->p_err = out->wi = out->Le = zero;
  out->pdf = (LaneF)(0.0f);
  LaneI valid = (LaneI)(0), is;
#ifdef PC_HAS_AREA_LIGHTS
  if (pc_any_(is = m & (light.type == PC_LIGHT_AREA))) {
    sample_area_light_lanes(sc, &light, choice, x, u1, u2, is, out);
    valid |= is;
  }
#endif
#ifdef PC_HAS_POINT_LIGHTS
  if (pc_any_(is = m & ((light.type == PC_LIGHT_POINT) | (light.type == PC_LIGHT_SPOT)))) {
    Lane3 d = lane3_sub(light.position, x);
    LaneF dist2 = pc_dot(d, d);
    Lane3 wi = lane3_div(d, sqrt(dist2));
    Lane3 le = lane3_div(light.emission, dist2);
    LaneI spot = is & (light.type == PC_LIGHT_SPOT);
    if (pc_any_(spot)) {
      LaneF falloff = spot_falloff_lanes(light.direction, light.cos_inner, light.cos_outer, lane3_neg(wi));
      le = lane3_select(le, lane3_scale(le, falloff), spot);
    }
    out->p = lane3_select(out->p, light.position, is);
    out->wi = lane3_select(out->wi, wi, is);
    out->n = lane3_select(out->n, lane3_neg(wi), is);
    out->Le = lane3_select(out->Le, le, is);
    out->pdf = select(out->pdf, choice, is);
    out->delta |= is;
    valid |= is & (dist2 > 0.0f); /* not where the shading point is the light's position */
  }
#endif
#ifdef PC_HAS_DIRECTIONAL_LIGHTS
  if (pc_any_(is = m & (light.type == PC_LIGHT_DIRECTIONAL))) {
    out->wi = lane3_select(out->wi, lane3_neg(light.direction), is);
    out->Le = lane3_select(out->Le, light.emission, is);
    out->pdf = select(out->pdf, choice, is);
    out->delta |= is;
    out->infinite |= is;
    valid |= is;
  }
#endif
#ifdef PC_HAS_ENVIRONMENT
  if (pc_any_(is = m & (light.type == PC_LIGHT_ENVIRONMENT))) {
    PC_EACH_LANE(j, pc_lane_bits(is)) {
      float pdf;
      float3 le, wi = env_sample(sc->lights[pc_lane(index, j)], sc->textures, sc->texels, sc->env_dist, (float2)(pc_lane(u1, j), pc_lane(u2, j)),
                                 &pdf, &le);
      out->wi = lane3_with(out->wi, j, wi);
      out->Le = lane3_with(out->Le, j, le);
      out->pdf = pc_with_lane(out->pdf, j, pc_lane(choice, j) * pdf);
    }
    out->infinite |= is;
    valid |= is;
  }
#endif
  return valid & (out->pdf > 0.0f) & isfinite(out->pdf) & lane3_any_positive(out->Le);
}

/* ---- One lane: the float3 functions of the W = 1 programs --------------------------------------------- */
#if PC_LANES == 1
/* Radiance from light point y with normal ny towards x. */
static inline float3 emitted_towards(float3 emission, uint flags, float3 ny, float3 y, float3 x) {
  return emitted_towards_lanes(emission, flags, ny, y, x);
}

/* Solid-angle pdf of reaching point y (normal ny) of area light light_index from x, light choice included. */
static inline float light_pdf(const SceneData* sc, uint light_index, float3 x, float3 y, float3 ny) {
  return light_pdf_lanes(sc, light_index, x, y, ny, 1);
}

#ifdef PC_HAS_ENVIRONMENT
/* Solid-angle pdf of light sampling from x producing direction d towards the environment. */
static inline float environment_light_pdf(const SceneData* sc, float3 x, float3 d) {
  return environment_light_pdf_lanes(sc, x, d, 1);
}
#endif

/* u: x chooses the light, yz the point on it. */
static inline bool sample_light(const SceneData* sc, float3 x, float3 u, LightSample* out) {
  LightSampleLanes ls;
  bool ok = sample_light_lanes(sc, x, u.x, u.y, u.z, 1, &ls) != 0;
  out->p = ls.p;
  out->p_err = ls.p_err;
  out->n = ls.n;
  out->wi = ls.wi;
  out->Le = ls.Le;
  out->pdf = ls.pdf;
  out->delta = ls.delta != 0;
  out->infinite = ls.infinite != 0;
  out->light = ls.light;
  return ok;
}
#endif

#endif
