/* The GGX (Trowbridge-Reitz) microfacet distribution in the local frame (normal +z), isotropic, with
 * Smith masking and sampling of the visible normals (Heitz 2018). */
#ifndef PATHCL_MICROFACET_CL
#define PATHCL_MICROFACET_CL

/* t = 1 + (a2 - 1) cos^2 written as sin^2 + a2 cos^2 (h is a unit vector): at the smallest alpha, 1e-4,
 * a2 - 1 rounds to -1 and the first form is 0 for normals within 1e-4 rad of +z, which made D infinite
 * and sample weights infinity / infinity. The second is at least a2 cos^2, so D <= 1 / (pi a2 cos^4). */
inline float ggx_d(float3 h, float alpha) {
  if (h.z <= 0.0f) return 0.0f;
  float a2 = alpha * alpha;
  float t = (h.x * h.x + h.y * h.y) + a2 * (h.z * h.z);
  return a2 / (PC_PI * t * t);
}

/* Smith Lambda: G1 = 1 / (1 + Lambda). */
inline float ggx_lambda(float3 w, float alpha) {
  float cos2 = w.z * w.z;
  if (cos2 <= 0.0f) return INFINITY;
  float tan2 = fmax(0.0f, 1.0f - cos2) / cos2;
  return 0.5f * (sqrt(1.0f + alpha * alpha * tan2) - 1.0f);
}

inline float ggx_g1(float3 w, float alpha) { return 1.0f / (1.0f + ggx_lambda(w, alpha)); }

/* Height-correlated masking-shadowing. */
inline float ggx_g2(float3 wo, float3 wi, float alpha) {
  return 1.0f / (1.0f + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

/* Density of visible normal h seen from wo (wo.z > 0). */
inline float ggx_visible_pdf(float3 wo, float3 h, float alpha) {
  float cos_oh = pc_dot(wo, h);
  if (cos_oh <= 0.0f || wo.z <= 0.0f) return 0.0f;
  return ggx_g1(wo, alpha) * cos_oh * ggx_d(h, alpha) / wo.z;
}

/* A visible normal for wo (wo.z > 0). */
inline float3 ggx_sample_visible(float3 wo, float alpha, float2 u) {
  float3 vh = pc_normalize((float3)(alpha * wo.x, alpha * wo.y, wo.z));
  float len2 = vh.x * vh.x + vh.y * vh.y;
  float3 t1 = len2 > 0.0f ? (float3)(-vh.y, vh.x, 0.0f) / sqrt(len2) : (float3)(1.0f, 0.0f, 0.0f);
  float3 t2 = pc_cross(vh, t1);
  float r = sqrt(u.x), phi = 2.0f * PC_PI * u.y;
  float cos_phi, sin_phi = pc_sincos(phi, &cos_phi);
  float p1 = r * cos_phi, p2 = r * sin_phi;
  float s = 0.5f * (1.0f + vh.z);
  p2 = (1.0f - s) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + s * p2;
  float3 nh = p1 * t1 + p2 * t2 + sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
  return pc_normalize((float3)(alpha * nh.x, alpha * nh.y, fmax(1e-6f, nh.z)));
}

/* Reflection off microfacet h: wi = reflect(wo, h); pdf(wi) = visible_pdf(h) / (4 |wo.h|). */
inline float3 reflect_about(float3 wo, float3 h) { return 2.0f * pc_dot(wo, h) * h - wo; }

inline float ggx_reflection_pdf(float3 wo, float3 wi, float alpha) {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
  float3 h = pc_normalize(wo + wi);
  return ggx_visible_pdf(wo, h, alpha) / (4.0f * pc_dot(wo, h));
}

#endif
