/* Phong's lane functions: a template, included by bsdf_phong.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

static inline PC_OVL F phong_specular_probability_lanes(V3 color, V3 specular) {
  F d = luminance_lanes(color), s = luminance_lanes(specular);
  return select((F)(0.0f), s / (d + s), d + s > 0.0f);
}
static inline PC_OVL F phong_cos_alpha_lanes(V3 wo, V3 wi) { return pc_dot(lane3(-wo.x, -wo.y, wo.z), wi); }
static inline PC_OVL V3 phong_eval_lanes(V3 color, V3 specular, F exponent, V3 wo, V3 wi) {
  F c = phong_cos_alpha_lanes(wo, wi);
  F spec = (exponent + 2.0f) * (0.5f * PC_INV_PI) * pc_powr(c, exponent);
  spec = select((F)(0.0f), spec, c > 0.0f);
  I below = (wi.z <= 0.0f) | (wo.z <= 0.0f);
  return lane3(select(color.x * PC_INV_PI + specular.x * spec, (F)(0.0f), below),
               select(color.y * PC_INV_PI + specular.y * spec, (F)(0.0f), below),
               select(color.z * PC_INV_PI + specular.z * spec, (F)(0.0f), below));
}
static inline PC_OVL F phong_pdf_lanes(V3 color, V3 specular, F exponent, V3 wo, V3 wi) {
  F ps = phong_specular_probability_lanes(color, specular);
  F c = phong_cos_alpha_lanes(wo, wi);
  F lobe = (exponent + 1.0f) * (0.5f * PC_INV_PI) * pc_powr(c, exponent);
  lobe = select((F)(0.0f), lobe, c > 0.0f);
  F pdf = (1.0f - ps) * wi.z * PC_INV_PI + ps * lobe;
  return select(pdf, (F)(0.0f), (wi.z <= 0.0f) | (wo.z <= 0.0f));
}
/* u2 chooses the lobe: cos^n about the mirror direction (cos(alpha) = u0^(1 / (n + 1))) or cosine-
 * weighted; the mask: where the sample is valid (weight is then f cos / pdf). */
static inline PC_OVL I phong_sample_lanes(V3 color, V3 specular, F exponent, V3 wo, F u0, F u1, F u2, V3* wi,
                                          F* pdf, V3* weight) {
  F cos_a = pc_powr(u0, 1.0f / (exponent + 1.0f));
  F sin_a = sqrt(fmax(0.0f, 1.0f - cos_a * cos_a));
  F phi = 2.0f * PC_PI * u1;
  V3 r = lane3(-wo.x, -wo.y, wo.z), t, b;
  make_frame(r, &t, &b);
  F cos_phi, sin_phi = pc_sincos(phi, &cos_phi);
  F ct = sin_a * cos_phi, st = sin_a * sin_phi;
  V3 lobe = pc_normalize(lane3(ct * t.x + st * b.x + cos_a * r.x, ct * t.y + st * b.y + cos_a * r.y,
                               ct * t.z + st * b.z + cos_a * r.z));
  F x, y, z;
  sample_cosine_hemisphere_lanes(u0, u1, &x, &y, &z);
  I specular_lobe = u2 < phong_specular_probability_lanes(color, specular);
  *wi = lane3(select(x, lobe.x, specular_lobe), select(y, lobe.y, specular_lobe),
              select(z, lobe.z, specular_lobe));
  *pdf = phong_pdf_lanes(color, specular, exponent, wo, *wi);
  V3 f = phong_eval_lanes(color, specular, exponent, wo, *wi);
  F cos_over_pdf = wi->z / *pdf;
  *weight = lane3(f.x * cos_over_pdf, f.y * cos_over_pdf, f.z * cos_over_pdf);
  return *pdf > 0.0f;
}

#include "templates/lane_width_end.h"
