/* Warps from the unit square to directions and points. */
#ifndef PATHCL_SAMPLING_CL
#define PATHCL_SAMPLING_CL

/* The warps over lanes (F float for one lane, float8/float16 for a lane-generic kernel, issue 15): each
 * written once, every lane doing the one-lane operations (branches as per-lane selects), so the points
 * are the same bits at every lane width (tests/camera_sampling_test.cpp). The float2/float3 functions
 * below are their one-lane instances. */
#define PC_LANE_W 1
#include "templates/sampling.cl"
#define PC_LANE_W 8
#include "templates/sampling.cl"
#define PC_LANE_W 16
#include "templates/sampling.cl"

static inline float2 sample_concentric_disk(float2 u) {
  float x, y;
  sample_concentric_disk_lanes(u.x, u.y, &x, &y);
  return (float2)(x, y);
}

static inline float3 sample_cosine_hemisphere(float2 u) {
  float x, y, z;
  sample_cosine_hemisphere_lanes(u.x, u.y, &x, &y, &z);
  return (float3)(x, y, z);
}

static inline float3 sample_uniform_sphere(float2 u) {
  float x, y, z;
  sample_uniform_sphere_lanes(u.x, u.y, &x, &y, &z);
  return (float3)(x, y, z);
}

static inline float2 sample_uniform_triangle(float2 u) {
  float a, b;
  sample_uniform_triangle_lanes(u.x, u.y, &a, &b);
  return (float2)(a, b);
}

/* Index i with cdf[i] <= u < cdf[i + 1], over count intervals (binary search of a cdf). */
static inline uint find_interval(__global const float* cdf, uint count, float u) {
  uint lo = 0, hi = count;
  while (hi - lo > 1) {
    uint mid = (lo + hi) / 2;
    if (cdf[mid] <= u) lo = mid; else hi = mid;
  }
  return lo;
}

#endif
