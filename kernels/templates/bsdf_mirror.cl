/* The mirror's lane functions: a template, included by bsdf_mirror.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

static inline PC_OVL I mirror_sample_lanes(V3 c, V3 wo, V3* wi, F* pdf, V3* weight) {
  *wi = reflect_local(wo);
  *weight = c;
  *pdf = 1.0f;
  return wo.z > 0.0f;
}

#include "templates/lane_width_end.h"
