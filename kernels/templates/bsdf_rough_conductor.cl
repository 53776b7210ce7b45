/* The rough conductor's lane functions: a template, included by bsdf_rough_conductor.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

static inline PC_OVL V3 rough_conductor_eval_lanes(V3 eta, V3 k, F alpha, V3 wo, V3 wi) {
  V3 h = pc_normalize(lane3(wo.x + wi.x, wo.y + wi.y, wo.z + wi.z));
  V3 f = fresnel_conductor(pc_dot(wo, h), eta, k);
  F s = ggx_d(h, alpha) * ggx_g2(wo, wi, alpha) / (4.0f * wo.z * wi.z);
  I below = (wi.z <= 0.0f) | (wo.z <= 0.0f);
  return lane3(select(f.x * s, (F)(0.0f), below), select(f.y * s, (F)(0.0f), below),
               select(f.z * s, (F)(0.0f), below));
}
static inline PC_OVL F rough_conductor_pdf_lanes(F alpha, V3 wo, V3 wi) { return ggx_reflection_pdf(wo, wi, alpha); }
/* The mask: where the sample is valid (weight is then f cos / pdf). */
static inline PC_OVL I rough_conductor_sample_lanes(V3 eta, V3 k, F alpha, V3 wo, F u0, F u1, V3* wi, F* pdf,
                                                    V3* weight) {
  *wi = reflect_about(wo, ggx_sample_visible(wo, alpha, u0, u1));
  *pdf = rough_conductor_pdf_lanes(alpha, wo, *wi);
  V3 f = rough_conductor_eval_lanes(eta, k, alpha, wo, *wi);
  F cos_over_pdf = wi->z / *pdf;
  *weight = lane3(f.x * cos_over_pdf, f.y * cos_over_pdf, f.z * cos_over_pdf);
  return (wi->z > 0.0f) & (*pdf > 0.0f);
}

#include "templates/lane_width_end.h"
