/* The qualitative Oren-Nayar model of rough diffuse reflection (pbrt-v3), sampled like Lambert.
 * sigma (radians) is the spread of facet slopes; sigma = 0 is Lambertian. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_OREN_NAYAR_CL
#define PATHCL_BSDF_OREN_NAYAR_CL

inline float3 oren_nayar_eval(Material m, float3 wo, float3 wi) {
  if (wi.z <= 0.0f || wo.z <= 0.0f) return (float3)(0.0f);
  float s2 = m.sigma * m.sigma;
  float a = 1.0f - s2 / (2.0f * (s2 + 0.33f));
  float b = 0.45f * s2 / (s2 + 0.09f);
  float sin_i = sqrt(fmax(0.0f, 1.0f - wi.z * wi.z)), sin_o = sqrt(fmax(0.0f, 1.0f - wo.z * wo.z));
  /* cos(phi_i - phi_o), only where both azimuths are defined. */
  float max_cos = 0.0f;
  if (sin_i > 1e-4f && sin_o > 1e-4f)
    max_cos = fmax(0.0f, clamp((wi.x * wo.x + wi.y * wo.y) / (sin_i * sin_o), -1.0f, 1.0f));
  /* alpha = max(theta_i, theta_o), beta = min: tan(beta) uses the larger cosine, never 0 here. */
  float sin_alpha, tan_beta;
  if (wi.z > wo.z) {
    sin_alpha = sin_o;
    tan_beta = sin_i / wi.z;
  } else {
    sin_alpha = sin_i;
    tan_beta = sin_o / wo.z;
  }
  return m.color.xyz * PC_INV_PI * (a + b * max_cos * sin_alpha * tan_beta);
}

inline float oren_nayar_pdf(Material m, float3 wo, float3 wi) { return fmax(wi.z, 0.0f) * PC_INV_PI; }

inline bool oren_nayar_sample(Material m, float3 wo, float3 u, BsdfSample* s) {
  s->wi = sample_cosine_hemisphere(u.xy);
  s->pdf = oren_nayar_pdf(m, wo, s->wi);
  s->delta = false;
  if (!(s->pdf > 0.0f)) return false;
  s->weight = oren_nayar_eval(m, wo, s->wi) * (s->wi.z / s->pdf);
  return true;
}

#endif
