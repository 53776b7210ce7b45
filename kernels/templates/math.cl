/* The vector helpers' lane functions: a template, included by math.cl once per lane width
 * PC_LANE_W (1, 8, 16) with templates/lane_width.h's types F, I, U and V3. */
#include "templates/lane_width.h"

/* An orthonormal basis around unit n (Duff et al. 2017). */
static inline PC_OVL void make_frame(V3 n, V3* t, V3* b) {
  F s = select((F)(-1.0f), (F)(1.0f), n.z >= 0.0f);
  F a = -1.0f / (s + n.z);
  F c = n.x * n.y * a;
  *t = lane3(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
  *b = lane3(c, s + n.y * n.y * a, -n.y);
}
/* p + offset, then one float further in offset's direction: nextafter(p + offset, +-INFINITY) by offset's
 * sign (p + offset itself where offset is 0 or NaN), by a step of the bits: the same bits for every value,
 * zeros, denormals and infinities included (NaN stays). PoCL's nextafter is a call per lane: offset_ray_origin
 * was a sixth of a BDPT sample's time at one lane. One step serves both directions: the magnitude grows where
 * p + offset has offset's sign and shrinks where not; from a zero, the least denormal of offset's sign; the
 * infinity of offset's sign stays. A step up and a step down selected by the sign took 337 instructions a
 * sample of the Cornell box (8 lanes, AVX2 code, cachegrind) in offset_ray_origin, this about 207. */
static inline PC_OVL F pc_offset_component_(F p, F offset) {
  F po = p + offset;
  U b = as_U(po), o = as_U(offset), magnitude = b & 0x7fffffffu;
  U differ = as_U(as_I(b ^ o) >> 31); /* all ones where the signs differ */
  U stepped = select(b + 1u + (differ << 1), (o & 0x80000000u) | 1u, magnitude == 0u);
  I keep = (magnitude > 0x7f800000u) | ((magnitude == 0x7f800000u) & (differ == 0u)) | (offset == 0.0f) | isnan(offset);
  return select(as_F(stepped), po, keep);
}
/* Moves p off the surface with normal n, by the error bound err, to the side of direction w, and
 * rounds away from the surface (pbrt-v4 OffsetRayOrigin), so a spawned ray cannot re-hit the surface
 * it left. */
static inline PC_OVL V3 offset_ray_origin(V3 p, V3 err, V3 n, V3 w) {
  F d = pc_dot(lane3(fabs(n.x), fabs(n.y), fabs(n.z)), err);
  I back = pc_dot(w, n) < 0.0f;
  F ox = d * n.x, oy = d * n.y, oz = d * n.z;
  ox = select(ox, -ox, back);
  oy = select(oy, -oy, back);
  oz = select(oz, -oz, back);
  return lane3(pc_offset_component_(p.x, ox), pc_offset_component_(p.y, oy), pc_offset_component_(p.z, oz));
}
static inline PC_OVL F luminance_lanes(V3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }
static inline PC_OVL F power_heuristic(F pdf_a, F pdf_b) {
  F a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  I squares = (a + b > 0.0f) & isfinite(a + b);
  F weight = a / (a + b);
  /* Where the squares overflowed (a light sampled from 1e18 away has a pdf of 1e36: inf / inf was
   * NaN) or underflowed: the same weight from the ratio of the pdfs (rare: its two divisions only
   * where a lane needs them). */
  if (pc_any_(!squares)) {
    F r = pdf_b / pdf_a;
    F from_ratio = select(1.0f / (1.0f + r * r), (F)(0.0f), !(pdf_a > 0.0f));
    weight = select(from_ratio, weight, squares);
  }
  return weight;
}

#include "templates/lane_width_end.h"
