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

/* Radiance from light point y with normal ny towards x. */
inline float3 emitted_towards(float3 emission, uint flags, float3 ny, float3 y, float3 x) {
  return ((flags & PC_FLAG_TWO_SIDED) || pc_dot(ny, x - y) > 0.0f) ? emission : (float3)(0.0f);
}

/* From inside (or on) a sphere every point is visible and area sampling is used. The tolerance keeps
 * points on the surface itself on the inside branch in both sampling and pdf evaluation. */
inline bool sphere_sampled_by_area(float3 x, float3 c, float r) {
  float3 d = x - c;
  return pc_dot(d, d) <= r * r * 1.0001f;
}

/* 1 - cos(theta_max) of the cone a sphere subtends, accurate for small cones. */
inline float sphere_cone_one_minus_cos(float sin2_max) {
  return sin2_max < 0.00068523f ? 0.5f * sin2_max : 1.0f - sqrt(fmax(0.0f, 1.0f - sin2_max));
}

inline float area_to_solid_angle(float3 x, float3 y, float3 ny, float area_pdf) {
  float3 d = y - x;
  float dist2 = pc_dot(d, d);
  float cos_y = fabs(pc_dot(ny, d)) / sqrt(dist2);
  return cos_y > 0.0f ? area_pdf * dist2 / cos_y : 0.0f;
}

inline float triangle_light_pdf(Light light, float3 x, float3 y, float3 ny) {
  return area_to_solid_angle(x, y, ny, 1.0f / light.area);
}

inline float sphere_light_pdf(Primitive sp, float3 x, float3 y, float3 ny) {
  float3 c = sp.a.xyz;
  float r = sp.b.x;
  if (sphere_sampled_by_area(x, c, r)) return area_to_solid_angle(x, y, ny, 1.0f / (4.0f * PC_PI * r * r));
  float3 d = c - x;
  float sin2_max = r * r / pc_dot(d, d);
  return 1.0f / (2.0f * PC_PI * sphere_cone_one_minus_cos(sin2_max));
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

/* A point on the sphere seen from x inside the cone it subtends (pbrt-v4's construction). */
inline float3 sample_sphere_cone(Primitive sp, float3 x, float2 u, float* pdf) {
  float3 c = sp.a.xyz;
  float r = sp.b.x;
  float3 d = x - c;
  float dc2 = pc_dot(d, d), dc = sqrt(dc2);
  float sin2_max = r * r / dc2;
  float one_minus_cos_max = sphere_cone_one_minus_cos(sin2_max);
  float cos_theta = 1.0f - u.x * one_minus_cos_max;
  float sin2_theta = 1.0f - cos_theta * cos_theta;
  if (sin2_max < 0.00068523f) { /* small cone: avoid cancellation */
    sin2_theta = sin2_max * u.x;
    cos_theta = sqrt(1.0f - sin2_theta);
  }
  /* Angle alpha at the centre between the direction to x and the sampled point. */
  float cos_alpha = sin2_theta / sqrt(sin2_max) + cos_theta * sqrt(fmax(0.0f, 1.0f - sin2_theta / sin2_max));
  float sin_alpha = sqrt(fmax(0.0f, 1.0f - cos_alpha * cos_alpha));
  float phi = 2.0f * PC_PI * u.y;
  float3 w = d / dc, t, b;
  make_frame(w, &t, &b);
  *pdf = 1.0f / (2.0f * PC_PI * one_minus_cos_max);
  float cos_phi, sin_phi = pc_sincos(phi, &cos_phi);
  return c + r * (cos_alpha * w + sin_alpha * (cos_phi * t + sin_phi * b));
}

inline void sample_area_light(Light light, float choice, __global const Primitive* prims,
                              __global const PrimShading* shading, float3 x, float2 u, LightSample* out) {
  Primitive p = prims[light.slot];
  uint flags = shading[light.prim].flags;
  float pdf;
  float3 ny;
#ifdef PC_HAS_SPHERES
  if (prim_kind_of(p) == PC_PRIM_SPHERE) {
    float3 c = p.a.xyz;
    float r = p.b.x;
    if (sphere_sampled_by_area(x, c, r)) {
      out->p = c + r * sample_uniform_sphere(u);
      ny = sphere_normal(p, out->p, flags);
      pdf = area_to_solid_angle(x, out->p, ny, 1.0f / (4.0f * PC_PI * r * r));
    } else {
      out->p = sample_sphere_cone(p, x, u, &pdf);
      ny = sphere_normal(p, out->p, flags);
    }
    out->p_err = error_gamma(5) * fabs(out->p - c) + error_gamma(1) * fabs(out->p);
  } else
#endif
  {
    float2 b = sample_uniform_triangle(u);
    float3 pa = b.x * p.a.xyz, pb = b.y * p.b.xyz, pc = (1.0f - b.x - b.y) * p.c.xyz;
    out->p = pa + pb + pc;
    out->p_err = error_gamma(7) * (fabs(pa) + fabs(pb) + fabs(pc));
    ny = triangle_normal(p);
    pdf = triangle_light_pdf(light, x, out->p, ny);
  }
  out->n = ny;
  out->wi = pc_normalize(out->p - x);
  out->pdf = choice * pdf;
  out->Le = emitted_towards(light.emission.xyz, flags, ny, out->p, x);
}

/* Spot falloff: 1 inside the inner cone, 0 outside the outer one, smoothstep between (pbrt-v4). */
inline float spot_falloff(Light light, float3 from_light) {
  float c = pc_dot(light.direction.xyz, from_light);
  if (c >= light.cos_inner) return 1.0f;
  if (c <= light.cos_outer) return 0.0f;
  float t = (c - light.cos_outer) / (light.cos_inner - light.cos_outer);
  return t * t * (3.0f - 2.0f * t);
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
      float3 d = light.position.xyz - x;
      float dist2 = pc_dot(d, d);
      if (!(dist2 > 0.0f)) return false; /* the shading point is the light's position */
      out->p = light.position.xyz;
      out->wi = d / sqrt(dist2);
      out->n = -out->wi;
      out->Le = light.emission.xyz / dist2;
      if (light.type == PC_LIGHT_SPOT) out->Le *= spot_falloff(light, -out->wi);
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
