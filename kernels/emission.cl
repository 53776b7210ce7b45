/* Emission sampling: where light paths start. A light is chosen by its power (emission_cdf, over every
 * light: area, point, spot, directional, environment; built by runtime/light_transport.cpp), then a point
 * and a direction of emission. The pdfs are kept apart, positional (area density of the point, 1 for a
 * point or spot light's delta) and directional (solid-angle density of the direction, 1 for a
 * directional light's delta), as BDPT's and photon merging's MIS need them (pbrt-v4's SampleLe / PDF_Le).
 * Directional and environment light paths start on a disk of the scene's bounding radius R, facing the
 * direction of travel, a distance R before the bounding sphere's centre: every ray of the light that
 * meets the scene crosses that disk.
 *
 * The choice here is by power alone (no shading point): the light BVH of light_tree.cl chooses lights
 * for shading points, and its lights at infinity are weighed by irradiance; a light path has no point
 * to weigh from. */
#ifndef PATHCL_EMISSION_CL
#define PATHCL_EMISSION_CL

#include "math.cl"
#include "sampling.cl"
#include "scene.cl"
#include "surface.cl"
#include "environment.cl"
#include "lights.cl"

typedef struct {
  float3 p;       /* the path's first vertex */
  float3 p_err;   /* bound on the rounding error of p */
  float3 n;       /* geometric normal at p on the side emitted into (area lights); else the direction */
  float3 d;       /* unit direction of emission */
  float3 Le;      /* emitted radiance (area, environment), intensity (point, spot), irradiance (directional) */
  float pdf_choice;
  float pdf_pos;  /* area density of p; 1 for a point or spot light (a delta) */
  float pdf_dir;  /* solid-angle density of d; 1 for a directional light (a delta) */
  uint light;     /* index into lights */
  uint prim;      /* area lights: scene-order primitive index (the first ray skips it); else PC_INVALID */
  bool delta_pos; /* point, spot */
  bool delta_dir; /* directional */
} EmissionSample;

/* A direction in the cone about +z of half-angle acos(cos_max), uniform in solid angle. */
static inline float3 sample_uniform_cone(float2 u, float cos_max) {
  float cos_theta = 1.0f - u.x * (1.0f - cos_max);
  float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
  float c, s = pc_sincos(2.0f * PC_PI * u.y, &c);
  return (float3)(sin_theta * c, sin_theta * s, cos_theta);
}

static inline float uniform_cone_pdf(float cos_max) { return 1.0f / (2.0f * PC_PI * (1.0f - cos_max)); }

/* A point of the disk of radius r about c facing w (w its normal). */
static inline float3 sample_disk_facing(float3 c, float r, float3 w, float2 u) {
  float3 t, b;
  make_frame(w, &t, &b);
  float2 q = r * sample_concentric_disk(u);
  return c + q.x * t + q.y * b;
}

/* The probability that the power distribution chooses light index. */
static inline float emission_choice_pdf(__global const float* emission_cdf, uint index) {
  return emission_cdf[index + 1] - emission_cdf[index];
}

/* Directional density of emitting d from a point of an area light with normal n (flags of its
 * primitive): cosine-weighted on the side(s) it emits. For one lane (emission sampling, lane by lane) and
 * for the program's lanes. */
#define PC_AREA_EMISSION_PDF_DIR(V3, F, U)                                                                \
  static inline PC_OVL F area_emission_pdf_dir(U flags, V3 n, V3 d) {                                     \
    F c = pc_dot(n, d);                                                                                   \
    return select(select((F)(0.0f), c * PC_INV_PI, c > 0.0f), 0.5f * fabs(c) * PC_INV_PI,                \
                  (flags & PC_FLAG_TWO_SIDED) != 0u);                                                     \
  }
PC_AREA_EMISSION_PDF_DIR(float3, float, uint)
#if PC_LANES > 1
PC_AREA_EMISSION_PDF_DIR(Lane3, LaneF, LaneU)
#endif
#undef PC_AREA_EMISSION_PDF_DIR

/* emission_choice_pdf of the lanes in m. */
static inline LaneF emission_choice_pdf_lanes(__global const float* emission_cdf, LaneU index, LaneI m) {
  LaneU at = lane_safe_index(index, m);
  return lane_gather_float(emission_cdf + 1, 1u, at) - lane_gather_float(emission_cdf, 1u, at);
}

/* Positional and directional densities of light `index` emitting direction d from point p (normal n
 * for area lights), choice excluded, for the lanes in m (the others: 0). For lights at infinity, d is the
 * direction of travel. */
