/* Plastic: a Lambertian base under a dielectric coat (index ior), smooth (alpha = 0: a delta reflection)
 * or rough (GGX). Light reaching the base passes the coat twice: the base lobe is scaled by
 * (1 - F(cos_o)) (1 - F(cos_i)); light reflected inside the coat is not returned, so energy never
 * exceeds 1. The coat lobe is chosen with probability F(cos_o) against (1 - F(cos_o)) times the base's
 * largest reflectance. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_PLASTIC_CL
#define PATHCL_BSDF_PLASTIC_CL

inline float plastic_coat_probability(Material m, float3 wo) {
  float f = fresnel_dielectric(wo.z, m.ior);
  float base = (1.0f - f) * max_component(m.color.xyz);
  return f + base > 0.0f ? f / (f + base) : 1.0f;
}

inline float3 plastic_base_eval(Material m, float3 wo, float3 wi) {
  return m.color.xyz * (PC_INV_PI * (1.0f - fresnel_dielectric(wo.z, m.ior)) * (1.0f - fresnel_dielectric(wi.z, m.ior)));
}

/* The non-delta part: the base, plus the rough coat. */
inline float3 plastic_eval(Material m, float3 wo, float3 wi) {
  if (wi.z <= 0.0f || wo.z <= 0.0f) return (float3)(0.0f);
  float3 f = plastic_base_eval(m, wo, wi);
  if (m.alpha > 0.0f) {
    float3 h = pc_normalize(wo + wi);
    f += fresnel_dielectric(pc_dot(wo, h), m.ior) * ggx_d(h, m.alpha) * ggx_g2(wo, wi, m.alpha) / (4.0f * wo.z * wi.z);
  }
  return f;
}

inline float plastic_pdf(Material m, float3 wo, float3 wi) {
  if (wi.z <= 0.0f || wo.z <= 0.0f) return 0.0f;
  float pc = plastic_coat_probability(m, wo);
  float pdf = (1.0f - pc) * wi.z * PC_INV_PI;
  if (m.alpha > 0.0f) pdf += pc * ggx_reflection_pdf(wo, wi, m.alpha);
  return pdf;
}

inline bool plastic_sample(Material m, float3 wo, float3 u, BsdfSample* s) {
  float pc = plastic_coat_probability(m, wo);
  bool coat = u.z < pc;
  s->delta = coat && m.alpha == 0.0f;
  if (s->delta) {
    s->wi = reflect_local(wo);
    s->pdf = pc;
    s->weight = (float3)(fresnel_dielectric(wo.z, m.ior) / pc);
    return true;
  }
  s->wi = coat ? reflect_about(wo, ggx_sample_visible(wo, m.alpha, u.xy)) : sample_cosine_hemisphere(u.xy);
  if (s->wi.z <= 0.0f) return false;
  s->pdf = plastic_pdf(m, wo, s->wi);
  if (!(s->pdf > 0.0f)) return false;
  s->weight = plastic_eval(m, wo, s->wi) * (s->wi.z / s->pdf);
  return true;
}

#endif
