/* BSDFs by material type, each in its own file with the *_eval / *_pdf / *_sample triad, and the
 * dispatch over them. Everything here works in the local shading frame: the shading normal's front side
 * is +z. Only the dielectric tells the two sides apart (outside = front); every other material reflects
 * the same on both sides, so a back-side wo is mirrored to the front and the result mirrored back.
 * eval returns f (without the cosine); delta lobes are not in eval or pdf, only in sample. */
#ifndef PATHCL_BSDF_CL
#define PATHCL_BSDF_CL

#include "lanes.cl"

typedef struct {
  float3 wi;     /* local frame */
  float3 weight; /* f cos / pdf: the factor the path throughput takes */
  float pdf;     /* solid-angle density; for a delta lobe the probability of having chosen it */
  float eta2;    /* (n_t / n_i)^2 where weight was divided by it on refraction, else 1 (for roulette) */
  bool delta;    /* wi came from a delta lobe: no light sampling can reach it, no MIS */
} BsdfSample;

#include "fresnel.cl"
#include "microfacet.cl"

/* The material types compiled in (their PC_HAS_* flags). */
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

/* ---- The dispatch over the program's lanes (kernels/lanes.cl): each material type present among the
 * lanes runs its *_lanes functions for all lanes at once, and its lanes take the results; the functions on
 * Material at the end are the one-lane instances. */

/* A Material's parameters by lane (kernels/material.cl, material_at_lanes). */
typedef struct {
  LaneU type;
  Lane3 color, specular, k;
  LaneF alpha, sigma, exponent, ior;
} MaterialLanes;

typedef struct {
  Lane3 wi, weight;
  LaneF pdf, eta2;
  LaneI delta;
} BsdfSampleLanes;

static inline LaneI bsdf_is_delta_lanes(LaneU type) {
  return (type == PC_MAT_MIRROR) | (type == PC_MAT_DIELECTRIC) | (type == PC_MAT_THIN_DIELECTRIC);
}

/* Where wo is on the back of a two-sided material: the lanes whose directions are mirrored to the front. */
static inline LaneI bsdf_flipped_lanes(const MaterialLanes* m, Lane3 wo) { return (wo.z < 0.0f) & (m->type != PC_MAT_DIELECTRIC); }

static inline Lane3 flip_z_lanes(Lane3 w, LaneI flip) { return lane3(w.x, w.y, select(w.z, -w.z, flip)); }

static inline Lane3 bsdf_eval_lanes(const MaterialLanes* m, Lane3 wo, Lane3 wi, LaneI mask) {
  LaneI flip = bsdf_flipped_lanes(m, wo);
  wo = flip_z_lanes(wo, flip);
  wi = flip_z_lanes(wi, flip);
  Lane3 f = lane3_splat((float3)(0.0f));
  LaneI is;
#ifdef PC_HAS_DIFFUSE
  if (pc_any_(is = mask & (m->type == PC_MAT_DIFFUSE))) f = lane3_select(f, diffuse_eval_lanes(m->color, wi), is);
#endif
#ifdef PC_HAS_OREN_NAYAR
  if (pc_any_(is = mask & (m->type == PC_MAT_OREN_NAYAR)))
    f = lane3_select(f, oren_nayar_eval_lanes(m->color, m->sigma, wo, wi), is);
#endif
#ifdef PC_HAS_PHONG
  if (pc_any_(is = mask & (m->type == PC_MAT_PHONG)))
    f = lane3_select(f, phong_eval_lanes(m->color, m->specular, m->exponent, wo, wi), is);
#endif
#ifdef PC_HAS_ROUGH_CONDUCTOR
  if (pc_any_(is = mask & (m->type == PC_MAT_ROUGH_CONDUCTOR)))
    f = lane3_select(f, rough_conductor_eval_lanes(m->specular, m->k, m->alpha, wo, wi), is);
#endif
#ifdef PC_HAS_PLASTIC
  if (pc_any_(is = mask & (m->type == PC_MAT_PLASTIC)))
    f = lane3_select(f, plastic_eval_lanes(m->color, m->ior, m->alpha, wo, wi), is);
#endif
  return f;
}

