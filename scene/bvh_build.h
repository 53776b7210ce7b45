// Binned SAH BVH over primitive bounding boxes, flattened depth-first into 32-byte BvhNodes.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "kernels/shared/types.h"

struct Aabb {
  glm::vec3 lo{1e30f}, hi{-1e30f};
  void grow(const glm::vec3& p);
  void grow(const Aabb& b);
  float half_area() const;  // surface area / 2; 0 for an empty box
};

// The kernel's traversal stack holds this many entries; the builder guarantees a tree no deeper.
constexpr uint32_t kBvhMaxDepth = 64;

struct Bvh {
  std::vector<BvhNode> nodes;       // nodes[0] is the root
  std::vector<uint32_t> prim_order; // leaf slot -> primitive index
  double sah_cost = 0;              // expected traversal + intersection cost (C_trav = C_isect = 1)
  uint32_t depth = 0, leaf_count = 0, max_leaf_size = 0;
  double build_ms = 0;
};

Bvh build_bvh(const std::vector<Aabb>& prim_boxes);
