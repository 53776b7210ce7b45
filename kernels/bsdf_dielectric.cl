/* Smooth glass: exact Fresnel reflectance chooses between mirror reflection and refraction; total
 * internal reflection past the critical angle. The front side (normal +z) faces the outside medium
 * (index 1), the back the inside (index ior). Radiance crossing into a denser medium is concentrated
 * by (n_i / n_t)^2 (pbrt's radiance transport mode); `color` tints transmission. */
#ifndef PATHCL_BSDF_DIELECTRIC_CL
#define PATHCL_BSDF_DIELECTRIC_CL

/* Written once over lanes, as bsdf_diffuse.cl's lobes (colour and ior per lane; reflection or refraction
 * a per-lane select); *eta2 is (n_t / n_i)^2 where the weight was divided by it, else 1. The mask: where
 * the sample is valid. */
#define PC_DIELECTRIC_LANES(V3, F, I)                                                                     \
  inline PC_OVL I dielectric_sample_lanes(V3 c, F ior, V3 wo, F u2, V3* wi, F* pdf, V3* weight, F* eta2) { \
    I entering = wo.z > 0.0f;                                                                             \
    F eta = select(1.0f / ior, ior, entering); /* n_t / n_i */                                            \
    F f = fresnel_dielectric(fabs(wo.z), eta);                                                            \
    I reflected = u2 < f;                                                                                 \
    V3 wt, wr = reflect_local(wo);                                                                        \
    I refracted = refract_dir(wo, lane3((F)(0.0f), (F)(0.0f), select((F)(-1.0f), (F)(1.0f), entering)), eta, &wt); \
    F e2 = eta * eta;                                                                                     \
    *wi = lane3(select(wt.x, wr.x, reflected), select(wt.y, wr.y, reflected), select(wt.z, wr.z, reflected)); \
    *weight = lane3(select(c.x / e2, (F)(1.0f), reflected), select(c.y / e2, (F)(1.0f), reflected),       \
                    select(c.z / e2, (F)(1.0f), reflected));                                              \
    *eta2 = select(e2, (F)(1.0f), reflected);                                                             \
    *pdf = select(1.0f - f, f, reflected);                                                                \
    return reflected | refracted; /* not refracted: unreachable, f == 1 there */                          \
  }
PC_DIELECTRIC_LANES(lane3f, float, int)
PC_DIELECTRIC_LANES(lane3f8, float8, int8)
PC_DIELECTRIC_LANES(lane3f16, float16, int16)
#undef PC_DIELECTRIC_LANES

#endif
