/* Normalised modified Phong (Lafortune and Willems 1994): a Lambertian lobe plus
 * specular (n + 2) / (2 pi) cos^n(angle between wi and the mirror direction of wo). The host keeps
 * diffuse + specular <= 1 per channel; the specular lobe's albedo is at most `specular` (equal at
 * normal incidence), so energy never exceeds 1. Sampling picks a lobe in proportion to luminance, then
 * cosine-weighted or cos^n about the mirror direction. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_PHONG_CL
#define PATHCL_BSDF_PHONG_CL

inline float phong_specular_probability(Material m) {
  float d = luminance(m.color.xyz), s = luminance(m.specular.xyz);
  return d + s > 0.0f ? s / (d + s) : 0.0f;
}

inline float phong_cos_alpha(float3 wo, float3 wi) { return pc_dot(reflect_local(wo), wi); }

inline float3 phong_eval(Material m, float3 wo, float3 wi) {
  if (wi.z <= 0.0f || wo.z <= 0.0f) return (float3)(0.0f);
  float c = phong_cos_alpha(wo, wi);
  float spec = c > 0.0f ? (m.exponent + 2.0f) * (0.5f * PC_INV_PI) * pc_powr(c, m.exponent) : 0.0f;
  return m.color.xyz * PC_INV_PI + m.specular.xyz * spec;
}

inline float phong_pdf(Material m, float3 wo, float3 wi) {
  if (wi.z <= 0.0f || wo.z <= 0.0f) return 0.0f;
  float ps = phong_specular_probability(m);
  float c = phong_cos_alpha(wo, wi);
  float lobe = c > 0.0f ? (m.exponent + 1.0f) * (0.5f * PC_INV_PI) * pc_powr(c, m.exponent) : 0.0f;
  return (1.0f - ps) * wi.z * PC_INV_PI + ps * lobe;
}

inline bool phong_sample(Material m, float3 wo, float3 u, BsdfSample* s) {
  s->delta = false;
  if (u.z < phong_specular_probability(m)) {
    /* cos^n lobe about the mirror direction: cos(alpha) = u^(1 / (n + 1)). */
    float cos_a = pc_powr(u.x, 1.0f / (m.exponent + 1.0f));
    float sin_a = sqrt(fmax(0.0f, 1.0f - cos_a * cos_a));
    float phi = 2.0f * PC_PI * u.y;
    float3 r = reflect_local(wo), t, b;
    make_frame(r, &t, &b);
    float cos_phi, sin_phi = pc_sincos(phi, &cos_phi);
    s->wi = pc_normalize(sin_a * cos_phi * t + sin_a * sin_phi * b + cos_a * r);
  } else {
    s->wi = sample_cosine_hemisphere(u.xy);
  }
  s->pdf = phong_pdf(m, wo, s->wi);
  if (!(s->pdf > 0.0f)) return false;
  s->weight = phong_eval(m, wo, s->wi) * (s->wi.z / s->pdf);
  return true;
}

#endif