static inline LaneF bsdf_pdf_lanes(const MaterialLanes* m, Lane3 wo, Lane3 wi, LaneI mask) {
  LaneI flip = bsdf_flipped_lanes(m, wo);
  wo = flip_z_lanes(wo, flip);
  wi = flip_z_lanes(wi, flip);
  LaneF pdf = (LaneF)(0.0f);
  LaneI is;
#ifdef PC_HAS_DIFFUSE
  if (pc_any_(is = mask & (m->type == PC_MAT_DIFFUSE))) pdf = select(pdf, diffuse_pdf_lanes(wi), is);
#endif
#ifdef PC_HAS_OREN_NAYAR
  if (pc_any_(is = mask & (m->type == PC_MAT_OREN_NAYAR))) pdf = select(pdf, oren_nayar_pdf_lanes(wi), is);
#endif
#ifdef PC_HAS_PHONG
  if (pc_any_(is = mask & (m->type == PC_MAT_PHONG)))
    pdf = select(pdf, phong_pdf_lanes(m->color, m->specular, m->exponent, wo, wi), is);
#endif
#ifdef PC_HAS_ROUGH_CONDUCTOR
  if (pc_any_(is = mask & (m->type == PC_MAT_ROUGH_CONDUCTOR)))
    pdf = select(pdf, rough_conductor_pdf_lanes(m->alpha, wo, wi), is);
#endif
#ifdef PC_HAS_PLASTIC
  if (pc_any_(is = mask & (m->type == PC_MAT_PLASTIC)))
    pdf = select(pdf, plastic_pdf_lanes(m->color, m->ior, m->alpha, wo, wi), is);
#endif
  return pdf;
}

