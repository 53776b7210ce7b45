/* BSDFs by material type, each in its own file with the *_eval / *_pdf / *_sample triad, and the
 * dispatch over them. Everything here works in the local shading frame: the shading normal's front side
 * is +z. Only the dielectric tells the two sides apart (outside = front); every other material reflects
 * the same on both sides, so a back-side wo is mirrored to the front and the result mirrored back.
 * eval returns f (without the cosine); delta lobes are not in eval or pdf, only in sample. */
#ifndef PATHCL_BSDF_CL
#define PATHCL_BSDF_CL

typedef struct {
  float3 wi;     /* local frame */
  float3 weight; /* f cos / pdf: the factor the path throughput takes */
  float pdf;     /* solid-angle density; for a delta lobe the probability of having chosen it */
  bool delta;    /* wi came from a delta lobe: no light sampling can reach it, no MIS */
} BsdfSample;

#include "fresnel.cl"
#include "microfacet.cl"
#ifdef PC_HAS_DIFFUSE
#include "bsdf_diffuse.cl"
#endif
#ifdef PC_HAS_OREN_NAYAR
#include "bsdf_oren_nayar.cl"
#endif
#ifdef PC_HAS_PHONG
#include "bsdf_phong.cl"
#endif
#ifdef PC_HAS_MIRROR
#include "bsdf_mirror.cl"
#endif
#ifdef PC_HAS_DIELECTRIC
#include "bsdf_dielectric.cl"
#endif
#ifdef PC_HAS_ROUGH_CONDUCTOR
#include "bsdf_rough_conductor.cl"
#endif
#ifdef PC_HAS_PLASTIC
#include "bsdf_plastic.cl"
#endif

/* Materials whose every lobe is a delta: light sampling is useless there. */
inline bool bsdf_is_delta(Material m) { return m.type == PC_MAT_MIRROR || m.type == PC_MAT_DIELECTRIC; }

inline bool bsdf_is_two_sided(Material m) { return m.type != PC_MAT_DIELECTRIC; }

inline float3 flip_z(float3 w) { return (float3)(w.x, w.y, -w.z); }

inline float3 bsdf_eval(Material m, float3 wo, float3 wi) {
  if (wo.z < 0.0f && bsdf_is_two_sided(m)) {
    wo = flip_z(wo);
    wi = flip_z(wi);
  }
  switch (m.type) {
#ifdef PC_HAS_DIFFUSE
    case PC_MAT_DIFFUSE: return diffuse_eval(m, wo, wi);
#endif
#ifdef PC_HAS_OREN_NAYAR
    case PC_MAT_OREN_NAYAR: return oren_nayar_eval(m, wo, wi);
#endif
#ifdef PC_HAS_PHONG
    case PC_MAT_PHONG: return phong_eval(m, wo, wi);
#endif
#ifdef PC_HAS_ROUGH_CONDUCTOR
    case PC_MAT_ROUGH_CONDUCTOR: return rough_conductor_eval(m, wo, wi);
#endif
#ifdef PC_HAS_PLASTIC
    case PC_MAT_PLASTIC: return plastic_eval(m, wo, wi);
#endif
    default: return (float3)(0.0f); /* delta-only materials */
  }
}

inline float bsdf_pdf(Material m, float3 wo, float3 wi) {
  if (wo.z < 0.0f && bsdf_is_two_sided(m)) {
    wo = flip_z(wo);
    wi = flip_z(wi);
  }
  switch (m.type) {
#ifdef PC_HAS_DIFFUSE
    case PC_MAT_DIFFUSE: return diffuse_pdf(m, wo, wi);
#endif
#ifdef PC_HAS_OREN_NAYAR
    case PC_MAT_OREN_NAYAR: return oren_nayar_pdf(m, wo, wi);
#endif
#ifdef PC_HAS_PHONG
    case PC_MAT_PHONG: return phong_pdf(m, wo, wi);
#endif
#ifdef PC_HAS_ROUGH_CONDUCTOR
    case PC_MAT_ROUGH_CONDUCTOR: return rough_conductor_pdf(m, wo, wi);
#endif
#ifdef PC_HAS_PLASTIC
    case PC_MAT_PLASTIC: return plastic_pdf(m, wo, wi);
#endif
    default: return 0.0f;
  }
}

/* u: three numbers, xy for the direction, z to choose a lobe. */
inline bool bsdf_sample(Material m, float3 wo, float3 u, BsdfSample* s) {
  bool flipped = wo.z < 0.0f && bsdf_is_two_sided(m);
  if (flipped) wo = flip_z(wo);
  bool ok = false;
  switch (m.type) {
#ifdef PC_HAS_DIFFUSE
    case PC_MAT_DIFFUSE: ok = diffuse_sample(m, wo, u, s); break;
#endif
#ifdef PC_HAS_OREN_NAYAR
    case PC_MAT_OREN_NAYAR: ok = oren_nayar_sample(m, wo, u, s); break;
#endif
#ifdef PC_HAS_PHONG
    case PC_MAT_PHONG: ok = phong_sample(m, wo, u, s); break;
#endif
#ifdef PC_HAS_MIRROR
    case PC_MAT_MIRROR: ok = mirror_sample(m, wo, u, s); break;
#endif
#ifdef PC_HAS_DIELECTRIC
    case PC_MAT_DIELECTRIC: ok = dielectric_sample(m, wo, u, s); break;
#endif
#ifdef PC_HAS_ROUGH_CONDUCTOR
    case PC_MAT_ROUGH_CONDUCTOR: ok = rough_conductor_sample(m, wo, u, s); break;
#endif
#ifdef PC_HAS_PLASTIC
    case PC_MAT_PLASTIC: ok = plastic_sample(m, wo, u, s); break;
#endif
    default: break;
  }
  if (flipped) s->wi = flip_z(s->wi);
  return ok;
}

#endif
