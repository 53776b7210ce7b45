// Binned SAH build (Wald 2007): at each node the centroids are binned along each axis, the cheapest
// plane by the surface area heuristic is taken, and a leaf is made when splitting costs more than
// intersecting every primitive. Nodes are emitted depth-first so the left child follows its parent.
#include "scene/bvh_build.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

float Aabb::half_area() const {
  glm::vec3 e = hi - lo;
  if (e.x < 0 || e.y < 0 || e.z < 0) return 0;
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

namespace {

constexpr int kBins = 32;
constexpr float kTraversalCost = 1, kIntersectionCost = 1;
constexpr uint32_t kMedianSplitDepth = kBvhMaxDepth - 24;  // past this, split by count to bound depth

// The bin of a centroid, given (centroid - lo) * scale. Clamped in float before the conversion to int,
// which is undefined for NaN or out-of-range values: a centroid extent below about 1e-37 makes the scale
// infinite, and 0 * infinity is NaN (found by fuzz/fuzz_scene_json).
int bin_index(float scaled) { return scaled >= float(kBins - 1) ? kBins - 1 : scaled > 0 ? int(scaled) : 0; }

// Subtrees of at least this many primitives build their two children as parallel tasks, the right one into a
// node array of its own that is appended after the left subtree, so the depth-first layout is the one a
// serial build gives, whatever the number of threads and whichever task finishes first.
constexpr uint32_t kParallelSubtree = 8192;
// Nodes of at least twice this many primitives gather their bounds and bins in parallel, over chunks of this
// size whose results are combined in chunk order: a fixed split, so the result does not depend on the
// threads either (and the min and max of a box are the serial ones, ties of -0 and +0 included, because
// keeping the first of equal values is associative).
constexpr uint32_t kParallelChunk = 32768;

struct Bins {
  Aabb box[3][kBins];
  uint32_t count[3][kBins] = {};
};

struct Builder {
  const std::vector<Aabb>& boxes;
  std::vector<glm::vec3> centroids;
  std::vector<uint32_t>& order;  // the Bvh's prim_order; each task partitions its own range of it

  // Bounds of the boxes and of the centroids of order[begin, end).
  void gather_bounds(uint32_t begin, uint32_t end, Aabb& bounds, Aabb& centroid_bounds) const {
    for (uint32_t i = begin; i < end; ++i) {
      bounds.grow(boxes[order[i]]);
      centroid_bounds.grow(centroids[order[i]]);
    }
  }
  void gather_bounds_parallel(uint32_t begin, uint32_t end, Aabb& bounds, Aabb& centroid_bounds) const {
    std::vector<std::pair<Aabb, Aabb>> parts((end - begin + kParallelChunk - 1) / kParallelChunk);
    tbb::parallel_for(size_t(0), parts.size(), [&](size_t c) {
      gather_bounds(begin + uint32_t(c) * kParallelChunk, std::min(end, begin + uint32_t(c + 1) * kParallelChunk),
                    parts[c].first, parts[c].second);
    });
    for (const auto& [box, centroid_box] : parts) {
      bounds.grow(box);
      centroid_bounds.grow(centroid_box);
    }
  }

  // The bins of order[begin, end) along each axis with a scale > 0.
  void gather_bins(uint32_t begin, uint32_t end, const Aabb& centroid_bounds, const glm::vec3& scale, Bins& bins) const {
    // One pass for the three axes; each bin still grows in primitive order.
    const bool binned[3] = {scale.x > 0, scale.y > 0, scale.z > 0};
    for (uint32_t i = begin; i < end; ++i) {
      const uint32_t p = order[i];
      const Aabb& box = boxes[p];
      for (int axis = 0; axis < 3; ++axis) {
        if (!binned[axis]) continue;
        int b = bin_index((centroids[p][axis] - centroid_bounds.lo[axis]) * scale[axis]);
        bins.box[axis][b].grow(box);
        ++bins.count[axis][b];
      }
    }
  }
  void gather_bins_parallel(uint32_t begin, uint32_t end, const Aabb& centroid_bounds, const glm::vec3& scale,
                            Bins& bins) const {
    std::vector<Bins> parts((end - begin + kParallelChunk - 1) / kParallelChunk);
    tbb::parallel_for(size_t(0), parts.size(), [&](size_t c) {
      gather_bins(begin + uint32_t(c) * kParallelChunk, std::min(end, begin + uint32_t(c + 1) * kParallelChunk),
                  centroid_bounds, scale, parts[c]);
    });
    for (const Bins& part : parts)
      for (int axis = 0; axis < 3; ++axis)
        for (int b = 0; b < kBins; ++b) {
          bins.box[axis][b].grow(part.box[axis][b]);
          bins.count[axis][b] += part.count[axis][b];
        }
  }

  // Builds the subtree of order[begin, end) into nodes[index] and the nodes it appends to `nodes`.
  // Interior nodes' left_first are indices into `nodes`.
  void build(std::vector<BvhNode>& nodes, uint32_t index, uint32_t begin, uint32_t end, uint32_t depth) {
    uint32_t count = end - begin;
    const bool parallel = count >= 2 * kParallelChunk;
    Aabb bounds, centroid_bounds;
    if (parallel)
      gather_bounds_parallel(begin, end, bounds, centroid_bounds);
    else
      gather_bounds(begin, end, bounds, centroid_bounds);
    BvhNode& node = nodes[index];
    for (int k = 0; k < 3; ++k) {
      node.lo[k] = bounds.lo[k];
      node.hi[k] = bounds.hi[k];
    }
    float area = bounds.half_area();
    float leaf_cost = kIntersectionCost * float(count);

    int best_axis = -1, best_plane = 0;
    float best_cost = INFINITY;
    glm::vec3 extent = centroid_bounds.hi - centroid_bounds.lo;
    if (count > 1 && depth < kMedianSplitDepth) {
      glm::vec3 scale(0);
      for (int axis = 0; axis < 3; ++axis)
        if (extent[axis] > 0) scale[axis] = kBins / extent[axis];
      Bins bins;
      if (parallel)
        gather_bins_parallel(begin, end, centroid_bounds, scale, bins);
      else
        gather_bins(begin, end, centroid_bounds, scale, bins);
      for (int axis = 0; axis < 3; ++axis) {
        if (!(extent[axis] > 0)) continue;
        const Aabb* bin_box = bins.box[axis];
        const uint32_t* bin_count = bins.count[axis];
        // Sweep from the right to get the right side's area and count for every plane.
        float right_area[kBins];
        uint32_t right_count[kBins];
        Aabb acc;
        uint32_t n = 0;
        for (int b = kBins - 1; b > 0; --b) {
          acc.grow(bin_box[b]);
          n += bin_count[b];
          right_area[b] = acc.half_area();
          right_count[b] = n;
        }
        acc = Aabb();
        n = 0;
        for (int plane = 1; plane < kBins; ++plane) {
          acc.grow(bin_box[plane - 1]);
          n += bin_count[plane - 1];
          if (n == 0 || right_count[plane] == 0) continue;
          float cost = kTraversalCost + kIntersectionCost *
                                            (acc.half_area() * n + right_area[plane] * right_count[plane]) / area;
          if (cost < best_cost) {
            best_cost = cost;
            best_axis = axis;
            best_plane = plane;
          }
        }
      }
    }

    uint32_t mid;
    if (best_axis >= 0 && (best_cost < leaf_cost || count > kBvhMaxLeafSize)) {
      float scale = kBins / extent[best_axis];
      float lo = centroid_bounds.lo[best_axis];
      auto first_right = std::partition(order.begin() + begin, order.begin() + end, [&](uint32_t p) {
        return bin_index((centroids[p][best_axis] - lo) * scale) < best_plane;
      });
      mid = uint32_t(first_right - order.begin());
    } else if (count > kBvhMaxLeafSize) {
      // All centroids coincide (or the tree is too deep): split by count along the widest axis.
      int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
      mid = begin + count / 2;
      std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                       [&](uint32_t a, uint32_t b) { return centroids[a][axis] < centroids[b][axis]; });
    } else {
      node.left_first = begin;
      node.prim_count = count;
      return;
    }
    uint32_t right;
    const uint32_t left = uint32_t(nodes.size());
    nodes.emplace_back();
    if (count >= kParallelSubtree) {
      // The left subtree goes on in `nodes` (it follows its parent there); the right one, built meanwhile into
      // an array of its own, is appended after it.
      std::vector<BvhNode> right_nodes(1);
      tbb::parallel_invoke([&] { build(nodes, left, begin, mid, depth + 1); },
                           [&] { build(right_nodes, 0, mid, end, depth + 1); });
      right = uint32_t(nodes.size());
      append(nodes, right_nodes);
    } else {
      build(nodes, left, begin, mid, depth + 1);
      right = uint32_t(nodes.size());
      nodes.emplace_back();
      build(nodes, right, mid, end, depth + 1);
    }
    nodes[index].left_first = right;  // `node` may dangle after the children grew the vector
    nodes[index].prim_count = 0;
  }

  // Appends a subtree built into a node array of its own, moving its interior nodes' child indices.
  static void append(std::vector<BvhNode>& nodes, const std::vector<BvhNode>& subtree) {
    const uint32_t offset = uint32_t(nodes.size());
    for (BvhNode n : subtree) {
      if (n.prim_count == 0) n.left_first += offset;
      nodes.push_back(n);
    }
  }
};

// Depth, leaves and SAH cost of the finished tree, in node order: that is the order in which a serial
// depth-first build meets them, so the cost's double sum is the same for any number of threads.
void tree_stats(Bvh& bvh, float root_area) {
  std::vector<uint32_t> depth(bvh.nodes.size(), 1);
  for (uint32_t i = 0; i < bvh.nodes.size(); ++i) {
    const BvhNode& n = bvh.nodes[i];
    bvh.depth = std::max(bvh.depth, depth[i]);
    float area = Aabb{{n.lo[0], n.lo[1], n.lo[2]}, {n.hi[0], n.hi[1], n.hi[2]}}.half_area();
    if (n.prim_count > 0) {
      bvh.leaf_count++;
      bvh.max_leaf_size = std::max(bvh.max_leaf_size, n.prim_count);
      bvh.sah_cost += kIntersectionCost * n.prim_count * area / root_area;
    } else {
      depth[i + 1] = depth[n.left_first] = depth[i] + 1;
      bvh.sah_cost += kTraversalCost * area / root_area;
    }
  }
}

}  // namespace

