#include "scene/light_bvh_build.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <numeric>

#include <glm/geometric.hpp>

namespace {

// A box, an intensity and a cone, as the nodes hold them before they are written as floats.
struct NodeBounds {
  glm::vec3 lo{FLT_MAX}, hi{-FLT_MAX};
  double intensity = 0;
  DirectionCone cone;
  double theta_e = 0;
  bool two_sided = false;
  bool empty = true;
};

NodeBounds bounds_of(const LightBounds& l) {
  NodeBounds b;
  b.lo = l.lo;
  b.hi = l.hi;
  b.intensity = l.intensity;
  b.cone = {glm::normalize(glm::dvec3(l.axis)), l.theta_o};
  b.theta_e = l.theta_e;
  b.two_sided = l.two_sided;
  b.empty = false;
  return b;
}

NodeBounds merge(const NodeBounds& a, const NodeBounds& b) {
  if (a.empty) return b;
  if (b.empty) return a;
  NodeBounds m;
  m.lo = glm::min(a.lo, b.lo);
  m.hi = glm::max(a.hi, b.hi);
  m.intensity = a.intensity + b.intensity;
  // A two-sided light's cone holds its axis and the opposite one: merged with a one-sided light, the
  // node is two-sided (the importance mirrors the direction to x), which bounds both.
  m.cone = cone_union(a.cone, b.cone);
  m.theta_e = std::max(a.theta_e, b.theta_e);
  m.two_sided = a.two_sided || b.two_sided;
  m.empty = false;
  return m;
}

LightBvhNode device_node(const NodeBounds& b) {
  LightBvhNode n{};
  // The importance divides by distances from these corners: a node's box holds its children's boxes
  // because min and max of floats are exact.
  float intensity = float(std::min(b.intensity, double(FLT_MAX)));
  n.lo = {b.lo.x, b.lo.y, b.lo.z, intensity};
  n.hi = {b.hi.x, b.hi.y, b.hi.z, float(std::cos(std::min(b.cone.theta, M_PI)))};
  glm::vec3 axis(b.cone.axis);
  n.axis = {axis.x, axis.y, axis.z, float(std::cos(std::min(b.theta_e, M_PI)))};
  n.second = PC_INVALID;
  n.light = PC_INVALID;
  n.two_sided = b.two_sided ? 1 : 0;
  return n;
}

struct Builder {
  std::vector<NodeBounds> leaves;  // each leaf's bounds: its lights' merged
  std::vector<uint32_t> first, count;  // each leaf's lights
  LightBvh out;

  // Builds the subtree over the leaves order[first, last) at the end of out.nodes; returns its bounds.
  NodeBounds build(std::vector<uint32_t>& order, size_t begin, size_t end) {
    uint32_t index = uint32_t(out.nodes.size());
    out.nodes.emplace_back();
    if (end - begin == 1) {
      uint32_t leaf = order[begin];
      out.nodes[index] = device_node(leaves[leaf]);
      out.nodes[index].light = first[leaf];
      out.nodes[index].light_count = count[leaf];
      for (uint32_t i = 0; i < count[leaf]; ++i) out.leaf_of[first[leaf] + i] = index;
      return leaves[leaf];
    }
    glm::dvec3 clo(INFINITY), chi(-INFINITY);
    for (size_t i = begin; i < end; ++i) {
      glm::dvec3 c = 0.5 * (glm::dvec3(leaves[order[i]].lo) + glm::dvec3(leaves[order[i]].hi));
      clo = glm::min(clo, c);
      chi = glm::max(chi, c);
    }
    glm::dvec3 extent = chi - clo;
    int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    size_t mid = begin + (end - begin) / 2;
    // Ties broken by leaf index, so that the tree does not depend on the sort's implementation.
    std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end, [&](uint32_t a, uint32_t b) {
      float ca = leaves[a].lo[axis] + leaves[a].hi[axis], cb = leaves[b].lo[axis] + leaves[b].hi[axis];
      return ca < cb || (ca == cb && a < b);
    });
    NodeBounds left = build(order, begin, mid);
    uint32_t second = uint32_t(out.nodes.size());
    NodeBounds right = build(order, mid, end);
    NodeBounds b = merge(left, right);
    out.nodes[index] = device_node(b);
    out.nodes[index].second = second;
    return b;
  }
};

}  // namespace

DirectionCone cone_union(const DirectionCone& a, const DirectionCone& b) {
  if (a.theta >= M_PI || b.theta >= M_PI) return {a.axis, M_PI};
  double theta_d = std::acos(std::clamp(glm::dot(a.axis, b.axis), -1.0, 1.0));
  if (theta_d + b.theta <= a.theta) return a;
  if (theta_d + a.theta <= b.theta) return b;
  // The cone from a's far edge to b's far edge: half-angle (theta_a + theta_d + theta_b) / 2, its axis a
  // rotated towards b by that minus theta_a.
  double theta = 0.5 * (a.theta + theta_d + b.theta);
  if (theta >= M_PI) return {a.axis, M_PI};
  double rotate = theta - a.theta;
  glm::dvec3 perpendicular = b.axis - glm::dot(a.axis, b.axis) * a.axis;
  double length = glm::length(perpendicular);
  if (!(length > 1e-12)) return {a.axis, M_PI};  // opposite axes
  glm::dvec3 axis = std::cos(rotate) * a.axis + std::sin(rotate) * (perpendicular / length);
  // Widened by a little more than the float rounding of the axis and the cosines the device reads.
  return {glm::normalize(axis), std::min(M_PI, theta + 1e-5)};
}

LightBvh build_light_bvh(const std::vector<LightBounds>& lights) {
  Builder b;
  if (lights.empty()) return b.out;
  for (uint32_t i = 0; i < lights.size(); ++i) {
    if (i == 0 || !lights[i].with_previous) {
      b.first.push_back(i);
      b.count.push_back(0);
      b.leaves.emplace_back();
    }
    b.count.back()++;
    b.leaves.back() = merge(b.leaves.back(), bounds_of(lights[i]));
  }
  b.out.leaf_of.assign(lights.size(), PC_INVALID);
  b.out.nodes.reserve(2 * b.leaves.size() - 1);
  std::vector<uint32_t> order(b.leaves.size());
  std::iota(order.begin(), order.end(), 0u);
  b.build(order, 0, order.size());
  return b.out;
}
