/* Warps from the unit square to directions and points. */
#ifndef PATHCL_SAMPLING_CL
#define PATHCL_SAMPLING_CL

/* Cosine-weighted direction about +z (Malley's method via the concentric disk map). */
inline float3 sample_cosine_hemisphere(float2 u) {
  float2 o = 2.0f * u - 1.0f;
  float r, phi;
  if (o.x == 0.0f && o.y == 0.0f) return (float3)(0.0f, 0.0f, 1.0f);
  if (fabs(o.x) > fabs(o.y)) {
    r = o.x;
    phi = (PC_PI / 4.0f) * (o.y / o.x);
  } else {
    r = o.y;
    phi = (PC_PI / 2.0f) - (PC_PI / 4.0f) * (o.x / o.y);
  }
  float x = r * cos(phi), y = r * sin(phi);
  return (float3)(x, y, sqrt(fmax(0.0f, 1.0f - x * x - y * y)));
}

inline float3 sample_uniform_sphere(float2 u) {
  float z = 1.0f - 2.0f * u.x;
  float r = sqrt(fmax(0.0f, 1.0f - z * z));
  float phi = 2.0f * PC_PI * u.y;
  return (float3)(r * cos(phi), r * sin(phi), z);
}

/* Uniform barycentrics over a triangle: weights of vertices a, b (c gets the rest). */
inline float2 sample_uniform_triangle(float2 u) {
  float su = sqrt(u.x);
  return (float2)(1.0f - su, u.y * su);
}

#endif
