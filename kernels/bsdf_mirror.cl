/* A perfect mirror of the given reflectance: one delta lobe. Local frame, wo.z > 0. */
#ifndef PATHCL_BSDF_MIRROR_CL
#define PATHCL_BSDF_MIRROR_CL

/* Written once over lanes, as bsdf_diffuse.cl's lobes; the mask: where the sample is valid. */
#define PC_MIRROR_LANES(V3, F, I)                                                                         \
  inline PC_OVL I mirror_sample_lanes(V3 c, V3 wo, V3* wi, F* pdf, V3* weight) {                          \
    *wi = reflect_local(wo);                                                                              \
    *weight = c;                                                                                          \
    *pdf = 1.0f;                                                                                          \
    return wo.z > 0.0f;                                                                                   \
  }
PC_MIRROR_LANES(lane3f, float, int)
PC_MIRROR_LANES(lane3f8, float8, int8)
PC_MIRROR_LANES(lane3f16, float16, int16)
#undef PC_MIRROR_LANES

#endif
