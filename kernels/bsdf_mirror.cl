/* A perfect mirror of the given reflectance: one delta lobe. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_MIRROR_CL
#define PATHCL_BSDF_MIRROR_CL

inline float3 mirror_eval(Material m, float3 wo, float3 wi) { return (float3)(0.0f); }
inline float mirror_pdf(Material m, float3 wo, float3 wi) { return 0.0f; }

inline bool mirror_sample(Material m, float3 wo, float3 u, BsdfSample* s) {
  s->wi = reflect_local(wo);
  s->weight = m.color.xyz;
  s->pdf = 1.0f;
  s->delta = true;
  return wo.z > 0.0f;
}

#endif