static inline void light_emission_pdf_lanes(const SceneData* sc, __constant const LightTransportHeader* lt, LaneU index,
                                            Lane3 p, Lane3 n, Lane3 d, LaneI m, LaneF* pdf_pos, LaneF* pdf_dir) {
  /* Each type's fields only where a lane has that type: one lane reads what its light needs. */
  __global const Light* lights = sc->lights;
  LaneU at = lane_safe_index(index, m), type = lane_gather_uint(PC_FIELD_U(lights, type), at);
  float r = lt->bounds.w;
  *pdf_pos = *pdf_dir = (LaneF)(0.0f);
#ifdef PC_HAS_AREA_LIGHTS
  LaneI area = m & (type == PC_LIGHT_AREA);
  if (pc_any_(area)) {
    LaneF pos = 1.0f / lane_gather_float(PC_FIELD_F(lights, area), at);
#ifdef PC_HAS_SPHERES
    Lane3 a, b, c;
    LaneI sphere;
    gather_primitive_shapes(sc->prims, lane_gather_uint(PC_FIELD_U(lights, slot), at), area, &a, &b, &c, &sphere);
    pos = select(pos, 1.0f / (4.0f * PC_PI * b.x * b.x), sphere);
#endif
    LaneU prim = lane_safe_index(lane_gather_uint(PC_FIELD_U(lights, prim), at), area);
    LaneU flags = lane_gather_uint(PC_FIELD_U(sc->shading, flags), prim);
    *pdf_pos = select(*pdf_pos, pos, area);
    *pdf_dir = select(*pdf_dir, area_emission_pdf_dir(flags, n, d), area);
  }
#endif
#ifdef PC_HAS_POINT_LIGHTS
  LaneI point = m & (type == PC_LIGHT_POINT), spot = m & (type == PC_LIGHT_SPOT);
  *pdf_pos = select(*pdf_pos, (LaneF)(1.0f), point | spot);
  *pdf_dir = select(*pdf_dir, (LaneF)(0.25f * PC_INV_PI), point);
  if (pc_any_(spot)) {
    Lane3 axis = lane3(lane_gather_float(PC_FIELD_AT(lights, direction, 0), at), lane_gather_float(PC_FIELD_AT(lights, direction, 1), at),
                       lane_gather_float(PC_FIELD_AT(lights, direction, 2), at));
    LaneF cos_outer = lane_gather_float(PC_FIELD_F(lights, cos_outer), at);
    LaneF cone = select((LaneF)(0.0f), 1.0f / (2.0f * PC_PI * (1.0f - cos_outer)), pc_dot(axis, d) >= cos_outer);
    *pdf_dir = select(*pdf_dir, cone, spot);
  }
#endif
#ifdef PC_HAS_DIRECTIONAL_LIGHTS
  LaneI directional = m & (type == PC_LIGHT_DIRECTIONAL);
  *pdf_pos = select(*pdf_pos, (LaneF)(1.0f / (PC_PI * r * r)), directional);
  *pdf_dir = select(*pdf_dir, (LaneF)(1.0f), directional);
#endif
#ifdef PC_HAS_ENVIRONMENT
  LaneI env = m & (type == PC_LIGHT_ENVIRONMENT);
  if (pc_any_(env)) {
    *pdf_pos = select(*pdf_pos, (LaneF)(1.0f / (PC_PI * r * r)), env);
    *pdf_dir = select(*pdf_dir, env_pdf_lanes(lights[sc->h->env_light], sc->textures, sc->env_dist, lane3_neg(d), env), env);
  }
#endif
}

#if PC_LANES == 1
/* light_emission_pdf_lanes of one lane (the sampling tests' kernels). */
static inline void light_emission_pdf(const SceneData* sc, __constant const LightTransportHeader* lt, uint index, float3 p,
                                      float3 n, float3 d, float* pdf_pos, float* pdf_dir) {
  light_emission_pdf_lanes(sc, lt, index, p, n, d, 1, pdf_pos, pdf_dir);
}
#endif

/* Samples the start of a light path: u_choice chooses the light, u_pos.xy the point (u_pos.z the side of a
 * two-sided emitter), u_dir the direction. False when nothing is emitted. */