Bvh build_bvh(const std::vector<Aabb>& prim_boxes) {
  auto start = std::chrono::steady_clock::now();
  Bvh bvh;
  uint32_t n = uint32_t(prim_boxes.size());
  bvh.prim_order.resize(n);
  for (uint32_t i = 0; i < n; ++i) bvh.prim_order[i] = i;
  bvh.nodes.reserve(n > 0 ? 2 * n : 1);
  bvh.nodes.emplace_back();
  if (n == 0) {
    // An empty scene: a leaf with no primitives and an empty box that no ray enters.
    BvhNode& root = bvh.nodes[0];
    for (int k = 0; k < 3; ++k) {
      root.lo[k] = 1e30f;
      root.hi[k] = -1e30f;
    }
    root.left_first = 0;
    root.prim_count = 0;
    bvh.depth = 1;
    bvh.leaf_count = 1;
  } else {
    Builder builder{prim_boxes, std::vector<glm::vec3>(n), bvh.prim_order};
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, n), [&](const tbb::blocked_range<uint32_t>& r) {
      for (uint32_t i = r.begin(); i < r.end(); ++i) builder.centroids[i] = (prim_boxes[i].lo + prim_boxes[i].hi) * 0.5f;
    });
    builder.build(bvh.nodes, 0, 0, n, 0);
    Aabb root{{bvh.nodes[0].lo[0], bvh.nodes[0].lo[1], bvh.nodes[0].lo[2]},
              {bvh.nodes[0].hi[0], bvh.nodes[0].hi[1], bvh.nodes[0].hi[2]}};
    tree_stats(bvh, std::max(root.half_area(), 1e-30f));
  }
  bvh.node_count = uint32_t(bvh.nodes.size());
  bvh.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return bvh;
}

