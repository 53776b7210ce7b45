/* The warps' lane functions: a template, included by sampling.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

/* A point on the unit disk, area-preserving (Shirley and Chiu's concentric map). */
static inline PC_OVL void sample_concentric_disk_lanes(F ux, F uy, F* x, F* y) {
  F ox = 2.0f * ux - 1.0f, oy = 2.0f * uy - 1.0f;
  I centre = (ox == 0.0f) & (oy == 0.0f), x_major = fabs(ox) > fabs(oy);
  F r = select(oy, ox, x_major);
  /* The angle is a = pi/4 (oy / ox) where x is the major axis, else pi/2 - a with a = pi/4 (ox / oy), whose
   * cosine and sine are a's sine and cosine: |a| <= pi/4, so one division and no reduction. */
  F a = (PC_PI / 4.0f) * (select(ox, oy, x_major) / select(oy, ox, x_major));
  F c, s = pc_sincos_quarter(a, &c);
  *x = select(r * select(s, c, x_major), (F)(0.0f), centre);
  *y = select(r * select(c, s, x_major), (F)(0.0f), centre);
}
/* Cosine-weighted direction about +z (Malley's method). */
static inline PC_OVL void sample_cosine_hemisphere_lanes(F ux, F uy, F* x, F* y, F* z) {
  sample_concentric_disk_lanes(ux, uy, x, y);
  *z = sqrt(fmax(0.0f, 1.0f - *x * *x - *y * *y));
}
static inline PC_OVL void sample_uniform_sphere_lanes(F ux, F uy, F* x, F* y, F* z) {
  *z = 1.0f - 2.0f * ux;
  F r = sqrt(fmax(0.0f, 1.0f - *z * *z));
  F phi = 2.0f * PC_PI * uy;
  F c, s = pc_sincos(phi, &c);
  *x = r * c;
  *y = r * s;
}
/* Uniform barycentrics over a triangle: weights of vertices a, b (c gets the rest). */
static inline PC_OVL void sample_uniform_triangle_lanes(F ux, F uy, F* a, F* b) {
  F su = sqrt(ux);
  *a = 1.0f - su;
  *b = uy * su;
}

#include "templates/lane_width_end.h"
