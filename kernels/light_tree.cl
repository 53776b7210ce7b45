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
#include "lanes.cl"

/* The largest float below 1: where a rescaled u must stay. */
#define PC_ONE_MINUS_EPSILON 0x1.fffffep-1f

/* Written once over the program's lanes (kernels/lanes.cl): each lane walks the tree on its own; where the
 * lanes' walks are at a few nodes (the top of the tree, or a tree of few lights), each is loaded once
 * (lane_groups). */

/* a's share of a + b: 1/2 when both are 0, all or nothing when the sum overflows. */
PC_LANE_INLINE LaneF share_of_lanes(LaneF a, LaneF b) {
  LaneF total = a + b;
  LaneF infinite = select((LaneF)(0.0f), select((LaneF)(1.0f), (LaneF)(0.5f), isinf(b)), isinf(a));
  return select(select(a / total, infinite, isinf(total)), (LaneF)(0.5f), !(total > 0.0f));
}

/* cos and sin of max(0, a - b) from the cosines and sines of angles a, b in [0, pi]. */
PC_LANE_INLINE LaneF cos_of_difference_clamped_lanes(LaneF cos_a, LaneF sin_a, LaneF cos_b, LaneF sin_b, LaneF* sin_out) {
  LaneI none = cos_a >= cos_b;
  *sin_out = select(fmax(0.0f, sin_a * cos_b - cos_a * sin_b), (LaneF)(0.0f), none);
  return select(cos_a * cos_b + sin_a * sin_b, (LaneF)(1.0f), none);
}

/* The importance of node[index] at x (see the top of the file), for the lanes in m (the others: any value).
 * From inside the node's bounding sphere every direction is possible and the distance is that sphere's
 * radius. Out of line: light_choice_lanes calls it three times, and the inlined copies were an eighth of the
 * path program's code (samples/s the same within noise, 1000 emitters included). */
PC_OUT_OF_LINE LaneF light_bounds_importance_lanes(__global const LightBvhNode* nodes, LaneU index, Lane3 x, LaneI m) {
  Lane3 lo, hi, axis;
  LaneF power, cos_o, cos_e;
  LaneI two_sided;
  LaneGroups at;
  lane_groups(index, m, &at);
  lo = lane_group_gather3(PC_FIELD_F(nodes, lo), &at), hi = lane_group_gather3(PC_FIELD_F(nodes, hi), &at);
  axis = lane_group_gather3(PC_FIELD_F(nodes, axis), &at);
  power = lane_group_gather_float(PC_FIELD_AT(nodes, lo, 3), &at);
  cos_o = lane_group_gather_float(PC_FIELD_AT(nodes, hi, 3), &at);
  cos_e = lane_group_gather_float(PC_FIELD_AT(nodes, axis, 3), &at);
  two_sided = lane_group_gather_uint(PC_FIELD_U(nodes, two_sided), &at) != 0u;
  Lane3 half_extent = lane3_scale(lane3_sub(hi, lo), 0.5f);
  Lane3 d = lane3_sub(x, lane3_add(lo, half_extent));
  LaneF r2 = pc_dot(half_extent, half_extent), d2 = pc_dot(d, d);
  /* theta_b: half the angle the bounding sphere subtends at x */
  LaneI outside = d2 > r2;
  LaneF sin2_b = r2 / d2;
  LaneF sin_b = select((LaneF)(0.0f), sqrt(sin2_b), outside), cos_b = select((LaneF)(-1.0f), sqrt(1.0f - sin2_b), outside);
  /* theta_w: between the cone's axis and the direction from the node's centre to x */
  LaneF cos_w = select((LaneF)(1.0f), pc_dot(axis, d) / sqrt(d2), d2 > 0.0f);
  cos_w = select(cos_w, fabs(cos_w), two_sided);
  cos_w = fmin(1.0f, fmax(-1.0f, cos_w));
  LaneF sin_w = sqrt(fmax(0.0f, 1.0f - cos_w * cos_w));
  LaneF sin_o = sqrt(fmax(0.0f, 1.0f - cos_o * cos_o));
  /* theta' = max(0, theta_w - theta_o - theta_b) */
  LaneF sin_x, sin_p;
  LaneF cos_x = cos_of_difference_clamped_lanes(cos_w, sin_w, cos_o, sin_o, &sin_x);
  LaneF cos_p = cos_of_difference_clamped_lanes(cos_x, sin_x, cos_b, sin_b, &sin_p);
  /* Distances to the box's nearest and farthest points: the intensity over their squares bounds the
     irradiance from above and below, and the mean of the two (as Cycles' light tree takes) is the
     estimate, exact for a point light. Unlike the distance to the centre (pbrt-v4's), it tells which of
     two large nodes is near (a thousand emitters over a floor: relMSE 0.006 against 0.04). The nearest
     distance is at least the box's thinnest half extent, so that from inside a room-sized node the
     estimate stays finite and the lights at infinity keep their share. */
  Lane3 nearest = lane3(fmax(fabs(d.x) - half_extent.x, 0.0f), fmax(fabs(d.y) - half_extent.y, 0.0f),
                        fmax(fabs(d.z) - half_extent.z, 0.0f));
  Lane3 farthest = lane3_add(lane3_abs(d), half_extent);
  LaneF thinnest = fmin(half_extent.x, fmin(half_extent.y, half_extent.z));
  LaneF dmin2 = fmax(fmax(pc_dot(nearest, nearest), thinnest * thinnest), FLT_MIN);
  LaneF dmax2 = fmax(pc_dot(farthest, farthest), FLT_MIN);
  LaneF importance = power * 0.5f * (1.0f / dmin2 + 1.0f / dmax2) * cos_p;
  /* beyond theta_e: no light of the node reaches x */
  return select(importance, (LaneF)(0.0f), (cos_p < cos_e) | !(cos_p > 0.0f));
}

