// Binned SAH BVH over primitive bounding boxes, flattened depth-first into 32-byte BvhNodes.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include "kernels/shared/types.h"
#include "scene/device_scene.h"

// The binary tree's nodes are BvhNodes (kernels/shared/types.h), flattened depth-first; leaves hold
// primitives in leaf order. The device gets the wide trees collapsed from it (collapse_to_bvh4/8).

struct Aabb {
  glm::vec3 lo{1e30f}, hi{-1e30f};
  // Inline: the BVH build calls them for every primitive at every level.
  void grow(const glm::vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void grow(const Aabb& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  float half_area() const;  // surface area / 2; 0 for an empty box
};

// The kernel's traversal stack holds this many entries; the builder guarantees a tree no deeper.
constexpr uint32_t kBvhMaxDepth = 64;
// Leaves hold at most this many primitives (a 4-bit count in Bvh4Node references).
constexpr uint32_t kBvhMaxLeafSize = 16;

struct Bvh : BvhStats {
  std::vector<BvhNode> nodes;       // nodes[0] is the root
  std::vector<uint32_t> prim_order; // leaf slot -> primitive index
};

Bvh build_bvh(const std::vector<Aabb>& prim_boxes);

// The device's wide BVHs (kernels/shared/types.h): each wide node takes up to four (Bvh4Node) or eight
// (Bvh8Node) subtrees of the binary tree, so a traversal step tests four or eight boxes at once; the used
// child slots come first. Primitive order is the binary tree's. Its depth is at most the binary tree's,
// which bounds the kernel's stack (kernels/intersect.cl). Needs fewer than PC_BVH4_MAX_LEAF_FIRST
// primitives and leaves of at most 16.
template <class Node>
struct WideBvh {
  std::vector<Node> nodes;  // nodes[0] is the root
  uint32_t depth = 0;
};
using Bvh4 = WideBvh<Bvh4Node>;
using Bvh8 = WideBvh<Bvh8Node>;
using Bvh16 = WideBvh<Bvh16Node>;
// The 4-wide tree: the binary tree's leaves, each node's children found by opening the child of largest
// surface area first.
Bvh4 collapse_to_bvh4(const std::vector<BvhNode>& binary);
// The 8-wide (16-wide) tree: of all the ways to collapse the binary tree into nodes of at most 8 (16)
// children whose leaves are binary subtrees (of at most 16 primitives), the one of least SAH cost, where a
// node visited costs kWideNodeCost and a leaf kLeafCost and kLeafBlockCost for each block of four
// primitives it is tested in. Its references are node indices and, for leaves, primitive slots as in
// Bvh4Node, until append_wide_bvh. Without kLeafCost (a block's bookkeeping, and a packet's test of each
// of its blocks) the 16-wide collapse split the Cornell box's few triangles into sixteen half-empty leaves,
// and its packets ran 5 % slower (docs/benchmarks-notes.md).
constexpr float kWideNodeCost = 1, kLeafCost = 1, kLeafBlockCost = 1;
Bvh8 collapse_to_bvh8(const std::vector<BvhNode>& binary);
Bvh16 collapse_to_bvh16(const std::vector<BvhNode>& binary);
// Appends the 8- or 16-wide tree (Node: Bvh8Node or Bvh16Node) to its array (bvh8 or bvh16) in the device's
// layout (kernels/shared/types.h): each node, then its leaf children's LeafBlocks of prims (whose slots the
// leaf references hold), references rewritten to word offsets in the array. Returns the root's. Throws
// std::length_error past PC_BVH8_MAX_WORDS.
template <class Node>
uint32_t append_wide_bvh(const std::vector<Node>& nodes, const std::vector<Primitive>& prims,
                         std::vector<pc_float4>& wide);
// The node (Bvh8Node or Bvh16Node), or block, at word offset at of bvh8 or bvh16 (a copy).
template <class Node>
Node wide_bvh_node(const std::vector<pc_float4>& wide, uint32_t at);
LeafBlock wide_bvh_block(const std::vector<pc_float4>& wide, uint32_t at);
