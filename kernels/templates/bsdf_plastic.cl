/* The plastic's lane functions: a template, included by bsdf_plastic.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

static inline PC_OVL F plastic_coat_probability_lanes(V3 c, F ior, V3 wo) {
  F f = fresnel_dielectric(wo.z, ior);
  F base = (1.0f - f) * fmax(c.x, fmax(c.y, c.z));
  return select((F)(1.0f), f / (f + base), f + base > 0.0f);
}
/* The non-delta part: the base, plus the rough coat. */
static inline PC_OVL V3 plastic_eval_lanes(V3 c, F ior, F alpha, V3 wo, V3 wi) {
  F base = PC_INV_PI * (1.0f - fresnel_dielectric(wo.z, ior)) * (1.0f - fresnel_dielectric(wi.z, ior));
  V3 h = pc_normalize(lane3(wo.x + wi.x, wo.y + wi.y, wo.z + wi.z));
  F coat = fresnel_dielectric(pc_dot(wo, h), ior) * ggx_d(h, alpha) * ggx_g2(wo, wi, alpha) / (4.0f * wo.z * wi.z);
  I rough = alpha > 0.0f, below = (wi.z <= 0.0f) | (wo.z <= 0.0f);
  F fx = c.x * base, fy = c.y * base, fz = c.z * base;
  fx = select(fx, fx + coat, rough);
  fy = select(fy, fy + coat, rough);
  fz = select(fz, fz + coat, rough);
  return lane3(select(fx, (F)(0.0f), below), select(fy, (F)(0.0f), below), select(fz, (F)(0.0f), below));
}
static inline PC_OVL F plastic_pdf_lanes(V3 c, F ior, F alpha, V3 wo, V3 wi) {
  F pc = plastic_coat_probability_lanes(c, ior, wo);
  F pdf = (1.0f - pc) * wi.z * PC_INV_PI;
  pdf = select(pdf, pdf + pc * ggx_reflection_pdf(wo, wi, alpha), alpha > 0.0f);
  return select(pdf, (F)(0.0f), (wi.z <= 0.0f) | (wo.z <= 0.0f));
}
/* u2 chooses the lobe: the coat (a delta where alpha = 0: *delta set) or the base. The mask: where the
 * sample is valid. */
static inline PC_OVL I plastic_sample_lanes(V3 c, F ior, F alpha, V3 wo, F u0, F u1, F u2, V3* wi, F* pdf,
                                            V3* weight, I* delta) {
  F pc = plastic_coat_probability_lanes(c, ior, wo);
  I coat = u2 < pc;
  *delta = coat & (alpha == 0.0f);
  V3 lobe = reflect_about(wo, ggx_sample_visible(wo, alpha, u0, u1));
  F x, y, z;
  sample_cosine_hemisphere_lanes(u0, u1, &x, &y, &z);
  V3 r = lane3(select(x, lobe.x, coat), select(y, lobe.y, coat), select(z, lobe.z, coat));
  F p = plastic_pdf_lanes(c, ior, alpha, wo, r);
  V3 f = plastic_eval_lanes(c, ior, alpha, wo, r);
  F cos_over_pdf = r.z / p;
  V3 m = reflect_local(wo);
  F coat_weight = fresnel_dielectric(wo.z, ior) / pc;
  *wi = lane3(select(r.x, m.x, *delta), select(r.y, m.y, *delta), select(r.z, m.z, *delta));
  *pdf = select(p, pc, *delta);
  *weight = lane3(select(f.x * cos_over_pdf, coat_weight, *delta), select(f.y * cos_over_pdf, coat_weight, *delta),
                  select(f.z * cos_over_pdf, coat_weight, *delta));
  return *delta | ((r.z > 0.0f) & (p > 0.0f));
}

#include "templates/lane_width_end.h"
