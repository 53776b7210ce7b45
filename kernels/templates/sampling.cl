/* The warps' lane functions: a template, included by sampling.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

/* A point on the unit disk, area-preserving (Shirley and Chiu's concentric map). */
static inline PC_OVL void sample_concentric_disk_lanes(F ux, F uy, F* x, F* y) {
  F ox = 2.0f * ux - 1.0f, oy = 2.0f * uy - 1.0f;
  I centre = (ox == 0.0f) & (oy == 0.0f), x_major = fabs(ox) > fabs(oy);
  F r = select(oy, ox, x_major);
  F phi = select((PC_PI / 2.0f) - (PC_PI / 4.0f) * (ox / oy), (PC_PI / 4.0f) * (oy / ox), x_major);
  F c, s = pc_sincos(phi, &c);
  *x = select(r * c, (F)(0.0f), centre);
  *y = select(r * s, (F)(0.0f), centre);
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
