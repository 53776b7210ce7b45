/* The smooth dielectric's lane functions: a template, included by bsdf_dielectric.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

static inline PC_OVL I dielectric_sample_lanes(V3 c, F ior, V3 wo, F u2, V3* wi, F* pdf, V3* weight, F* eta2) {
  I entering = wo.z > 0.0f;
  F eta = select(1.0f / ior, ior, entering); /* n_t / n_i */
  F f = fresnel_dielectric(fabs(wo.z), eta);
  I reflected = u2 < f;
  V3 wt, wr = reflect_local(wo);
  I refracted = refract_dir(wo, lane3((F)(0.0f), (F)(0.0f), select((F)(-1.0f), (F)(1.0f), entering)), eta, &wt);
  F e2 = eta * eta;
  *wi = lane3(select(wt.x, wr.x, reflected), select(wt.y, wr.y, reflected), select(wt.z, wr.z, reflected));
  *weight = lane3(select(c.x / e2, (F)(1.0f), reflected), select(c.y / e2, (F)(1.0f), reflected),
                  select(c.z / e2, (F)(1.0f), reflected));
  *eta2 = select(e2, (F)(1.0f), reflected);
  *pdf = select(1.0f - f, f, reflected);
  return reflected | refracted; /* not refracted: unreachable, f == 1 there */
}

/* A thin sheet of glass (a window pane): the light reflected inside the sheet summed over its bounces,
 * R' = R + T^2 R / (1 - R^2) = 2 R / (1 + R) with R the Fresnel reflectance of one face and T = 1 - R;
 * what is not reflected passes straight through (no offset, no bending, no radiance scaling), tinted by c.
 * Both sides alike (the caller flips wo to +z). */
static inline PC_OVL I thin_dielectric_sample_lanes(V3 c, F ior, V3 wo, F u2, V3* wi, F* pdf, V3* weight) {
  F r = fresnel_dielectric(fabs(wo.z), ior);
  r = 2.0f * r / (1.0f + r);
  I reflected = u2 < r;
  *wi = lane3(-wo.x, -wo.y, select(-wo.z, wo.z, reflected));
  *weight = lane3(select(c.x, (F)(1.0f), reflected), select(c.y, (F)(1.0f), reflected), select(c.z, (F)(1.0f), reflected));
  *pdf = select(1.0f - r, r, reflected);
  return wo.z != 0.0f;
}

#include "templates/lane_width_end.h"
