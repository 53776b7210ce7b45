/* Perspective camera: pixel row 0 is the top of the image; each pixel is sampled uniformly (box filter). */
#ifndef PATHCL_CAMERA_CL
#define PATHCL_CAMERA_CL

inline float3 camera_direction(__constant const SceneHeader* h, uint px, uint py, float2 jitter) {
  float sx = 2.0f * ((float)px + jitter.x) / (float)h->width - 1.0f;
  float sy = 1.0f - 2.0f * ((float)py + jitter.y) / (float)h->height;
  return normalize(h->cam_forward.xyz + sx * h->cam_right.xyz + sy * h->cam_up.xyz);
}

#endif