/* u0, u1 for the direction, u2 to choose a lobe. Returns the lanes of mask with a valid sample. */
PC_OUT_OF_LINE LaneI bsdf_sample_lanes(const MaterialLanes* m, Lane3 wo, LaneF u0, LaneF u1, LaneF u2, LaneI mask,
                                       BsdfSampleLanes* s) {
  LaneI flip = bsdf_flipped_lanes(m, wo);
  wo = flip_z_lanes(wo, flip);
  LaneI ok = (LaneI)(0), is, valid;
  s->wi = s->weight = lane3_splat((float3)(0.0f));
  s->pdf = (LaneF)(0.0f);
  s->eta2 = (LaneF)(1.0f);
  s->delta = (LaneI)(0);
  Lane3 wi, weight;
  LaneF pdf;
  /* Each type's lanes take its sample: wi, weight, pdf and the validity. */
#define PC_TAKE_SAMPLE(IS, VALID)                                                                         \
  s->wi = lane3_select(s->wi, wi, IS);                                                                    \
  s->weight = lane3_select(s->weight, weight, IS);                                                        \
  s->pdf = select(s->pdf, pdf, IS);                                                                       \
  ok = select(ok, VALID, IS);
#ifdef PC_HAS_DIFFUSE
  if (pc_any_(is = mask & (m->type == PC_MAT_DIFFUSE))) {
    valid = diffuse_sample_lanes(m->color, u0, u1, &wi, &pdf, &weight);
    PC_TAKE_SAMPLE(is, valid)
  }
#endif
#ifdef PC_HAS_OREN_NAYAR
  if (pc_any_(is = mask & (m->type == PC_MAT_OREN_NAYAR))) {
    valid = oren_nayar_sample_lanes(m->color, m->sigma, wo, u0, u1, &wi, &pdf, &weight);
    PC_TAKE_SAMPLE(is, valid)
  }
#endif
#ifdef PC_HAS_PHONG
  if (pc_any_(is = mask & (m->type == PC_MAT_PHONG))) {
    valid = phong_sample_lanes(m->color, m->specular, m->exponent, wo, u0, u1, u2, &wi, &pdf, &weight);
    PC_TAKE_SAMPLE(is, valid)
  }
#endif
#ifdef PC_HAS_MIRROR
  if (pc_any_(is = mask & (m->type == PC_MAT_MIRROR))) {
    valid = mirror_sample_lanes(m->color, wo, &wi, &pdf, &weight);
    /* A metal mirror (eta and k given, not both 0): its reflectance times the conductor's Fresnel term;
     * a plain mirror's weight stays its reflectance, bit for bit. */
    LaneI metal = is & ((m->specular.x != 0.0f) | (m->specular.y != 0.0f) | (m->specular.z != 0.0f) |
                        (m->k.x != 0.0f) | (m->k.y != 0.0f) | (m->k.z != 0.0f));
    if (pc_any_(metal)) weight = lane3_select(weight, lane3_mul(weight, fresnel_conductor(wo.z, m->specular, m->k)), metal);
    PC_TAKE_SAMPLE(is, valid)
    s->delta |= is;
  }
#endif
#ifdef PC_HAS_DIELECTRIC
  if (pc_any_(is = mask & (m->type == PC_MAT_DIELECTRIC))) {
    LaneF eta2;
    valid = dielectric_sample_lanes(m->color, m->ior, wo, u2, &wi, &pdf, &weight, &eta2);
    PC_TAKE_SAMPLE(is, valid)
    s->eta2 = select(s->eta2, eta2, is);
    s->delta |= is;
  }
  if (pc_any_(is = mask & (m->type == PC_MAT_THIN_DIELECTRIC))) {
    valid = thin_dielectric_sample_lanes(m->color, m->ior, wo, u2, &wi, &pdf, &weight);
    PC_TAKE_SAMPLE(is, valid)
    s->delta |= is;
  }
#endif
#ifdef PC_HAS_ROUGH_CONDUCTOR
  if (pc_any_(is = mask & (m->type == PC_MAT_ROUGH_CONDUCTOR))) {
    valid = rough_conductor_sample_lanes(m->specular, m->k, m->alpha, wo, u0, u1, &wi, &pdf, &weight);
    PC_TAKE_SAMPLE(is, valid)
  }
#endif
#ifdef PC_HAS_PLASTIC
  if (pc_any_(is = mask & (m->type == PC_MAT_PLASTIC))) {
    LaneI delta;
    valid = plastic_sample_lanes(m->color, m->ior, m->alpha, wo, u0, u1, u2, &wi, &pdf, &weight, &delta);
    PC_TAKE_SAMPLE(is, valid)
    s->delta = select(s->delta, delta, is);
  }
#endif
#undef PC_TAKE_SAMPLE
  s->wi = flip_z_lanes(s->wi, flip);
  return ok & mask;
}

#if PC_LANES == 1
/* A Material's BSDF parameters as one lane. */
static inline MaterialLanes material_lanes_of(Material m) {
  MaterialLanes l;
  l.type = m.type;
  l.color = m.color.xyz;
  l.specular = m.specular.xyz;
  l.k = m.k.xyz;
  l.alpha = m.alpha;
  l.sigma = m.sigma;
  l.exponent = m.exponent;
  l.ior = m.ior;
  return l;
}

/* Materials whose every lobe is a delta: light sampling is useless there. */
static inline bool bsdf_is_delta(Material m) { return bsdf_is_delta_lanes(m.type) != 0; }

static inline float3 bsdf_eval(Material m, float3 wo, float3 wi) {
  MaterialLanes l = material_lanes_of(m);
  return bsdf_eval_lanes(&l, wo, wi, 1);
}

static inline float bsdf_pdf(Material m, float3 wo, float3 wi) {
  MaterialLanes l = material_lanes_of(m);
  return bsdf_pdf_lanes(&l, wo, wi, 1);
}

/* u: three numbers, xy for the direction, z to choose a lobe. */
static inline bool bsdf_sample(Material m, float3 wo, float3 u, BsdfSample* s) {
  MaterialLanes l = material_lanes_of(m);
  BsdfSampleLanes b;
  bool ok = bsdf_sample_lanes(&l, wo, u.x, u.y, u.z, 1, &b) != 0;
  s->wi = b.wi;
  s->weight = b.weight;
  s->pdf = b.pdf;
  s->eta2 = b.eta2;
  s->delta = b.delta != 0;
  return ok;
}
#endif

#endif