static inline bool sample_emission(const SceneData* sc, __constant const LightTransportHeader* lt,
                                   __global const float* emission_cdf, float u_choice, float3 u_pos, float2 u_dir,
                                   EmissionSample* out) {
  uint index = find_interval(emission_cdf, lt->light_count, u_choice);
  Light light = sc->lights[index];
  out->light = index;
  out->pdf_choice = emission_choice_pdf(emission_cdf, index);
  out->prim = PC_INVALID;
  out->p_err = (float3)(0.0f);
  out->delta_pos = false;
  out->delta_dir = false;
  out->Le = light.emission.xyz;
  float3 c = lt->bounds.xyz;
  float r = lt->bounds.w;
  switch (light.type) {
#ifdef PC_HAS_AREA_LIGHTS
    case PC_LIGHT_AREA: {
      Primitive prim = sc->prims[light.slot];
      uint flags = sc->shading[light.prim].flags;
      out->prim = light.prim;
#ifdef PC_HAS_SPHERES
      if (prim_kind_of(prim) == PC_PRIM_SPHERE) {
        float3 sc_c = prim.a.xyz;
        float rad = prim.b.x;
        out->p = sc_c + rad * sample_uniform_sphere(u_pos.xy);
        out->p_err = error_gamma(5) * fabs(out->p - sc_c) + error_gamma(1) * fabs(out->p);
        out->n = sphere_normal(prim, out->p, flags);
        out->pdf_pos = 1.0f / (4.0f * PC_PI * rad * rad);
      } else
#endif
      {
        float2 b = sample_uniform_triangle(u_pos.xy);
        float3 pa = b.x * prim.a.xyz, pb = b.y * prim.b.xyz, pc = (1.0f - b.x - b.y) * prim.c.xyz;
        out->p = pa + pb + pc;
        out->p_err = error_gamma(7) * (fabs(pa) + fabs(pb) + fabs(pc));
        out->n = triangle_normal(prim);
        out->pdf_pos = 1.0f / light.area;
      }
      /* Two-sided emitters: either side with probability 1/2. */
      if ((flags & PC_FLAG_TWO_SIDED) && u_pos.z < 0.5f) out->n = -out->n;
      float3 t, bt, w = sample_cosine_hemisphere(u_dir);
      make_frame(out->n, &t, &bt);
      out->d = pc_normalize(w.x * t + w.y * bt + w.z * out->n);
      out->pdf_dir = area_emission_pdf_dir(flags, out->n, out->d);
      break;
    }
#endif
#ifdef PC_HAS_POINT_LIGHTS
    case PC_LIGHT_POINT:
    case PC_LIGHT_SPOT:
      out->p = light.position.xyz;
      out->pdf_pos = 1.0f;
      out->delta_pos = true;
      if (light.type == PC_LIGHT_POINT) {
        out->d = sample_uniform_sphere(u_dir);
        out->pdf_dir = 0.25f * PC_INV_PI;
      } else {
        float3 t, bt, a = light.direction.xyz, w = sample_uniform_cone(u_dir, light.cos_outer);
        make_frame(a, &t, &bt);
        out->d = pc_normalize(w.x * t + w.y * bt + w.z * a);
        out->pdf_dir = uniform_cone_pdf(light.cos_outer);
        out->Le *= spot_falloff(light, out->d);
      }
      out->n = out->d;
      break;
#endif
#ifdef PC_HAS_DIRECTIONAL_LIGHTS
    case PC_LIGHT_DIRECTIONAL:
      out->d = light.direction.xyz;
      out->p = sample_disk_facing(c - r * out->d, r, out->d, u_pos.xy);
      out->n = out->d;
      out->pdf_pos = 1.0f / (PC_PI * r * r);
      out->pdf_dir = 1.0f;
      out->delta_dir = true;
      break;
#endif
#ifdef PC_HAS_ENVIRONMENT
    case PC_LIGHT_ENVIRONMENT: {
      float pdf;
      float3 towards = env_sample(light, sc->textures, sc->texels, sc->env_dist, u_dir, &pdf, &out->Le);
      out->d = -towards;
      out->p = sample_disk_facing(c - r * out->d, r, out->d, u_pos.xy);
      out->n = out->d;
      out->pdf_pos = 1.0f / (PC_PI * r * r);
      out->pdf_dir = pdf;
      break;
    }
#endif
    default:
      return false;
  }
  return out->pdf_choice > 0.0f && out->pdf_pos > 0.0f && out->pdf_dir > 0.0f && isfinite(out->pdf_dir) &&
         (out->Le.x > 0.0f || out->Le.y > 0.0f || out->Le.z > 0.0f);
}

/* The light path's initial throughput: Le |cos| / (choice pos dir) (the cosine of area lights only). */
static inline float3 emission_weight(const EmissionSample* e) {
  float cos_term = e->delta_pos || e->delta_dir ? 1.0f : fabs(pc_dot(e->n, e->d));
  return e->Le * (cos_term / (e->pdf_choice * e->pdf_pos * e->pdf_dir));
}

#endif