namespace {

void set_lane(pc_float4& v, int lane, float x) { (lane == 0 ? v.x : lane == 1 ? v.y : lane == 2 ? v.z : v.w) = x; }
template <size_t N>
void set_lane(float (&v)[N], int lane, float x) { v[lane] = x; }

float node_half_area(const BvhNode& n) {
  return Aabb{{n.lo[0], n.lo[1], n.lo[2]}, {n.hi[0], n.hi[1], n.hi[2]}}.half_area();
}

// The cheapest kWidth-wide tree by the surface area heuristic over the ways of collapsing the binary tree
// (Ylitie, Karras and Laine 2017, "Efficient incoherent ray traversal on GPUs through compressed wide
// BVHs", section 4.1), by the costs of scene/bvh_build.h (kWideNodeCost, kLeafBlockCost). For each binary
// node n and i = 1..8, the least cost of its subtree as at most i subtrees of the wide tree (i = 1: one wide
// leaf or node) is found from its children's; split[n][i - 1] keeps how it is reached (kFewer: with i - 1;
// else the left child's share of the i). Against the greedy collapse with leaves of up to 4 primitives: a third fewer nodes on
// the benchmark terrain, 5.79 -> 6.15 M bounce and 11.0 -> 11.5 M camera rays/s.
template <int kWidth>
struct WideCollapseCost {
  static constexpr uint8_t kLeaf = 0, kNode = 255, kFewer = 254;  // split values that are no share
  std::vector<std::array<uint8_t, kWidth>> split;  // i = 1: kLeaf or kNode
  std::vector<uint8_t> node_split;  // as a wide node: the left child's share of its kWidth children

