/* The camera's lane functions: a template, included by camera.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

/* Inverse error function, single precision (Giles 2010). */
static inline PC_OVL F erf_inverse(F x) {
  F w = -pc_log(fmax((1.0f - x) * (1.0f + x), FLT_MIN)), p = (F)(0.0f);
  I central = w < 5.0f;
  if (pc_any_(central)) {
    F v = w - 2.5f, q;
    q = (F)(2.81022636e-08f);
    q = 3.43273939e-07f + q * v;
    q = -3.5233877e-06f + q * v;
    q = -4.39150654e-06f + q * v;
    q = 0.00021858087f + q * v;
    q = -0.00125372503f + q * v;
    q = -0.00417768164f + q * v;
    q = 0.246640727f + q * v;
    q = 1.50140941f + q * v;
    p = select(p, q, central);
  }
  if (pc_any_(!central)) {
    F v = sqrt(w) - 3.0f, q;
    q = (F)(-0.000200214257f);
    q = 0.000100950558f + q * v;
    q = 0.00134934322f + q * v;
    q = -0.00367342844f + q * v;
    q = 0.00573950773f + q * v;
    q = -0.0076224613f + q * v;
    q = 0.00943887047f + q * v;
    q = 1.00167406f + q * v;
    q = 2.83297682f + q * v;
    p = select(q, p, central);
  }
  return p * x;
}
/* An offset from the pixel centre, in pixels, distributed as the filter along one axis. */
static inline PC_OVL F sample_filter_1d(__constant const SceneHeader* h, F u) {
  float r = h->filter_radius;
  if (h->filter == PC_FILTER_TENT) return select(r * (1.0f - sqrt(2.0f - 2.0f * u)), r * (sqrt(2.0f * u) - 1.0f), u < 0.5f);
  if (h->filter == PC_FILTER_GAUSSIAN) {
    /* Truncated to [-r, r] by inverting the normal CDF between its values there. */
    float s = h->filter_sigma * sqrt(2.0f);
    float e = pc_erf(r / s);
    return clamp(s * erf_inverse((2.0f * u - 1.0f) * e), -r, r);
  }
  return u - 0.5f;
}
/* The camera ray through pixel (px, py) of each lane: u0, u1 the position in the pixel (through the
 * filter), u2, u3 the position on the lens. */
static inline PC_OVL void camera_ray_lanes(__constant const SceneHeader* h, U px, U py, F u0, F u1, F u2, F u3,
                                           V3* o, V3* d) {
  F fx = convert_F(px) + 0.5f + sample_filter_1d(h, u0);
  F fy = convert_F(py) + 0.5f + sample_filter_1d(h, u1);
  F sx = 2.0f * fx / (float)h->width - 1.0f;
  F sy = 1.0f - 2.0f * fy / (float)h->height;
  float4 f = h->cam_forward, r = h->cam_right, up = h->cam_up, c = h->cam_position;
  V3 pinhole = lane3(f.x + sx * r.x + sy * up.x, f.y + sx * r.y + sy * up.y, f.z + sx * r.z + sy * up.z);
  *o = lane3((F)(c.x), (F)(c.y), (F)(c.z));
  if (h->lens_radius > 0.0f) {
    /* Thin lens: rays through the lens meet where the pinhole ray meets the plane in focus. */
    F lx, ly;
    sample_concentric_disk_lanes(u2, u3, &lx, &ly);
    lx = h->lens_radius * lx;
    ly = h->lens_radius * ly;
    float3 nr = pc_normalize(r.xyz), nu = pc_normalize(up.xyz);
    V3 offset = lane3(lx * nr.x + ly * nu.x, lx * nr.y + ly * nu.y, lx * nr.z + ly * nu.z);
    *o = lane3(c.x + offset.x, c.y + offset.y, c.z + offset.z);
    float fd = h->focus_distance;
    *d = pc_normalize(lane3(fd * pinhole.x - offset.x, fd * pinhole.y - offset.y, fd * pinhole.z - offset.z));
    return;
  }
  *d = pc_normalize(pinhole);
}

#include "templates/lane_width_end.h"
