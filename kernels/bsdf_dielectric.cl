/* Smooth glass: exact Fresnel reflectance chooses between mirror reflection and refraction; total
 * internal reflection past the critical angle. The front side (normal +z) faces the outside medium
 * (index 1), the back the inside (index ior). Radiance crossing into a denser medium is concentrated
 * by (n_i / n_t)^2 (pbrt's radiance transport mode); `color` tints transmission. */
#ifndef PATHCL_BSDF_DIELECTRIC_CL
#define PATHCL_BSDF_DIELECTRIC_CL

inline float3 dielectric_eval(Material m, float3 wo, float3 wi) { return (float3)(0.0f); }
inline float dielectric_pdf(Material m, float3 wo, float3 wi) { return 0.0f; }

inline bool dielectric_sample(Material m, float3 wo, float3 u, BsdfSample* s) {
  bool entering = wo.z > 0.0f;
  float eta = entering ? m.ior : 1.0f / m.ior; /* n_t / n_i */
  float f = fresnel_dielectric(fabs(wo.z), eta);
  s->delta = true;
  if (u.z < f) {
    s->wi = reflect_local(wo);
    s->weight = (float3)(1.0f);
    s->pdf = f;
    return true;
  }
  float3 n = (float3)(0.0f, 0.0f, entering ? 1.0f : -1.0f);
  if (!refract_dir(wo, n, eta, &s->wi)) return false; /* unreachable: f == 1 there */
  s->weight = m.color.xyz / (eta * eta);
  s->eta2 = eta * eta;
  s->pdf = 1.0f - f;
  return true;
}

#endif