  // The costs of the subtrees not yet joined to their parents are a stack: in reverse depth-first order
  // (the tree's node order backwards) a node's right subtree, then its left one, then the node itself
  // are met, so its children's costs are the top two. 9 bytes a node are kept, not 41.
  WideCollapseCost(const std::vector<BvhNode>& binary, const std::vector<uint32_t>& count)
      : split(binary.size()), node_split(binary.size()) {
    struct Pending {
      uint32_t node;
      std::array<float, kWidth> cost;
    };
    std::vector<Pending> pending;
    for (size_t n = binary.size(); n-- > 0;) {
      const BvhNode& b = binary[n];
      bool interior = b.prim_count == 0 && b.left_first != 0;
      std::array<float, kWidth> left{}, right{};
      if (interior) {
        if (pending.size() < 2 || pending.back().node != n + 1 || pending[pending.size() - 2].node != b.left_first)
          throw std::logic_error("collapse_to_bvh" + std::to_string(kWidth) + ": the binary tree is not in depth-first order");
        left = pending.back().cost;
        right = pending[pending.size() - 2].cost;
        pending.resize(pending.size() - 2);
      }
      // spread[i - 1]: the subtree as at most i subtrees drawn from both children, the left's share k.
      std::array<float, kWidth> spread;
      std::array<uint8_t, kWidth> spread_split;
      for (int i = 1; i <= kWidth; ++i) {
        spread[i - 1] = INFINITY;
        spread_split[i - 1] = kFewer;
        for (int k = 1; interior && k < i; ++k) {
          float c = left[k - 1] + right[i - k - 1];
          if (c < spread[i - 1]) spread[i - 1] = c, spread_split[i - 1] = uint8_t(k);
        }
      }
      float area = node_half_area(b);
      float leaf = count[n] > 0 && count[n] <= kBvhMaxLeafSize
                       ? area * (kLeafCost + kLeafBlockCost * float((count[n] + 3) / 4))
                       : INFINITY;
      float node = interior ? kWideNodeCost * area + spread[kWidth - 1] : INFINITY;
      Pending p{uint32_t(n), {}};
      p.cost[0] = std::min(leaf, node);
      split[n][0] = leaf <= node && leaf < INFINITY ? kLeaf : kNode;  // the empty scene's root is neither
      node_split[n] = spread_split[kWidth - 1];
      for (int i = 2; i <= kWidth; ++i) {
        bool fewer = p.cost[i - 2] <= spread[i - 1];
        p.cost[i - 1] = fewer ? p.cost[i - 2] : spread[i - 1];
        split[n][i - 1] = fewer ? kFewer : spread_split[i - 1];
      }
      pending.push_back(p);
    }
  }
  // The children of binary node n as a wide node, appended to out.
  void children(const std::vector<BvhNode>& binary, uint32_t n, std::vector<uint32_t>& out) const {
    roots(binary, n + 1, node_split[n], out);
    roots(binary, binary[n].left_first, kWidth - node_split[n], out);
  }
  // The subtrees of the least cost of binary node n as at most i, appended to out.
  void roots(const std::vector<BvhNode>& binary, uint32_t n, int i, std::vector<uint32_t>& out) const {
    while (i > 1 && split[n][i - 1] == kFewer) --i;
    if (i == 1) {
      out.push_back(n);
      return;
    }
    int k = split[n][i - 1];
    roots(binary, n + 1, k, out);
    roots(binary, binary[n].left_first, i - k, out);
  }
};

template <class Node, int Width>
struct Collapser {
  const std::vector<BvhNode>& binary;
  WideBvh<Node>& out;
  std::vector<uint32_t> subtree_first, subtree_count;  // per binary node: its leaf slots
  // The leaves and children of the least-cost 8- or 16-wide tree; without it (4-wide), the binary leaves
  // and the greedy opening of the largest child.
  using Cost = WideCollapseCost<Width>;
  std::unique_ptr<Cost> sah;

