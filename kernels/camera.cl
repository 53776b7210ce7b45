/* Camera rays: a pinhole or thin-lens perspective camera; pixel row 0 is the top of the image. The
 * pixel filter (box, tent, Gaussian) is applied by filter importance sampling: each sample's image
 * position is drawn from the filter around the pixel centre and every sample has weight 1, so no
 * splatting is needed and a pixel stays a pure function of its own samples. */
#ifndef PATHCL_CAMERA_CL
#define PATHCL_CAMERA_CL

/* Written once over lanes (F float for one lane, float8/float16 for a lane-generic kernel, issue 15; the
 * uniform camera and filter settings branch as before, the rest selects per lane), with the one-lane
 * instances below: every lane gets the one-lane bits (tests/camera_sampling_test.cpp). */
#define PC_LANE_W 1
#include "templates/camera.cl"
#define PC_LANE_W 8
#include "templates/camera.cl"
#define PC_LANE_W 16
#include "templates/camera.cl"

/* u.xy: position in the pixel (through the filter), u.zw: position on the lens. */
static inline void camera_ray(__constant const SceneHeader* h, uint px, uint py, float4 u, float3* o, float3* d) {
  lane3f lo, ld;
  camera_ray_lanes(h, px, py, u.x, u.y, u.z, u.w, &lo, &ld);
  *o = (float3)(lo.x, lo.y, lo.z);
  *d = (float3)(ld.x, ld.y, ld.z);
}

#endif
