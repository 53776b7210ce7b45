/* Rough metal: GGX microfacet reflection with the conductor Fresnel term (complex index eta + i k per
 * channel; a "specular" colour is turned into eta = 1 and the k that reflects it at normal incidence),
 * sampled by visible normals. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_ROUGH_CONDUCTOR_CL
#define PATHCL_BSDF_ROUGH_CONDUCTOR_CL

/* Written once over lanes, as bsdf_diffuse.cl's lobes (eta, k and alpha per lane); bsdf.cl dispatches
 * to them at every width (tests/bsdf_test.cpp, LobesGiveTheOneLaneBits). */
#define PC_ROUGH_CONDUCTOR_LANES(V3, F, I)                                                                \
  inline PC_OVL V3 rough_conductor_eval_lanes(V3 eta, V3 k, F alpha, V3 wo, V3 wi) {                      \
    V3 h = pc_normalize(lane3(wo.x + wi.x, wo.y + wi.y, wo.z + wi.z));                                    \
    V3 f = fresnel_conductor(pc_dot(wo, h), eta, k);                                                      \
    F s = ggx_d(h, alpha) * ggx_g2(wo, wi, alpha) / (4.0f * wo.z * wi.z);                                 \
    I below = (wi.z <= 0.0f) | (wo.z <= 0.0f);                                                            \
    return lane3(select(f.x * s, (F)(0.0f), below), select(f.y * s, (F)(0.0f), below),                    \
                 select(f.z * s, (F)(0.0f), below));                                                      \
  }                                                                                                       \
  inline PC_OVL F rough_conductor_pdf_lanes(F alpha, V3 wo, V3 wi) { return ggx_reflection_pdf(wo, wi, alpha); } \
  /* The mask: where the sample is valid (weight is then f cos / pdf). */                                \
  inline PC_OVL I rough_conductor_sample_lanes(V3 eta, V3 k, F alpha, V3 wo, F u0, F u1, V3* wi, F* pdf,  \
                                               V3* weight) {                                              \
    *wi = reflect_about(wo, ggx_sample_visible(wo, alpha, u0, u1));                                       \
    *pdf = rough_conductor_pdf_lanes(alpha, wo, *wi);                                                     \
    V3 f = rough_conductor_eval_lanes(eta, k, alpha, wo, *wi);                                            \
    F cos_over_pdf = wi->z / *pdf;                                                                        \
    *weight = lane3(f.x * cos_over_pdf, f.y * cos_over_pdf, f.z * cos_over_pdf);                          \
    return (wi->z > 0.0f) & (*pdf > 0.0f);                                                                \
  }
PC_ROUGH_CONDUCTOR_LANES(lane3f, float, int)
PC_ROUGH_CONDUCTOR_LANES(lane3f8, float8, int8)
PC_ROUGH_CONDUCTOR_LANES(lane3f16, float16, int16)
#undef PC_ROUGH_CONDUCTOR_LANES

#endif
