/* The microfacet distribution's lane functions: a template, included by microfacet.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

/* t = 1 + (a2 - 1) cos^2 written as sin^2 + a2 cos^2 (h is a unit vector): at the smallest alpha,
 * 1e-4, a2 - 1 rounds to -1 and the first form is 0 for normals within 1e-4 rad of +z, which made D
 * infinite and sample weights infinity / infinity. The second is at least a2 cos^2, so
 * D <= 1 / (pi a2 cos^4). */
static inline PC_OVL F ggx_d(V3 h, F alpha) {
  F a2 = alpha * alpha;
  F t = (h.x * h.x + h.y * h.y) + a2 * (h.z * h.z);
  return select(a2 / (PC_PI * t * t), (F)(0.0f), h.z <= 0.0f);
}
/* Smith Lambda: G1 = 1 / (1 + Lambda). */
static inline PC_OVL F ggx_lambda(V3 w, F alpha) {
  F cos2 = w.z * w.z;
  F tan2 = fmax(0.0f, 1.0f - cos2) / cos2;
  return select(0.5f * (sqrt(1.0f + alpha * alpha * tan2) - 1.0f), (F)(INFINITY), cos2 <= 0.0f);
}
static inline PC_OVL F ggx_g1(V3 w, F alpha) { return 1.0f / (1.0f + ggx_lambda(w, alpha)); }
/* Height-correlated masking-shadowing. */
static inline PC_OVL F ggx_g2(V3 wo, V3 wi, F alpha) {
  return 1.0f / (1.0f + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}
/* Density of visible normal h seen from wo (wo.z > 0). */
static inline PC_OVL F ggx_visible_pdf(V3 wo, V3 h, F alpha) {
  F cos_oh = pc_dot(wo, h);
  return select(ggx_g1(wo, alpha) * cos_oh * ggx_d(h, alpha) / wo.z, (F)(0.0f),
                (cos_oh <= 0.0f) | (wo.z <= 0.0f));
}
/* A visible normal for wo (wo.z > 0). */
static inline PC_OVL V3 ggx_sample_visible(V3 wo, F alpha, F u0, F u1) {
  V3 vh = pc_normalize(lane3(alpha * wo.x, alpha * wo.y, wo.z));
  F len2 = vh.x * vh.x + vh.y * vh.y;
  F len = sqrt(len2);
  I tilted = len2 > 0.0f;
  V3 t1 = lane3(select((F)(1.0f), -vh.y / len, tilted), select((F)(0.0f), vh.x / len, tilted),
                select((F)(0.0f), 0.0f / len, tilted));
  V3 t2 = pc_cross(vh, t1);
  F r = sqrt(u0), phi = 2.0f * PC_PI * u1;
  F cos_phi, sin_phi = pc_sincos(phi, &cos_phi);
  F p1 = r * cos_phi, p2 = r * sin_phi;
  F s = 0.5f * (1.0f + vh.z);
  p2 = (1.0f - s) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + s * p2;
  F n = sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2));
  F nx = p1 * t1.x + p2 * t2.x + n * vh.x, ny = p1 * t1.y + p2 * t2.y + n * vh.y;
  F nz = p1 * t1.z + p2 * t2.z + n * vh.z;
  return pc_normalize(lane3(alpha * nx, alpha * ny, fmax(1e-6f, nz)));
}
/* Reflection off microfacet h: wi = reflect(wo, h); pdf(wi) = visible_pdf(h) / (4 |wo.h|). */
static inline PC_OVL V3 reflect_about(V3 wo, V3 h) {
  F d = 2.0f * pc_dot(wo, h);
  return lane3(d * h.x - wo.x, d * h.y - wo.y, d * h.z - wo.z);
}
static inline PC_OVL F ggx_reflection_pdf(V3 wo, V3 wi, F alpha) {
  V3 h = pc_normalize(lane3(wo.x + wi.x, wo.y + wi.y, wo.z + wi.z));
  return select(ggx_visible_pdf(wo, h, alpha) / (4.0f * pc_dot(wo, h)), (F)(0.0f),
                (wo.z <= 0.0f) | (wi.z <= 0.0f));
}

#include "templates/lane_width_end.h"
