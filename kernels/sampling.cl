/* Warps from the unit square to directions and points. */
#ifndef PATHCL_SAMPLING_CL
#define PATHCL_SAMPLING_CL

/* A point on the unit disk, area-preserving (Shirley and Chiu's concentric map). */
inline float2 sample_concentric_disk(float2 u) {
  float2 o = 2.0f * u - 1.0f;
  if (o.x == 0.0f && o.y == 0.0f) return (float2)(0.0f);
  float r, phi;
  if (fabs(o.x) > fabs(o.y)) {
    r = o.x;
    phi = (PC_PI / 4.0f) * (o.y / o.x);
  } else {
    r = o.y;
    phi = (PC_PI / 2.0f) - (PC_PI / 4.0f) * (o.x / o.y);
  }
  float c, s = pc_sincos(phi, &c);
  return (float2)(r * c, r * s);
}

/* Cosine-weighted direction about +z (Malley's method). */
inline float3 sample_cosine_hemisphere(float2 u) {
  float2 d = sample_concentric_disk(u);
  return (float3)(d.x, d.y, sqrt(fmax(0.0f, 1.0f - d.x * d.x - d.y * d.y)));
}

inline float3 sample_uniform_sphere(float2 u) {
  float z = 1.0f - 2.0f * u.x;
  float r = sqrt(fmax(0.0f, 1.0f - z * z));
  float phi = 2.0f * PC_PI * u.y;
  float c, s = pc_sincos(phi, &c);
  return (float3)(r * c, r * s, z);
}

/* Uniform barycentrics over a triangle: weights of vertices a, b (c gets the rest). */
inline float2 sample_uniform_triangle(float2 u) {
  float su = sqrt(u.x);
  return (float2)(1.0f - su, u.y * su);
}

/* Index i with cdf[i] <= u < cdf[i + 1], over count intervals (binary search of a cdf). */
inline uint find_interval(__global const float* cdf, uint count, float u) {
  uint lo = 0, hi = count;
  while (hi - lo > 1) {
    uint mid = (lo + hi) / 2;
    if (cdf[mid] <= u) lo = mid; else hi = mid;
  }
  return lo;
}

#endif
