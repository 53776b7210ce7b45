/* Lambertian reflection. Local frame (normal +z), wo.z > 0 (bsdf.cl mirrors back-side hits). */
#ifndef PATHCL_BSDF_DIFFUSE_CL
#define PATHCL_BSDF_DIFFUSE_CL

/* Test builds only (RenderOptions::debug_bias_diffuse): a 1 % error that `pathcl bench`'s gate must catch. */
#ifdef PC_DEBUG_BIAS_DIFFUSE
#define PC_DIFFUSE_SCALE 1.01f
#else
#define PC_DIFFUSE_SCALE 1.0f
#endif

inline float3 diffuse_eval(Material m, float3 wo, float3 wi) {
  return wi.z > 0.0f ? m.color.xyz * PC_DIFFUSE_SCALE * PC_INV_PI : (float3)(0.0f);
}

inline float diffuse_pdf(Material m, float3 wo, float3 wi) { return fmax(wi.z, 0.0f) * PC_INV_PI; }

/* Cosine-weighted wi; weight = f cos / pdf = reflectance. */
inline bool diffuse_sample(Material m, float3 wo, float3 u, BsdfSample* s) {
  s->wi = sample_cosine_hemisphere(u.xy);
  s->pdf = diffuse_pdf(m, wo, s->wi);
  s->weight = m.color.xyz * PC_DIFFUSE_SCALE;
  s->delta = false;
  return s->pdf > 0.0f;
}

#endif
