/* Oren-Nayar's lane functions: a template, included by bsdf_oren_nayar.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

static inline PC_OVL V3 oren_nayar_eval_lanes(V3 c, F sigma, V3 wo, V3 wi) {
  F s2 = sigma * sigma;
  F a = 1.0f - s2 / (2.0f * (s2 + 0.33f));
  F b = 0.45f * s2 / (s2 + 0.09f);
  F sin_i = sqrt(fmax(0.0f, 1.0f - wi.z * wi.z)), sin_o = sqrt(fmax(0.0f, 1.0f - wo.z * wo.z));
  /* cos(phi_i - phi_o), only where both azimuths are defined. */
  F max_cos = fmax(0.0f, clamp((wi.x * wo.x + wi.y * wo.y) / (sin_i * sin_o), -1.0f, 1.0f));
  max_cos = select((F)(0.0f), max_cos, (sin_i > 1e-4f) & (sin_o > 1e-4f));
  /* alpha = max(theta_i, theta_o), beta = min: tan(beta) uses the larger cosine, never 0 here. */
  I i_higher = wi.z > wo.z;
  F sin_alpha = select(sin_i, sin_o, i_higher);
  F tan_beta = select(sin_o / wo.z, sin_i / wi.z, i_higher);
  F k = a + b * max_cos * sin_alpha * tan_beta;
  I below = (wi.z <= 0.0f) | (wo.z <= 0.0f);
  return lane3(select(c.x * PC_INV_PI * k, (F)(0.0f), below), select(c.y * PC_INV_PI * k, (F)(0.0f), below),
               select(c.z * PC_INV_PI * k, (F)(0.0f), below));
}
static inline PC_OVL F oren_nayar_pdf_lanes(V3 wi) { return fmax(wi.z, 0.0f) * PC_INV_PI; }
/* Sampled like Lambert; the mask: where the sample is valid (weight is then f cos / pdf). */
static inline PC_OVL I oren_nayar_sample_lanes(V3 c, F sigma, V3 wo, F u0, F u1, V3* wi, F* pdf, V3* weight) {
  F x, y, z;
  sample_cosine_hemisphere_lanes(u0, u1, &x, &y, &z);
  *wi = lane3(x, y, z);
  *pdf = oren_nayar_pdf_lanes(*wi);
  V3 f = oren_nayar_eval_lanes(c, sigma, wo, *wi);
  F cos_over_pdf = z / *pdf;
  *weight = lane3(f.x * cos_over_pdf, f.y * cos_over_pdf, f.z * cos_over_pdf);
  return *pdf > 0.0f;
}

#include "templates/lane_width_end.h"
