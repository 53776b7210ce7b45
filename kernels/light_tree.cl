/* Choosing a light from a shading point x (pbrt-v4's BVHLightSampler and Cycles' light tree are the
 * anchors). The finite lights (area, point, spot) are the leaves of the light BVH; at each node the walk
 * takes a child in proportion to its importance at x, an estimate of the irradiance its lights give a
 * surface facing them: peak intensity x cos(theta') / distance^2 (below), with theta' the smallest angle that the
 * node's cone of emission can make with a direction to x (zero where no light of the node can reach x).
 * The lights at infinity (directional, environment) are chosen beside the tree, with probability
 *   p_inf(x) = E_inf / (E_inf + importance of the root at x),
 * E_inf their irradiance estimate (SceneHeader.infinite_irradiance). Both sides are irradiances at x, so
 * no scene size enters the proportion (choice by power weighed an environment by the scene's bounding
 * radius squared). Among themselves the lights at infinity are chosen by light_cdf.
 *
 * light_choice is written once for both directions: it chooses a light, or follows the path to a given
 * one, with the same operations, so the probability that MIS reads for a light hit by a BSDF-sampled ray
 * is bit for bit the probability with which sample_light would have chosen it from the same x. */
#ifndef PATHCL_LIGHT_TREE_CL
#define PATHCL_LIGHT_TREE_CL

#include "math.cl"
#include "sampling.cl"
#include "scene.cl"

/* a's share of a + b: 1/2 when both are 0, all or nothing when the sum overflows. */
inline float share_of(float a, float b) {
  float total = a + b;
  if (!(total > 0.0f)) return 0.5f;
  if (isinf(total)) return isinf(a) ? (isinf(b) ? 0.5f : 1.0f) : 0.0f;
  return a / total;
}

/* cos and sin of max(0, a - b) from the cosines and sines of angles a, b in [0, pi]. */
inline float cos_of_difference_clamped(float cos_a, float sin_a, float cos_b, float sin_b, float* sin_out) {
  if (cos_a >= cos_b) {
    *sin_out = 0.0f;
    return 1.0f;
  }
  *sin_out = fmax(0.0f, sin_a * cos_b - cos_a * sin_b);
  return cos_a * cos_b + sin_a * sin_b;
}

/* The node's importance at x (see the top of the file). From inside the node's bounding sphere every
 * direction is possible and the distance is that sphere's radius. */
inline float light_bounds_importance(LightBvhNode nd, float3 x) {
  float3 half_extent = 0.5f * (nd.hi.xyz - nd.lo.xyz);
  float3 d = x - (nd.lo.xyz + half_extent);
  float r2 = pc_dot(half_extent, half_extent), d2 = pc_dot(d, d);
  /* theta_b: half the angle the bounding sphere subtends at x */
  float cos_b = -1.0f, sin_b = 0.0f;
  if (d2 > r2) {
    float sin2_b = r2 / d2;
    sin_b = sqrt(sin2_b);
    cos_b = sqrt(1.0f - sin2_b);
  }
  /* theta_w: between the cone's axis and the direction from the node's centre to x */
  float cos_w = d2 > 0.0f ? pc_dot(nd.axis.xyz, d) / sqrt(d2) : 1.0f;
  if (nd.two_sided) cos_w = fabs(cos_w);
  cos_w = fmin(1.0f, fmax(-1.0f, cos_w));
  float sin_w = sqrt(fmax(0.0f, 1.0f - cos_w * cos_w));
  float cos_o = nd.hi.w, sin_o = sqrt(fmax(0.0f, 1.0f - cos_o * cos_o));
  /* theta' = max(0, theta_w - theta_o - theta_b) */
  float sin_x, sin_p;
  float cos_x = cos_of_difference_clamped(cos_w, sin_w, cos_o, sin_o, &sin_x);
  float cos_p = cos_of_difference_clamped(cos_x, sin_x, cos_b, sin_b, &sin_p);
  if (cos_p < nd.axis.w || !(cos_p > 0.0f)) return 0.0f; /* beyond theta_e: no light of the node reaches x */
  /* Distances to the box's nearest and farthest points: the intensity over their squares bounds the
     irradiance from above and below, and the mean of the two (as Cycles' light tree takes) is the
     estimate, exact for a point light. Unlike the distance to the centre (pbrt-v4's), it tells which of
     two large nodes is near (a thousand emitters over a floor: relMSE 0.006 against 0.04). The nearest
     distance is at least the box's thinnest half extent, so that from inside a room-sized node the
     estimate stays finite and the lights at infinity keep their share. */
  float3 nearest = fmax(fabs(d) - half_extent, 0.0f), farthest = fabs(d) + half_extent;
  float thinnest = fmin(half_extent.x, fmin(half_extent.y, half_extent.z));
  float dmin2 = fmax(fmax(pc_dot(nearest, nearest), thinnest * thinnest), FLT_MIN), dmax2 = fmax(pc_dot(farthest, farthest), FLT_MIN);
  return nd.lo.w * 0.5f * (1.0f / dmin2 + 1.0f / dmax2) * cos_p;
}

/* The largest float below 1: where a rescaled u must stay. */
#define PC_ONE_MINUS_EPSILON 0x1.fffffep-1f

/* With target == PC_INVALID: chooses a light with u and stores its index in *chosen. Otherwise follows
 * the choice of light target. Returns the probability of that choice from x (0: never chosen from x). */
inline float light_choice(const SceneData* sc, float3 x, uint target, float u, uint* chosen) {
  __constant const SceneHeader* h = sc->h;
  uint tree_count = h->tree_light_count, infinite_count = h->light_count - tree_count;
  bool sampling = target == PC_INVALID;
  float p_infinite = infinite_count == 0 ? 0.0f
                     : tree_count == 0   ? 1.0f
                                         : share_of(h->infinite_irradiance, light_bounds_importance(sc->light_bvh[0], x));
  if (sampling ? u < p_infinite : target >= tree_count) {
    if (sampling) {
      float v = fmin(u / p_infinite, PC_ONE_MINUS_EPSILON);
      target = tree_count + find_interval(sc->light_cdf, infinite_count, v);
      *chosen = target;
    }
    return p_infinite * sc->lights[target].infinite_share;
  }
  if (sampling) u = fmin((u - p_infinite) / (1.0f - p_infinite), PC_ONE_MINUS_EPSILON);
  uint leaf = sampling ? 0u : sc->lights[target].tree_leaf;
  float p = 1.0f - p_infinite;
  uint node = 0;
  for (;;) {
    uint second = sc->light_bvh[node].second;
    if (second == PC_INVALID) break;
    float p_first =
        share_of(light_bounds_importance(sc->light_bvh[node + 1], x), light_bounds_importance(sc->light_bvh[second], x));
    /* Depth-first order: the first child's subtree is [node + 1, second). */
    bool first = sampling ? u < p_first : leaf < second;
    if (sampling) u = fmin(first ? u / p_first : (u - p_first) / (1.0f - p_first), PC_ONE_MINUS_EPSILON);
    p *= first ? p_first : 1.0f - p_first;
    node = first ? node + 1 : second;
  }
  if (sampling) *chosen = sc->light_bvh[node].light;
  return p;
}

/* The probability that sample_light from x chooses light index. */
inline float light_choice_pdf(const SceneData* sc, float3 x, uint index) {
  uint unused;
  return light_choice(sc, x, index, 0.0f, &unused);
}

#endif
