/* Area lights: choosing one in proportion to power, sampling a point on it, and the matching pdf for
 * multiple importance sampling. Triangles are sampled uniformly by area; spheres by the cone of
 * directions they subtend, or by area from inside. */
#ifndef PATHCL_LIGHTS_CL
#define PATHCL_LIGHTS_CL

typedef struct {
  float3 p;   /* point on the light */
  float3 p_err; /* bound on the rounding error of p */
  float3 n;   /* the light's geometric normal at p */
  float3 Le;  /* radiance leaving it towards the shading point (0 when its back faces the point) */
  float pdf;  /* solid-angle density at the shading point, light choice included */
} LightSample;

/* Index i with cdf[i] <= u < cdf[i + 1]. */
inline uint choose_light(__global const float* cdf, uint count, float u) {
  uint lo = 0, hi = count;
  while (hi - lo > 1) {
    uint mid = (lo + hi) / 2;
    if (cdf[mid] <= u) lo = mid; else hi = mid;
  }
  return lo;
}

/* Radiance from light point y with normal ny towards x. */
inline float3 emitted_towards(float3 emission, uint flags, float3 ny, float3 y, float3 x) {
  return ((flags & PC_FLAG_TWO_SIDED) || dot(ny, x - y) > 0.0f) ? emission : (float3)(0.0f);
}

/* From inside (or on) a sphere every point is visible and area sampling is used. The tolerance keeps
 * points on the surface itself on the inside branch in both sampling and pdf evaluation. */
inline bool sphere_sampled_by_area(float3 x, float3 c, float r) {
  float3 d = x - c;
  return dot(d, d) <= r * r * 1.0001f;
}

/* 1 - cos(theta_max) of the cone a sphere subtends, accurate for small cones. */
inline float sphere_cone_one_minus_cos(float sin2_max) {
  return sin2_max < 0.00068523f ? 0.5f * sin2_max : 1.0f - sqrt(fmax(0.0f, 1.0f - sin2_max));
}

inline float area_to_solid_angle(float3 x, float3 y, float3 ny, float area_pdf) {
  float3 d = y - x;
  float dist2 = dot(d, d);
  float cos_y = fabs(dot(ny, d)) / sqrt(dist2);
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
  float sin2_max = r * r / dot(d, d);
  return 1.0f / (2.0f * PC_PI * sphere_cone_one_minus_cos(sin2_max));
}

/* Solid-angle pdf of reaching light point y (normal ny) from x, light choice included. */
inline float light_pdf(__global const Light* lights, __global const Primitive* prims, uint light_index, float3 x,
                       float3 y, float3 ny) {
  Light light = lights[light_index];
#ifdef PC_HAS_SPHERES
  Primitive p = prims[light.slot];
  if (prim_kind_of(p) == PC_PRIM_SPHERE) return light.select_pdf * sphere_light_pdf(p, x, y, ny);
#endif
  return light.select_pdf * triangle_light_pdf(light, x, y, ny);
}

/* A point on the sphere seen from x inside the cone it subtends (pbrt-v4's construction). */
inline float3 sample_sphere_cone(Primitive sp, float3 x, float2 u, float* pdf) {
  float3 c = sp.a.xyz;
  float r = sp.b.x;
  float3 d = x - c;
  float dc2 = dot(d, d), dc = sqrt(dc2);
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
  return c + r * (cos_alpha * w + sin_alpha * (cos(phi) * t + sin(phi) * b));
}

inline bool sample_light(__global const Light* lights, __global const float* cdf, uint light_count,
                         __global const Primitive* prims, __global const PrimShading* shading, float3 x,
                         float u_choose, float2 u, LightSample* out) {
  uint i = choose_light(cdf, light_count, u_choose);
  Light light = lights[i];
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
  out->pdf = light.select_pdf * pdf;
  out->Le = emitted_towards(light.emission.xyz, flags, ny, out->p, x);
  return out->pdf > 0.0f && isfinite(out->pdf) && (out->Le.x > 0.0f || out->Le.y > 0.0f || out->Le.z > 0.0f);
}

#endif
