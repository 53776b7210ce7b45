/* Fresnel's lane functions: a template, included by fresnel.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

static inline PC_OVL F fresnel_conductor_channel(F cos_i, F cos2, F sin2, F eta, F k) {
  F t0 = eta * eta - k * k - sin2;
  F a2_plus_b2 = sqrt(fmax(t0 * t0 + 4.0f * eta * eta * k * k, 0.0f));
  F t1 = a2_plus_b2 + cos2;
  F a = sqrt(fmax(0.5f * (a2_plus_b2 + t0), 0.0f));
  F t2 = 2.0f * cos_i * a;
  /* Both are squared magnitudes in [0, 1]. Where the index is that of the medium (eta 1, k 0: the
   * "specular": 0 channel) t1 and t2 are equal up to rounding, and their difference, negative half the
   * time, made negative radiance. */
  F rs = clamp((t1 - t2) / (t1 + t2), 0.0f, 1.0f);
  F t3 = cos2 * a2_plus_b2 + sin2 * sin2;
  F t4 = t2 * sin2;
  F rp = rs * clamp((t3 - t4) / (t3 + t4), 0.0f, 1.0f);
  return 0.5f * (rp + rs);
}
/* Dielectric: cos_i > 0 on the incident side, eta = n_transmitted / n_incident. 1 under total internal
 * reflection. */
static inline PC_OVL F fresnel_dielectric(F cos_i, F eta) {
  cos_i = clamp(cos_i, 0.0f, 1.0f);
  F sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  F cos_t = sqrt(fmax(0.0f, 1.0f - sin2_t));
  F r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  F r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return select(0.5f * (r_parallel * r_parallel + r_perpendicular * r_perpendicular), (F)(1.0f),
                sin2_t >= 1.0f);
}
/* Conductor with complex index eta + i k per channel, from a medium of index 1. */
static inline PC_OVL V3 fresnel_conductor(F cos_i, V3 eta, V3 k) {
  cos_i = clamp(cos_i, 0.0f, 1.0f);
  F cos2 = cos_i * cos_i, sin2 = 1.0f - cos2;
  return lane3(fresnel_conductor_channel(cos_i, cos2, sin2, eta.x, k.x),
               fresnel_conductor_channel(cos_i, cos2, sin2, eta.y, k.y),
               fresnel_conductor_channel(cos_i, cos2, sin2, eta.z, k.z));
}
static inline PC_OVL V3 reflect_local(V3 wo) { return lane3(-wo.x, -wo.y, wo.z); }
/* Refraction of wo through the interface with normal n on wo's side; eta = n_t / n_i. The mask: where
 * there is no total internal reflection (*wt is valid). */
static inline PC_OVL I refract_dir(V3 wo, V3 n, F eta, V3* wt) {
  F cos_i = pc_dot(wo, n);
  F sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  F cos_t = sqrt(fmax(0.0f, 1.0f - sin2_t));
  F s = cos_i / eta - cos_t;
  *wt = pc_normalize(lane3(-wo.x / eta + s * n.x, -wo.y / eta + s * n.y, -wo.z / eta + s * n.z));
  return !(sin2_t >= 1.0f);
}

#include "templates/lane_width_end.h"
