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
  float eta2;    /* (n_t / n_i)^2 where weight was divided by it on refraction, else 1 (for roulette) */
  bool delta;    /* wi came from a delta lobe: no light sampling can reach it, no MIS */
} BsdfSample;

/* A lobe's BsdfSample from its one-lane *_sample_lanes results (bsdf_diffuse.cl); delta: wi came from a
 * delta lobe. */
inline bool lobe_sample(int valid, lane3f wi, float pdf, lane3f weight, int delta, BsdfSample* s) {
  s->wi = float3_of(wi);
  s->pdf = pdf;
  s->weight = float3_of(weight);
  s->delta = delta;
  return valid;
}

#include "fresnel.cl"
#include "microfacet.cl"

/* One X(type constant, function prefix) per material type compiled in (its PC_HAS_* flag). */
#ifdef PC_HAS_DIFFUSE
#include "bsdf_diffuse.cl"
#define PC_BSDF_DIFFUSE(X) X(PC_MAT_DIFFUSE, diffuse)
#else
#define PC_BSDF_DIFFUSE(X)
#endif
#ifdef PC_HAS_OREN_NAYAR
#include "bsdf_oren_nayar.cl"
#define PC_BSDF_OREN_NAYAR(X) X(PC_MAT_OREN_NAYAR, oren_nayar)
#else
#define PC_BSDF_OREN_NAYAR(X)
#endif
#ifdef PC_HAS_PHONG
#include "bsdf_phong.cl"
#define PC_BSDF_PHONG(X) X(PC_MAT_PHONG, phong)
#else
#define PC_BSDF_PHONG(X)
#endif
#ifdef PC_HAS_MIRROR
#include "bsdf_mirror.cl"
#define PC_BSDF_MIRROR(X) X(PC_MAT_MIRROR, mirror)
#else
#define PC_BSDF_MIRROR(X)
#endif
#ifdef PC_HAS_DIELECTRIC
#include "bsdf_dielectric.cl"
#define PC_BSDF_DIELECTRIC(X) X(PC_MAT_DIELECTRIC, dielectric)
#else
#define PC_BSDF_DIELECTRIC(X)
#endif
#ifdef PC_HAS_ROUGH_CONDUCTOR
#include "bsdf_rough_conductor.cl"
#define PC_BSDF_ROUGH_CONDUCTOR(X) X(PC_MAT_ROUGH_CONDUCTOR, rough_conductor)
#else
#define PC_BSDF_ROUGH_CONDUCTOR(X)
#endif
#ifdef PC_HAS_PLASTIC
#include "bsdf_plastic.cl"
#define PC_BSDF_PLASTIC(X) X(PC_MAT_PLASTIC, plastic)
#else
#define PC_BSDF_PLASTIC(X)
#endif
#define PC_BSDF_TYPES(X)                                                                                  \
  PC_BSDF_DIFFUSE(X) PC_BSDF_OREN_NAYAR(X) PC_BSDF_PHONG(X) PC_BSDF_MIRROR(X) PC_BSDF_DIELECTRIC(X)       \
  PC_BSDF_ROUGH_CONDUCTOR(X) PC_BSDF_PLASTIC(X)

/* Materials whose every lobe is a delta: light sampling is useless there. */
inline bool bsdf_is_delta(Material m) { return m.type == PC_MAT_MIRROR || m.type == PC_MAT_DIELECTRIC; }

inline bool bsdf_is_two_sided(Material m) { return m.type != PC_MAT_DIELECTRIC; }

inline float3 flip_z(float3 w) { return (float3)(w.x, w.y, -w.z); }

inline float3 bsdf_eval(Material m, float3 wo, float3 wi) {
  if (wo.z < 0.0f && bsdf_is_two_sided(m)) {
    wo = flip_z(wo);
    wi = flip_z(wi);
  }
#define PC_EVAL_CASE(type, name) case type: return name##_eval(m, wo, wi);
  switch (m.type) {
    PC_BSDF_TYPES(PC_EVAL_CASE)
    default: return (float3)(0.0f);
  }
#undef PC_EVAL_CASE
}

inline float bsdf_pdf(Material m, float3 wo, float3 wi) {
  if (wo.z < 0.0f && bsdf_is_two_sided(m)) {
    wo = flip_z(wo);
    wi = flip_z(wi);
  }
#define PC_PDF_CASE(type, name) case type: return name##_pdf(m, wo, wi);
  switch (m.type) {
    PC_BSDF_TYPES(PC_PDF_CASE)
    default: return 0.0f;
  }
#undef PC_PDF_CASE
}

/* u: three numbers, xy for the direction, z to choose a lobe. */
inline bool bsdf_sample(Material m, float3 wo, float3 u, BsdfSample* s) {
  bool flipped = wo.z < 0.0f && bsdf_is_two_sided(m);
  if (flipped) wo = flip_z(wo);
  bool ok = false;
  s->eta2 = 1.0f;
#define PC_SAMPLE_CASE(type, name) case type: ok = name##_sample(m, wo, u, s); break;
  switch (m.type) {
    PC_BSDF_TYPES(PC_SAMPLE_CASE)
    default: break;
  }
#undef PC_SAMPLE_CASE
  if (flipped) s->wi = flip_z(s->wi);
  return ok;
}

#endif
