/* The camera seen from the scene: importance We, its densities and the raster position of a direction
 * (pbrt-v4's PerspectiveCamera::We / PDF_We / SampleWi), for the pinhole and the thin lens of camera.cl.
 * The image plane is the plane at distance 1 along cam_forward, of area A = 4 |cam_right| |cam_up|; a
 * direction at angle theta to the axis through image position (fx, fy) (in pixels, as camera_ray draws
 * them) carries, towards pixel j,
 *   We_j = filter(fx - cx_j) filter(fy - cy_j) W H / (A cos^4 theta)    (divided by pi r^2 with a lens),
 * filter the 1-D density of camera.cl's sample_filter_1d, so that the light tracer estimates the same
 * pixel values as the path tracer. */
#ifndef PATHCL_CAMERA_IMPORTANCE_CL
#define PATHCL_CAMERA_IMPORTANCE_CL

#include "math.cl"
#include "sampling.cl"
#include "camera.cl"

/* The density of sample_filter_1d at offset x (pixels) from the pixel centre. */
static inline float filter_density_1d(__constant const SceneHeader* h, float x) {
  float r = h->filter_radius, ax = fabs(x);
  if (h->filter == PC_FILTER_TENT) return ax < r ? (r - ax) / (r * r) : 0.0f;
  if (h->filter == PC_FILTER_GAUSSIAN) {
    if (!(ax <= r)) return 0.0f;
    float s = h->filter_sigma;
    float norm = pc_erf(r / (s * sqrt(2.0f)));
    return pc_exp(-0.5f * x * x / (s * s)) / (s * sqrt(2.0f * PC_PI) * norm);
  }
  return ax < 0.5f ? 1.0f : 0.0f;
}

static inline float camera_image_area(__constant const SceneHeader* h) {
  return 4.0f * pc_length(h->cam_right.xyz) * pc_length(h->cam_up.xyz);
}

/* The image position (pixels, fractional) of the camera ray from lens point o (device coordinates) in unit
 * direction d; false when d points behind the camera. *cos_theta: d's cosine with the axis. */
static inline bool camera_raster(__constant const SceneHeader* h, float3 o, float3 d, float2* raster, float* cos_theta) {
  float3 fwd = h->cam_forward.xyz; /* unit length */
  float c = pc_dot(d, fwd);
  *cos_theta = c;
  if (!(c > 0.0f)) return false;
  /* The point of the plane in focus (the image plane for a pinhole) the ray meets, as a pinhole direction
     of forward part 1: camera_ray's `pinhole`. */
  float3 offset = o - h->cam_position.xyz;
  float focus = h->lens_radius > 0.0f ? h->focus_distance : 1.0f;
  float3 pinhole = (offset + (focus / c) * d) / focus;
  float3 right = h->cam_right.xyz, up = h->cam_up.xyz;
  float sx = pc_dot(pinhole, right) / pc_dot(right, right), sy = pc_dot(pinhole, up) / pc_dot(up, up);
  *raster = (float2)(0.5f * (sx + 1.0f) * (float)h->width, 0.5f * (1.0f - sy) * (float)h->height);
  return true;
}

/* Importance of the ray from lens point o in direction d summed over the filter, without the filter
 * (pixel count times the directional part): W H / (A cos^4 theta), over pi r^2 for a lens. 0 outside the
 * image (whose border the filter may reach past: rays that land within filter_radius still count). */
static inline float camera_we(__constant const SceneHeader* h, float3 o, float3 d, float2* raster) {
  float c;
  if (!camera_raster(h, o, d, raster, &c)) return 0.0f;
  float r = h->filter_radius;
  if (raster->x <= -r || raster->y <= -r || raster->x >= (float)h->width + r || raster->y >= (float)h->height + r)
    return 0.0f;
  float lens_area = h->lens_radius > 0.0f ? PC_PI * h->lens_radius * h->lens_radius : 1.0f;
  float c2 = c * c;
  return (float)h->width * (float)h->height / (camera_image_area(h) * c2 * c2 * lens_area);
}

/* The density per solid angle of camera ray direction d (unit) from any lens point, the image position
 * uniform over the whole image plane extended past its border (filter excluded): 1 / (A cos^3 theta). */
#define PC_CAMERA_DIRECTION_PDF(V3, F, FORWARD)                                                           \
  static inline PC_OVL F camera_direction_pdf(__constant const SceneHeader* h, V3 d) {                    \
    F c = pc_dot(d, FORWARD);                                                                             \
    return select((F)(0.0f), 1.0f / (camera_image_area(h) * c * c * c), c > 0.0f);                        \
  }
PC_CAMERA_DIRECTION_PDF(float3, float, h->cam_forward.xyz) /* light_path.cl adds the program's lanes */

/* Densities of the camera ray (o, d): the lens point per area (1 for a pinhole: a delta) and the direction
 * per solid angle, pixel position uniform over the image: camera_direction_pdf inside it, 0 outside. */
static inline void camera_pdf_we(__constant const SceneHeader* h, float3 o, float3 d, float* pdf_pos, float* pdf_dir) {
  float2 raster;
  float c;
  *pdf_pos = h->lens_radius > 0.0f ? 1.0f / (PC_PI * h->lens_radius * h->lens_radius) : 1.0f;
  *pdf_dir = 0.0f;
  if (!camera_raster(h, o, d, &raster, &c)) return;
  if (raster.x < 0.0f || raster.y < 0.0f || raster.x >= (float)h->width || raster.y >= (float)h->height) return;
  *pdf_dir = camera_direction_pdf(h, d);
}

typedef struct {
  float3 p;      /* the lens point */
  float3 wi;     /* unit direction from the scene point to p */
  float dist;    /* distance from the scene point to p */
  float2 raster; /* image position (pixels) of the ray from p towards the scene point */
  float We;      /* camera_we of that ray (filter excluded) */
  float pdf;     /* solid-angle density of wi at the scene point: dist^2 / (cos_lens lens area), the lens
                    area 1 for a pinhole (a delta; camera_we is not divided by it either) */
} CameraWiSample;

/* Connects scene point x to the lens: u chooses the lens point. False when the camera cannot see x. */
static inline bool camera_sample_wi(__constant const SceneHeader* h, float3 x, float2 u, CameraWiSample* out) {
  float3 p = h->cam_position.xyz;
  if (h->lens_radius > 0.0f) {
    float2 lens = h->lens_radius * sample_concentric_disk(u);
    p += lens.x * pc_normalize(h->cam_right.xyz) + lens.y * pc_normalize(h->cam_up.xyz);
  }
  float3 to_lens = p - x;
  float dist2 = pc_dot(to_lens, to_lens);
  if (!(dist2 > 0.0f)) return false;
  out->dist = sqrt(dist2);
  out->wi = to_lens / out->dist;
  out->p = p;
  out->We = camera_we(h, p, -out->wi, &out->raster);
  float cos_lens = pc_dot(-out->wi, h->cam_forward.xyz);
  float lens_area = h->lens_radius > 0.0f ? PC_PI * h->lens_radius * h->lens_radius : 1.0f;
  out->pdf = dist2 / (cos_lens * lens_area);
  return out->We > 0.0f && cos_lens > 0.0f;
}

#endif