  void count_subtrees() {
    subtree_first.resize(binary.size());
    subtree_count.resize(binary.size());
    for (size_t i = binary.size(); i-- > 0;) {  // children come after their parent
      const BvhNode& n = binary[i];
      bool interior = n.prim_count == 0 && n.left_first != 0;
      subtree_first[i] = interior ? subtree_first[i + 1] : n.left_first;
      subtree_count[i] = interior ? subtree_count[i + 1] + subtree_count[n.left_first] : n.prim_count;
    }
  }
  bool is_leaf(uint32_t b) const {
    return sah ? sah->split[b][0] == Cost::kLeaf : binary[b].prim_count > 0;
  }

  // Fills out.nodes[wide] with the subtrees of binary node `b`: its children, opened further (largest
  // interior child first) while fewer than Width. A leaf at the root becomes the only child; the
  // empty scene's root (neither leaf nor interior) gives a node with no children.
  void fill(uint32_t wide, uint32_t b, uint32_t depth) {
    out.depth = std::max(out.depth, depth + 1);
    std::vector<uint32_t> kids;
    if (is_leaf(b)) {
      kids = {b};
    } else if (sah) {
      if (binary[b].left_first != 0) sah->children(binary, b, kids);
    } else if (binary[b].left_first != 0) {
      kids = {b + 1, binary[b].left_first};
      while (kids.size() < Width) {
        int open = -1;
        for (int i = 0; i < int(kids.size()); ++i) {
          const BvhNode& k = binary[kids[i]];
          if (!is_leaf(kids[i]) && (open < 0 || node_half_area(k) > node_half_area(binary[kids[open]]))) open = i;
        }
        if (open < 0) break;
        uint32_t k = kids[open];
        kids[open] = k + 1;
        kids.push_back(binary[k].left_first);
      }
    }
    // Leaf children in order of increasing box area, interior ones kept in their places: a packet of rays
    // going different ways tests a node's leaves in slot order (kernels/templates/packet.cl), and the small
    // ones (the objects in a room before its walls) give the nearer hits that the larger boxes after them
    // are then tested against. The Cornell box about +1.5 % on AVX2 code (docs/benchmarks-notes.md).
    std::vector<uint32_t> leaves;
    for (uint32_t k : kids)
      if (is_leaf(k)) leaves.push_back(k);
    std::stable_sort(leaves.begin(), leaves.end(), [&](uint32_t x, uint32_t y) {
      return node_half_area(binary[x]) < node_half_area(binary[y]);
    });
    for (size_t i = 0, l = 0; i < kids.size(); ++i)
      if (is_leaf(kids[i])) kids[i] = leaves[l++];
    Node node{};
    for (int lane = 0; lane < Width; ++lane) {
      bool used = lane < int(kids.size());
      const BvhNode* k = used ? &binary[kids[lane]] : nullptr;
      set_lane(node.lo_x, lane, used ? k->lo[0] : INFINITY);
      set_lane(node.lo_y, lane, used ? k->lo[1] : INFINITY);
      set_lane(node.lo_z, lane, used ? k->lo[2] : INFINITY);
      set_lane(node.hi_x, lane, used ? k->hi[0] : -INFINITY);
      set_lane(node.hi_y, lane, used ? k->hi[1] : -INFINITY);
      set_lane(node.hi_z, lane, used ? k->hi[2] : -INFINITY);
      node.child[lane] = PC_INVALID;
      if (used && is_leaf(kids[lane]))
        node.child[lane] = PC_LEAF_REF(subtree_first[kids[lane]], subtree_count[kids[lane]]);
    }
    out.nodes[wide] = node;
    for (int lane = 0; lane < int(kids.size()); ++lane) {
      if (is_leaf(kids[lane])) continue;
      uint32_t child = uint32_t(out.nodes.size());
      out.nodes.emplace_back();
      out.nodes[wide].child[lane] = child;
      fill(child, kids[lane], depth + 1);
    }
  }
};

template <class Node, int Width>
WideBvh<Node> collapse(const std::vector<BvhNode>& binary) {
  WideBvh<Node> out;
  out.nodes.reserve(binary.size() / (Width / 2) + 1);
  out.nodes.emplace_back();
  Collapser<Node, Width> collapser{binary, out, {}, {}, {}};
  collapser.count_subtrees();
  if constexpr (Width >= 8) collapser.sah = std::make_unique<WideCollapseCost<Width>>(binary, collapser.subtree_count);
  collapser.fill(0, 0, 0);
  return out;
}

}  // namespace

