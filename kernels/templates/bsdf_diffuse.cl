/* Lambertian reflection's lane functions: a template, included by bsdf_diffuse.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

static inline PC_OVL V3 diffuse_eval_lanes(V3 c, V3 wi) {
  I above = wi.z > 0.0f;
  return lane3(select((F)(0.0f), c.x * PC_DIFFUSE_SCALE * PC_INV_PI, above),
               select((F)(0.0f), c.y * PC_DIFFUSE_SCALE * PC_INV_PI, above),
               select((F)(0.0f), c.z * PC_DIFFUSE_SCALE * PC_INV_PI, above));
}
static inline PC_OVL F diffuse_pdf_lanes(V3 wi) { return fmax(wi.z, 0.0f) * PC_INV_PI; }
/* Cosine-weighted wi; weight = f cos / pdf = reflectance. The mask: where the sample is valid. */
static inline PC_OVL I diffuse_sample_lanes(V3 c, F u0, F u1, V3* wi, F* pdf, V3* weight) {
  F x, y, z;
  sample_cosine_hemisphere_lanes(u0, u1, &x, &y, &z);
  *wi = lane3(x, y, z);
  *pdf = diffuse_pdf_lanes(*wi);
  *weight = lane3(c.x * PC_DIFFUSE_SCALE, c.y * PC_DIFFUSE_SCALE, c.z * PC_DIFFUSE_SCALE);
  return *pdf > 0.0f;
}

#include "templates/lane_width_end.h"
