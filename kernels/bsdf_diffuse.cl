/* Lambertian reflection, on both sides of the surface. n is the shading normal turned towards wo. */
#ifndef PATHCL_BSDF_DIFFUSE_CL
#define PATHCL_BSDF_DIFFUSE_CL

inline float3 diffuse_eval(Material m, float3 n, float3 wo, float3 wi) {
  return dot(n, wi) > 0.0f ? m.reflectance.xyz * PC_INV_PI : (float3)(0.0f);
}

inline float diffuse_pdf(float3 n, float3 wo, float3 wi) { return fmax(dot(n, wi), 0.0f) * PC_INV_PI; }

/* Cosine-weighted wi; *weight = f cos / pdf = reflectance. */
inline bool diffuse_sample(Material m, float3 n, float3 wo, float2 u, float3* wi, float3* weight, float* pdf) {
  float3 t, b;
  make_frame(n, &t, &b);
  float3 h = sample_cosine_hemisphere(u); /* in the frame (t, b, n) */
  *wi = normalize(h.x * t + h.y * b + h.z * n);
  *pdf = diffuse_pdf(n, wo, *wi);
  *weight = m.reflectance.xyz;
  return *pdf > 0.0f;
}

#endif
