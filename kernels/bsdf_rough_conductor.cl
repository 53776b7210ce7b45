/* Rough metal: GGX microfacet reflection with the conductor Fresnel term (complex index eta + i k per
 * channel; a "specular" colour is turned into eta = 1 and the k that reflects it at normal incidence),
 * sampled by visible normals. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_ROUGH_CONDUCTOR_CL
#define PATHCL_BSDF_ROUGH_CONDUCTOR_CL

inline float3 rough_conductor_eval(Material m, float3 wo, float3 wi) {
  if (wi.z <= 0.0f || wo.z <= 0.0f) return (float3)(0.0f);
  float3 h = pc_normalize(wo + wi);
  float3 f = fresnel_conductor(pc_dot(wo, h), m.specular.xyz, m.k.xyz);
  return f * (ggx_d(h, m.alpha) * ggx_g2(wo, wi, m.alpha) / (4.0f * wo.z * wi.z));
}

inline float rough_conductor_pdf(Material m, float3 wo, float3 wi) { return ggx_reflection_pdf(wo, wi, m.alpha); }

inline bool rough_conductor_sample(Material m, float3 wo, float3 u, BsdfSample* s) {
  float3 h = ggx_sample_visible(wo, m.alpha, u.xy);
  s->wi = reflect_about(wo, h);
  s->delta = false;
  if (s->wi.z <= 0.0f) return false;
  s->pdf = rough_conductor_pdf(m, wo, s->wi);
  if (!(s->pdf > 0.0f)) return false;
  s->weight = rough_conductor_eval(m, wo, s->wi) * (s->wi.z / s->pdf);
  return true;
}

#endif