Bvh4 collapse_to_bvh4(const std::vector<BvhNode>& binary) { return collapse<Bvh4Node, 4>(binary); }
Bvh8 collapse_to_bvh8(const std::vector<BvhNode>& binary) { return collapse<Bvh8Node, 8>(binary); }
Bvh16 collapse_to_bvh16(const std::vector<BvhNode>& binary) { return collapse<Bvh16Node, 16>(binary); }

namespace {

// The block of prims[first, first + count) (count 1 to 4); unused lanes repeat the last primitive (and
// are masked off by count).
LeafBlock leaf_block(const std::vector<Primitive>& prims, uint32_t first, uint32_t count, bool last) {
  LeafBlock b{};
  b.first_slot = first;
  b.count = count;
  b.last = last ? 1u : 0u;
  for (int lane = 0; lane < 4; ++lane) {
    const Primitive& p = prims[first + std::min(uint32_t(lane), count - 1)];
    set_lane(b.ax, lane, p.a.x), set_lane(b.ay, lane, p.a.y), set_lane(b.az, lane, p.a.z);
    set_lane(b.bx, lane, p.b.x), set_lane(b.by, lane, p.b.y), set_lane(b.bz, lane, p.b.z);
    set_lane(b.cx, lane, p.c.x), set_lane(b.cy, lane, p.c.y), set_lane(b.cz, lane, p.c.z);
    uint32_t prim, kind;
    std::memcpy(&prim, &p.a.w, 4);
    std::memcpy(&kind, &p.b.w, 4);
    b.prim[lane] = prim;
    if (uint32_t(lane) < count && kind == PC_PRIM_SPHERE) b.sphere_mask |= 1u << lane;
  }
  return b;
}

constexpr size_t kWord = 8;  // the references of bvh8 and bvh16 count these (kernels/shared/types.h)

template <class T>
T wide_bvh_at(const std::vector<pc_float4>& wide, uint32_t at) {
  T x;
  std::memcpy(&x, reinterpret_cast<const char*>(wide.data()) + size_t(at) * kWord, sizeof x);
  return x;
}

}  // namespace