/* node[index].second for the lanes in m (the others: the first such lane's). */
PC_LANE_INLINE LaneU light_node_second_lanes(__global const LightBvhNode* nodes, LaneU index, LaneI m) {
  LaneGroups at;
  lane_groups(index, m, &at);
  return lane_group_gather_uint(PC_FIELD_U(nodes, second), &at);
}

/* For the lanes in m: where target is PC_INVALID, chooses a light with u and stores its index in *chosen;
 * elsewhere follows the choice of light target. Returns the probability of that choice from x (0: never
 * chosen from x). */
static inline LaneF light_choice_lanes(const SceneData* sc, Lane3 x, LaneU target, LaneF u, LaneI m, LaneU* chosen) {
  __constant const SceneHeader* h = sc->h;
  *chosen = target;
  if (!pc_any_(m)) return (LaneF)(0.0f);
  uint tree_count = h->tree_light_count, infinite_count = h->light_count - tree_count;
  LaneI sampling = target == PC_INVALID;
  LaneF p_infinite = (LaneF)(infinite_count == 0u ? 0.0f : 1.0f);
  if (infinite_count != 0u && tree_count != 0u)
    p_infinite = share_of_lanes((LaneF)(h->infinite_irradiance),
                                light_bounds_importance_lanes(sc->light_bvh, (LaneU)(0u), x, m));
  LaneI infinite = m & select(target >= tree_count, u < p_infinite, sampling);
  LaneF p = (LaneF)(0.0f);
  if (pc_any_(infinite)) {
    LaneF v = fmin(u / p_infinite, PC_ONE_MINUS_EPSILON);
    LaneU index = target;
    PC_EACH_LANE(j, pc_lane_bits(infinite & sampling)) {
      index = pc_with_lane(index, j, tree_count + find_interval(sc->light_cdf, infinite_count, pc_lane(v, j)));
    }
    LaneF share = lane_gather_float(PC_FIELD_F(sc->lights, infinite_share), lane_safe_index(index, infinite));
    p = select(p, p_infinite * share, infinite);
    *chosen = select(*chosen, index, infinite);
  }
  LaneI tree = m & !infinite;
  if (pc_any_(tree)) {
    u = select(u, fmin((u - p_infinite) / (1.0f - p_infinite), PC_ONE_MINUS_EPSILON), sampling);
    LaneU leaf = (LaneU)(0u);
    LaneI following = tree & !sampling;
    if (pc_any_(following)) {
      leaf = select(leaf, lane_gather_uint(PC_FIELD_U(sc->lights, tree_leaf), lane_safe_index(target, following)),
                    following);
    }
    LaneF p_tree = 1.0f - p_infinite;
    LaneU node = (LaneU)(0u);
    for (LaneI walking = tree;;) {
      LaneU second = light_node_second_lanes(sc->light_bvh, node, walking);
      walking &= second != PC_INVALID;
      if (!pc_any_(walking)) break;
      LaneF p_first = share_of_lanes(light_bounds_importance_lanes(sc->light_bvh, node + 1u, x, walking),
                                     light_bounds_importance_lanes(sc->light_bvh, second, x, walking));
      /* Depth-first order: the first child's subtree is [node + 1, second). */
      LaneI first = select(leaf < second, u < p_first, sampling);
      u = select(u, fmin(select((u - p_first) / (1.0f - p_first), u / p_first, first), PC_ONE_MINUS_EPSILON),
                 walking & sampling);
      p_tree = select(p_tree, p_tree * select(1.0f - p_first, p_first, first), walking);
      node = select(node, select(second, node + 1u, first), walking);
    }
    LaneI chose = tree & sampling;
    /* Among the leaf's lights (an emitter group, or one light: scene/light_bvh_build.h), one in proportion to
     * its group_share, by the rest of u: the first whose group_cdf exceeds u (binary search; the last's is 1). */
    if (pc_any_(following))
      p_tree = select(p_tree, p_tree * lane_gather_float(PC_FIELD_F(sc->lights, group_share), lane_safe_index(target, following)),
                      following);
    if (pc_any_(chose)) {
      LaneGroups at;
      lane_groups(node, chose, &at);
      LaneU lo = lane_group_gather_uint(PC_FIELD_U(sc->light_bvh, light), &at);
      LaneU hi = lo + lane_group_gather_uint(PC_FIELD_U(sc->light_bvh, light_count), &at) - 1u;
      for (LaneI searching = chose & (lo < hi); pc_any_(searching); searching &= lo < hi) {
        LaneU mid = (lo + hi) / 2u;
        LaneI above = searching & (u >= lane_gather_float(PC_FIELD_F(sc->lights, group_cdf), lane_safe_index(mid, searching)));
        lo = select(lo, mid + 1u, above);
        hi = select(hi, mid, searching & !above);
      }
      LaneF share = lane_gather_float(PC_FIELD_F(sc->lights, group_share), lane_safe_index(lo, chose));
      p_tree = select(p_tree, p_tree * share, chose);
      *chosen = select(*chosen, lo, chose);
    }
    p = select(p, p_tree, tree);
  }
  return p;
}

#if PC_LANES == 1
/* With target == PC_INVALID: chooses a light with u and stores its index in *chosen. Otherwise follows
 * the choice of light target. Returns the probability of that choice from x. */
static inline float light_choice(const SceneData* sc, float3 x, uint target, float u, uint* chosen) {
  uint index;
  float p = light_choice_lanes(sc, x, target, u, 1, &index);
  if (target == PC_INVALID) *chosen = index;
  return p;
}

/* The probability that sample_light from x chooses light index. */
static inline float light_choice_pdf(const SceneData* sc, float3 x, uint index) {
  uint unused;
  return light_choice(sc, x, index, 0.0f, &unused);
}
#endif

#endif
