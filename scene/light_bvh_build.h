// The light BVH: a binary tree over the scene's finite lights (area, point, spot) whose nodes bound where
// the lights are, how strongly they emit and in which directions, so that the kernel can choose a light in
// proportion to an estimate of its irradiance at the shading point (kernels/light_tree.cl). The anchors are
// pbrt-v4's BVHLightSampler and Cycles' light tree; the importance is pbrt-v4's, the split a median split.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "kernels/shared/types.h"

// What the tree knows of one light, in device coordinates.
struct LightBounds {
  glm::vec3 lo, hi;     // a box around the light (a point for point and spot lights)
  double intensity = 0; // peak radiant intensity, luminance (W/sr): I for point and spot lights, L x area
                        // for triangles (along the normal), L x pi r^2 for spheres (every direction)
  glm::vec3 axis{0, 0, 1};
  double theta_o = 0;   // every emission axis is within theta_o of axis
  double theta_e = 0;   // and the light emits within theta_e of its axis
  bool two_sided = false;
  // In the leaf of the light before it: an emitter group, lights that the tree does not tell apart (a small
  // planar lamp's triangles of one emission, scene/device_scene_build.cpp). The kernel chooses among a leaf's
  // lights in proportion to Light::group_share, so a quad or disk lamp costs a scene no walk of the tree.
  bool with_previous = false;
};

// A cone of directions: every direction within theta of axis (theta = pi: all of them).
struct DirectionCone {
  glm::dvec3 axis{0, 0, 1};
  double theta = 0;
};
// The smallest cone (of this construction, pbrt-v4's) that holds both.
DirectionCone cone_union(const DirectionCone& a, const DirectionCone& b);

struct LightBvh {
  std::vector<LightBvhNode> nodes;  // depth-first; empty when there are no lights
  std::vector<uint32_t> leaf_of;    // lights[i]'s leaf node
};

// Each light, or each emitter group (a light and those after it with_previous), becomes a leaf whose
// LightBvhNode::light is its first light. Nodes are split at the median centroid along the centroids'
// longest axis: a balanced tree of depth ceil(log2 n) over n leaves.
LightBvh build_light_bvh(const std::vector<LightBounds>& lights);
