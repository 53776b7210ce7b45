/* Camera rays: a pinhole or thin-lens perspective camera; pixel row 0 is the top of the image. The
 * pixel filter (box, tent, Gaussian) is applied by filter importance sampling: each sample's image
 * position is drawn from the filter around the pixel centre and every sample has weight 1, so no
 * splatting is needed and a pixel stays a pure function of its own samples. */
#ifndef PATHCL_CAMERA_CL
#define PATHCL_CAMERA_CL

/* Inverse error function, single precision (Giles 2010). */
inline float erf_inverse(float x) {
  float w = -pc_log(fmax((1.0f - x) * (1.0f + x), FLT_MIN)), p;
  if (w < 5.0f) {
    w -= 2.5f;
    p = 2.81022636e-08f;
    p = 3.43273939e-07f + p * w;
    p = -3.5233877e-06f + p * w;
    p = -4.39150654e-06f + p * w;
    p = 0.00021858087f + p * w;
    p = -0.00125372503f + p * w;
    p = -0.00417768164f + p * w;
    p = 0.246640727f + p * w;
    p = 1.50140941f + p * w;
  } else {
    w = sqrt(w) - 3.0f;
    p = -0.000200214257f;
    p = 0.000100950558f + p * w;
    p = 0.00134934322f + p * w;
    p = -0.00367342844f + p * w;
    p = 0.00573950773f + p * w;
    p = -0.0076224613f + p * w;
    p = 0.00943887047f + p * w;
    p = 1.00167406f + p * w;
    p = 2.83297682f + p * w;
  }
  return p * x;
}

/* An offset from the pixel centre, in pixels, distributed as the filter along one axis. */
inline float sample_filter_1d(__constant const SceneHeader* h, float u) {
  float r = h->filter_radius;
  if (h->filter == PC_FILTER_TENT) return u < 0.5f ? r * (sqrt(2.0f * u) - 1.0f) : r * (1.0f - sqrt(2.0f - 2.0f * u));
  if (h->filter == PC_FILTER_GAUSSIAN) {
    /* Truncated to [-r, r] by inverting the normal CDF between its values there. */
    float s = h->filter_sigma * sqrt(2.0f);
    float e = pc_erf(r / s);
    return clamp(s * erf_inverse((2.0f * u - 1.0f) * e), -r, r);
  }
  return u - 0.5f;
}

/* u.xy: position in the pixel (through the filter), u.zw: position on the lens. */
inline void camera_ray(__constant const SceneHeader* h, uint px, uint py, float4 u, float3* o, float3* d) {
  float fx = (float)px + 0.5f + sample_filter_1d(h, u.x);
  float fy = (float)py + 0.5f + sample_filter_1d(h, u.y);
  float sx = 2.0f * fx / (float)h->width - 1.0f;
  float sy = 1.0f - 2.0f * fy / (float)h->height;
  float3 pinhole = h->cam_forward.xyz + sx * h->cam_right.xyz + sy * h->cam_up.xyz; /* forward part 1 */
  *o = h->cam_position.xyz;
  if (h->lens_radius > 0.0f) {
    /* Thin lens: rays through the lens meet where the pinhole ray meets the plane in focus. */
    float2 lens = h->lens_radius * sample_concentric_disk(u.zw);
    float3 offset = lens.x * pc_normalize(h->cam_right.xyz) + lens.y * pc_normalize(h->cam_up.xyz);
    *o = h->cam_position.xyz + offset;
    *d = pc_normalize(h->focus_distance * pinhole - offset);
    return;
  }
  *d = pc_normalize(pinhole);
}

#endif
