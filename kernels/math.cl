/* Small math helpers shared by every kernel. */
#ifndef PATHCL_MATH_CL
#define PATHCL_MATH_CL

#include "exact_math.cl"

#define PC_PI 3.14159265358979323846f
#define PC_INV_PI 0.31830988618379067154f
#define PC_MACHINE_EPSILON (FLT_EPSILON * 0.5f)

/* pbrt's gamma(n): bound on the relative error of n floating-point operations. */
inline float error_gamma(int n) { return (n * PC_MACHINE_EPSILON) / (1.0f - n * PC_MACHINE_EPSILON); }

inline float max_component(float3 v) { return fmax(v.x, fmax(v.y, v.z)); }
inline float luminance(float3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

/* An orthonormal basis around unit n (Duff et al. 2017). */
inline void make_frame(float3 n, float3* t, float3* b) {
  float s = n.z >= 0.0f ? 1.0f : -1.0f;
  float a = -1.0f / (s + n.z);
  float c = n.x * n.y * a;
  *t = (float3)(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
  *b = (float3)(c, s + n.y * n.y * a, -n.y);
}

/* Moves p off the surface with normal n, by the error bound err, to the side of direction w, and rounds
 * away from the surface (pbrt-v4 OffsetRayOrigin), so a spawned ray cannot re-hit the surface it left. */
inline float3 offset_ray_origin(float3 p, float3 err, float3 n, float3 w) {
  float d = pc_dot(fabs(n), err);
  float3 offset = d * n;
  if (pc_dot(w, n) < 0.0f) offset = -offset;
  float3 po = p + offset;
  po.x = offset.x > 0.0f ? nextafter(po.x, INFINITY) : offset.x < 0.0f ? nextafter(po.x, -INFINITY) : po.x;
  po.y = offset.y > 0.0f ? nextafter(po.y, INFINITY) : offset.y < 0.0f ? nextafter(po.y, -INFINITY) : po.y;
  po.z = offset.z > 0.0f ? nextafter(po.z, INFINITY) : offset.z < 0.0f ? nextafter(po.z, -INFINITY) : po.z;
  return po;
}

inline float power_heuristic(float pdf_a, float pdf_b) {
  float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  if (a + b > 0.0f && isfinite(a + b)) return a / (a + b);
  /* The squares overflowed (a light sampled from 1e18 away has a pdf of 1e36: inf / inf was NaN) or
   * underflowed: the same weight from the ratio of the pdfs. */
  if (!(pdf_a > 0.0f)) return 0.0f;
  float r = pdf_b / pdf_a;
  return 1.0f / (1.0f + r * r);
}

#endif
