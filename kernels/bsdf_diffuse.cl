/* Lambertian reflection. Local frame (normal +z), wo.z > 0 (bsdf.cl mirrors back-side hits). */
#ifndef PATHCL_BSDF_DIFFUSE_CL
#define PATHCL_BSDF_DIFFUSE_CL

/* Test builds only (RenderOptions::debug_bias_diffuse): a 1 % error that `pathcl bench`'s gate must catch. */
#ifdef PC_DEBUG_BIAS_DIFFUSE
#define PC_DIFFUSE_SCALE 1.01f
#else
#define PC_DIFFUSE_SCALE 1.0f
#endif

/* Written once over lanes (V3 lane3f/lane3f8/lane3f16, F, I their float and int types; issue 15): c is the
 * reflectance per lane and branches are per-lane selects, so every lane gets the one-lane bits
 * (tests/bsdf_test.cpp, LobesGiveTheOneLaneBits); bsdf.cl dispatches to these at every width, one included. */
#define PC_DIFFUSE_LANES(V3, F, I)                                                                        \
  inline PC_OVL V3 diffuse_eval_lanes(V3 c, V3 wi) {                                                      \
    I above = wi.z > 0.0f;                                                                                \
    return lane3(select((F)(0.0f), c.x * PC_DIFFUSE_SCALE * PC_INV_PI, above),                            \
                 select((F)(0.0f), c.y * PC_DIFFUSE_SCALE * PC_INV_PI, above),                            \
                 select((F)(0.0f), c.z * PC_DIFFUSE_SCALE * PC_INV_PI, above));                           \
  }                                                                                                       \
  inline PC_OVL F diffuse_pdf_lanes(V3 wi) { return fmax(wi.z, 0.0f) * PC_INV_PI; }                       \
  /* Cosine-weighted wi; weight = f cos / pdf = reflectance. The mask: where the sample is valid. */     \
  inline PC_OVL I diffuse_sample_lanes(V3 c, F u0, F u1, V3* wi, F* pdf, V3* weight) {                    \
    F x, y, z;                                                                                            \
    sample_cosine_hemisphere_lanes(u0, u1, &x, &y, &z);                                                   \
    *wi = lane3(x, y, z);                                                                                 \
    *pdf = diffuse_pdf_lanes(*wi);                                                                        \
    *weight = lane3(c.x * PC_DIFFUSE_SCALE, c.y * PC_DIFFUSE_SCALE, c.z * PC_DIFFUSE_SCALE);              \
    return *pdf > 0.0f;                                                                                   \
  }
PC_DIFFUSE_LANES(lane3f, float, int)
PC_DIFFUSE_LANES(lane3f8, float8, int8)
PC_DIFFUSE_LANES(lane3f16, float16, int16)
#undef PC_DIFFUSE_LANES

#endif
