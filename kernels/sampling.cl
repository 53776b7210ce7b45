/* Warps from the unit square to directions and points. */
#ifndef PATHCL_SAMPLING_CL
#define PATHCL_SAMPLING_CL

/* The warps over lanes (F float for one lane, float8/float16 for a lane-generic kernel, issue 15): each
 * written once, every lane doing the one-lane operations (branches as per-lane selects), so the points
 * are the same bits at every lane width (tests/camera_sampling_test.cpp). The float2/float3 functions
 * below are their one-lane instances. */
#define PC_SAMPLING_LANES(F, I)                                                                           \
  /* A point on the unit disk, area-preserving (Shirley and Chiu's concentric map). */                   \
  inline PC_OVL void sample_concentric_disk_lanes(F ux, F uy, F* x, F* y) {                               \
    F ox = 2.0f * ux - 1.0f, oy = 2.0f * uy - 1.0f;                                                       \
    I centre = (ox == 0.0f) & (oy == 0.0f), x_major = fabs(ox) > fabs(oy);                                \
    F r = select(oy, ox, x_major);                                                                        \
    F phi = select((PC_PI / 2.0f) - (PC_PI / 4.0f) * (ox / oy), (PC_PI / 4.0f) * (oy / ox), x_major);     \
    F c, s = pc_sincos(phi, &c);                                                                          \
    *x = select(r * c, (F)(0.0f), centre);                                                                \
    *y = select(r * s, (F)(0.0f), centre);                                                                \
  }                                                                                                       \
  /* Cosine-weighted direction about +z (Malley's method). */                                            \
  inline PC_OVL void sample_cosine_hemisphere_lanes(F ux, F uy, F* x, F* y, F* z) {                       \
    sample_concentric_disk_lanes(ux, uy, x, y);                                                           \
    *z = sqrt(fmax(0.0f, 1.0f - *x * *x - *y * *y));                                                      \
  }                                                                                                       \
  inline PC_OVL void sample_uniform_sphere_lanes(F ux, F uy, F* x, F* y, F* z) {                          \
    *z = 1.0f - 2.0f * ux;                                                                                \
    F r = sqrt(fmax(0.0f, 1.0f - *z * *z));                                                               \
    F phi = 2.0f * PC_PI * uy;                                                                            \
    F c, s = pc_sincos(phi, &c);                                                                          \
    *x = r * c;                                                                                           \
    *y = r * s;                                                                                           \
  }                                                                                                       \
  /* Uniform barycentrics over a triangle: weights of vertices a, b (c gets the rest). */                \
  inline PC_OVL void sample_uniform_triangle_lanes(F ux, F uy, F* a, F* b) {                              \
    F su = sqrt(ux);                                                                                      \
    *a = 1.0f - su;                                                                                       \
    *b = uy * su;                                                                                         \
  }
PC_SAMPLING_LANES(float, int)
PC_SAMPLING_LANES(float8, int8)
PC_SAMPLING_LANES(float16, int16)
#undef PC_SAMPLING_LANES

inline float2 sample_concentric_disk(float2 u) {
  float x, y;
  sample_concentric_disk_lanes(u.x, u.y, &x, &y);
  return (float2)(x, y);
}

inline float3 sample_cosine_hemisphere(float2 u) {
  float x, y, z;
  sample_cosine_hemisphere_lanes(u.x, u.y, &x, &y, &z);
  return (float3)(x, y, z);
}

inline float3 sample_uniform_sphere(float2 u) {
  float x, y, z;
  sample_uniform_sphere_lanes(u.x, u.y, &x, &y, &z);
  return (float3)(x, y, z);
}

inline float2 sample_uniform_triangle(float2 u) {
  float a, b;
  sample_uniform_triangle_lanes(u.x, u.y, &a, &b);
  return (float2)(a, b);
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