template <class Node>
uint32_t append_wide_bvh(const std::vector<Node>& nodes, const std::vector<Primitive>& prims,
                         std::vector<pc_float4>& wide) {
  // Where everything goes: each node at a multiple of 64 bytes, then its leaves' blocks.
  std::vector<size_t> node_at(nodes.size());
  size_t end = wide.size() * sizeof(pc_float4);
  for (size_t k = 0; k < nodes.size(); ++k) {
    end = (end + 63) / 64 * 64;
    node_at[k] = end;
    end += sizeof(Node);
    for (pc_uint ref : nodes[k].child)
      if (ref != PC_INVALID && (ref & PC_BVH4_LEAF)) end += (PC_LEAF_COUNT(ref) + 3) / 4 * sizeof(LeafBlock);
  }
  if (end / kWord > PC_BVH8_MAX_WORDS)
    throw std::length_error("the " + std::to_string(sizeof(Node::child) / sizeof(pc_uint)) + "-wide BVH takes " +
                            std::to_string(end >> 20) + " MiB; at most " +
                            std::to_string((size_t(PC_BVH8_MAX_WORDS) * kWord) >> 20) + " are supported");
  wide.resize(end / sizeof(pc_float4));  // zero-filled: the padding before nodes and in them
  char* bytes = reinterpret_cast<char*>(wide.data());
  for (size_t k = 0; k < nodes.size(); ++k) {
    Node node = nodes[k];
    size_t at = node_at[k] + sizeof(Node);
    for (pc_uint& ref : node.child) {
      if (ref == PC_INVALID) continue;
      if (!(ref & PC_BVH4_LEAF)) {
        ref = pc_uint(node_at[ref] / kWord);
        continue;
      }
      uint32_t first = PC_LEAF_FIRST(ref), count = PC_LEAF_COUNT(ref);
      ref = PC_BVH4_LEAF | pc_uint(at / kWord);
      for (uint32_t start = 0; start < count; start += 4, at += sizeof(LeafBlock)) {
        LeafBlock b = leaf_block(prims, first + start, std::min(count - start, 4u), start + 4 >= count);
        std::memcpy(bytes + at, &b, sizeof b);
      }
    }
    std::memcpy(bytes + node_at[k], &node, sizeof node);
  }
  return pc_uint(node_at[0] / kWord);
}

template uint32_t append_wide_bvh(const std::vector<Bvh8Node>&, const std::vector<Primitive>&, std::vector<pc_float4>&);
template uint32_t append_wide_bvh(const std::vector<Bvh16Node>&, const std::vector<Primitive>&, std::vector<pc_float4>&);

template <class Node>
Node wide_bvh_node(const std::vector<pc_float4>& wide, uint32_t at) {
  return wide_bvh_at<Node>(wide, at);
}
template Bvh8Node wide_bvh_node<Bvh8Node>(const std::vector<pc_float4>&, uint32_t);
template Bvh16Node wide_bvh_node<Bvh16Node>(const std::vector<pc_float4>&, uint32_t);

LeafBlock wide_bvh_block(const std::vector<pc_float4>& wide, uint32_t at) { return wide_bvh_at<LeafBlock>(wide, at); }
