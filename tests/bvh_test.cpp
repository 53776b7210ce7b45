// The BVH: structural invariants on the host, and traversal on the device against brute force.
#include <bit>
#include <cstring>
#include <random>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "runtime/checkpoint.h"
#include "runtime/ray_trace.h"
#include "scene/bvh_build.h"
#include "test_support.h"

namespace {

// A random soup of triangles of mixed sizes plus some spheres, inside [-10, 10]^3.
std::string random_scene_json(int triangles, int spheres, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-10, 10), size(0.05f, 3.0f), off(-1, 1);
  std::ostringstream s;
  s << R"({"camera": {"position": [0,0,30], "look_at": [0,0,0], "width": 8, "height": 8},
  "materials": {"m": {"type": "diffuse"}}, "shapes": [{"type": "triangles", "material": "m", "positions": [)";
  for (int i = 0; i < triangles; ++i) {
    float cx = pos(rng), cy = pos(rng), cz = pos(rng), sz = size(rng);
    for (int k = 0; k < 3; ++k)
      s << (i || k ? "," : "") << "[" << cx + sz * off(rng) << "," << cy + sz * off(rng) << "," << cz + sz * off(rng)
        << "]";
  }
  s << R"(], "indices": [)";
  for (int i = 0; i < triangles; ++i) s << (i ? "," : "") << "[" << 3 * i << "," << 3 * i + 1 << "," << 3 * i + 2 << "]";
  s << "]}";
  for (int i = 0; i < spheres; ++i)
    s << R"(, {"type": "sphere", "material": "m", "center": [)" << pos(rng) << "," << pos(rng) << "," << pos(rng)
      << R"(], "radius": )" << size(rng) * 0.5f << "}";
  s << "]}";
  return s.str();
}

std::vector<RayRecord> random_rays(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-14, 14), dir(-1, 1);
  std::vector<RayRecord> rays(n);
  for (RayRecord& r : rays) {
    r = {{pos(rng), pos(rng), pos(rng)}, 0, {dir(rng), dir(rng), dir(rng)}, INFINITY};
  }
  for (size_t i = 0; i < n; i += 10) rays[i].dir[i % 3] = 0;  // axis-parallel components
  for (size_t i = 5; i < n; i += 10) rays[i].tmax = 8;        // limited range
  return rays;
}

float lane(const pc_float4& v, int i) { return i == 0 ? v.x : i == 1 ? v.y : i == 2 ? v.z : v.w; }
template <size_t N>
float lane(const float (&v)[N], int i) {
  return v[i];
}

// Lane i's box of a wide node, as {lo, hi}.
template <class Node>
std::pair<glm::vec3, glm::vec3> lane_box(const Node& n, int i) {
  return {{lane(n.lo_x, i), lane(n.lo_y, i), lane(n.lo_z, i)}, {lane(n.hi_x, i), lane(n.hi_y, i), lane(n.hi_z, i)}};
}

// A wide tree's nodes by reference: the 4-wide tree's are indices into nodes; the 8- and 16-wide trees' are
// word offsets into bvh8 or bvh16, where each node is followed by its leaves' blocks
// (kernels/shared/types.h).
struct Tree4 {
  const DeviceScene& scene;
  const Bvh4Node& node(uint32_t ref) const { return scene.nodes.at(ref); }
  size_t node_count() const { return scene.nodes.size(); }
};
template <class Node>
struct TreeWide {
  const DeviceScene& scene;
  const std::vector<pc_float4>& array;  // bvh8 or bvh16
  uint32_t nodes;
  Node node(uint32_t ref) const {
    EXPECT_EQ(ref % (64 / 8), 0u) << "a node at a multiple of 64 bytes";
    EXPECT_LE((size_t(ref) * 8 + sizeof(Node)) / sizeof(pc_float4), array.size());
    return wide_bvh_node<Node>(array, ref);
  }
  size_t node_count() const { return nodes; }
};
using Tree8 = TreeWide<Bvh8Node>;
using Tree16 = TreeWide<Bvh16Node>;
Tree8 tree8(const DeviceScene& scene) { return {scene, scene.bvh8, scene.wide8_nodes}; }
Tree16 tree16(const DeviceScene& scene) { return {scene, scene.bvh16, scene.wide16_nodes}; }

// The leaf slots of a wide leaf reference of the node at node_ref: its references hold slots (4-wide) or
// its first block (8- and 16-wide), whose blocks hold full lanes up to the last.
std::vector<uint32_t> leaf_slots(const Tree4&, uint32_t, uint32_t ref) {
  std::vector<uint32_t> slots;
  for (uint32_t k = 0; k < PC_LEAF_COUNT(ref); ++k) slots.push_back(PC_LEAF_FIRST(ref) + k);
  return slots;
}
template <class Node>
std::vector<uint32_t> leaf_slots(const TreeWide<Node>& tree, uint32_t node_ref, uint32_t ref) {
  std::vector<uint32_t> slots;
  uint32_t at = ref & ~PC_BVH4_LEAF;
  EXPECT_GE(at, node_ref + sizeof(Node) / 8) << "a leaf's blocks after its node";
  for (;; at += sizeof(LeafBlock) / 8) {
    if (size_t(at) * 8 + sizeof(LeafBlock) > tree.array.size() * sizeof(pc_float4)) {
      ADD_FAILURE() << "a leaf's blocks past the end of the array, or no last block";
      break;
    }
    LeafBlock b = wide_bvh_block(tree.array, at);
    EXPECT_TRUE(b.count >= 1 && b.count <= 4 && (b.last || b.count == 4)) << "count " << b.count;
    for (uint32_t k = 0; k < b.count; ++k) {
      uint32_t slot = b.first_slot + k;
      // The block holds the primitive's index and vertices (a sphere's lane is tested from prims).
      const Primitive& p = tree.scene.prims.at(slot);
      uint32_t prim;
      std::memcpy(&prim, &p.a.w, 4);
      EXPECT_EQ(b.prim[k], prim);
      if (!(b.sphere_mask & (1u << k))) {
        EXPECT_EQ(lane(b.ax, k), p.a.x);
        EXPECT_EQ(lane(b.by, k), p.b.y);
        EXPECT_EQ(lane(b.cz, k), p.c.z);
      }
      if (!slots.empty()) { EXPECT_EQ(slot, slots.back() + 1); }
      slots.push_back(slot);
    }
    if (b.last) break;
  }
  return slots;
}

// A wide tree of Width children a node: every primitive in exactly one leaf, children inside parents.
template <int Width, class Tree>
void check_wide_tree(const DeviceScene& scene, const Tree& tree, uint32_t wide_depth) {
  std::vector<int> seen(scene.prims.size(), 0);
  // (wide node, depth, the box its parent gave it)
  struct Item {
    uint32_t node, depth;
    glm::vec3 lo, hi;
  };
  std::vector<Item> stack = {{0, 1, glm::vec3(-INFINITY), glm::vec3(INFINITY)}};
  uint32_t max_depth = 0, leaves = 0, max_leaf = 0;
  while (!stack.empty()) {
    Item item = stack.back();
    stack.pop_back();
    max_depth = std::max(max_depth, item.depth);
    const auto n = tree.node(item.node);
    int used = 0, interior = 0;
    for (int i = 0; i < Width; ++i) {
      auto [lo, hi] = lane_box(n, i);
      if (lo.x > hi.x) {  // an unused slot: an empty box in every axis
        EXPECT_TRUE(lo.x == INFINITY && lo.y == INFINITY && lo.z == INFINITY && hi.x == -INFINITY &&
                    hi.y == -INFINITY && hi.z == -INFINITY);
        continue;
      }
      ++used;
      for (int a = 0; a < 3; ++a) {  // inside the parent's box
        EXPECT_LE(item.lo[a], lo[a]);
        EXPECT_GE(item.hi[a], hi[a]);
      }
      uint32_t ref = n.child[i];
      if (!(ref & PC_BVH4_LEAF)) {
        ++interior;
        EXPECT_GT(ref, item.node);  // depth-first: children after their parent
        stack.push_back({ref, item.depth + 1, lo, hi});
        continue;
      }
      std::vector<uint32_t> slots = leaf_slots(tree, item.node, ref);
      ++leaves;
      max_leaf = std::max(max_leaf, uint32_t(slots.size()));
      for (uint32_t slot : slots) {
        ASSERT_LT(slot, scene.prims.size());
        seen[slot]++;
        // The leaf's box holds the primitive.
        Primitive p = scene.prims[slot];
        uint32_t kind;
        std::memcpy(&kind, &p.b.w, 4);
        std::vector<glm::vec3> pts = kind == PC_PRIM_SPHERE
            ? std::vector<glm::vec3>{{p.a.x - p.b.x, p.a.y - p.b.x, p.a.z - p.b.x}, {p.a.x + p.b.x, p.a.y + p.b.x, p.a.z + p.b.x}}
            : std::vector<glm::vec3>{{p.a.x, p.a.y, p.a.z}, {p.b.x, p.b.y, p.b.z}, {p.c.x, p.c.y, p.c.z}};
        for (glm::vec3 q : pts)
          for (int a = 0; a < 3; ++a) {
            EXPECT_LE(lo[a], q[a]);
            EXPECT_GE(hi[a], q[a]);
          }
      }
    }
    // The greedy 4-wide collapse fills every node up to 4 children unless all of them are leaves.
    if (Width == 4) {
      EXPECT_TRUE(used == Width || interior == 0) << "node " << item.node << ": " << used << " children";
    }
    // The used slots come first (the packet traversal stops at the first unused one).
    for (int i = 0; i < Width; ++i) EXPECT_EQ(n.child[i] == PC_INVALID, i >= used) << "node " << item.node;
  }
  for (size_t s = 0; s < seen.size(); ++s) ASSERT_EQ(seen[s], 1) << "leaf slot " << s;
  if (Width == 4) {  // the binary tree's leaves
    EXPECT_EQ(leaves, scene.bvh.leaf_count);
    EXPECT_EQ(max_leaf, scene.bvh.max_leaf_size);
  } else {  // binary subtrees as leaves: fewer than the binary leaves (least-cost tree: see below)
    EXPECT_LT(leaves, scene.bvh.leaf_count);
    EXPECT_LE(max_leaf, kBvhMaxLeafSize);
  }
  EXPECT_EQ(max_depth, wide_depth);
  // The kernel's stack holds Width - 1 entries per wide level: the wide tree is no deeper than the binary one.
  EXPECT_LE(wide_depth, scene.bvh.depth);
  EXPECT_LT(tree.node_count(), scene.bvh.node_count / (Width / 2));
}

// The nearest hit of each ray by testing every primitive of the scene (tests.cl's brute_force_trace).
std::vector<HitRecord> brute_force_hits(ClContext& cl, const DeviceScene& scene, const std::vector<RayRecord>& rays) {
  KernelProgram program = build_kernel_program(cl, "tests.cl", kernel_options(scene.features));
  ClBuffer prims = upload(cl, scene.prims), rb = upload(cl, rays);
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, rays.size() * sizeof(HitRecord));
  ClKernel k(program.kernel("brute_force_trace"));
  k.arg(0, prims.mem);
  k.arg(1, cl_uint(scene.prims.size()));
  k.arg(2, rb.mem);
  k.arg(3, out.mem);
  run_kernel(cl, k.k, rays.size());
  return read_buffer<HitRecord>(cl, out, rays.size());
}

}  // namespace

TEST(Bvh, EveryPrimitiveInExactlyOneLeafAndChildrenInsideParents) {
  DeviceScene scene = load_device_scene(write_temp_file("bvh-structure.json", random_scene_json(3000, 30, 1)));
  ASSERT_EQ(scene.prims.size(), 3030u);
  check_wide_tree<4>(scene, Tree4{scene}, scene.wide_depth);
  check_wide_tree<8>(scene, tree8(scene), scene.wide8_depth);
  check_wide_tree<16>(scene, tree16(scene), scene.wide16_depth);
  EXPECT_LT(scene.wide8_depth, scene.wide_depth);
  EXPECT_LE(scene.wide16_depth, scene.wide8_depth);
  EXPECT_LT(scene.wide16_nodes, scene.wide8_nodes);
  EXPECT_LE(scene.bvh.depth, kBvhMaxDepth);
  // A SAH tree over 3000 scattered primitives is far cheaper than testing them all.
  EXPECT_LT(scene.bvh.sah_cost, 100.0);
  EXPECT_GT(scene.bvh.sah_cost, 1.0);
}

// The SAH cost of a leaf of count primitives with box area `area`, by scene/bvh_build.h's costs: the leaf
// and the blocks of four primitives it is tested in.
double leaf_cost(double area, uint32_t count) { return area * (kLeafCost + kLeafBlockCost * ((count + 3) / 4)); }

// The SAH cost of an 8- or 16-wide tree of collapse_to_bvh8 or 16 over binary tree `binary`: each node's box
// (its parent's lane box; the root's is the binary root's) and each leaf's.
template <class Node>
double wide_tree_cost(const WideBvh<Node>& wide, const std::vector<BvhNode>& binary) {
  auto area = [](glm::vec3 lo, glm::vec3 hi) { return double(Aabb{lo, hi}.half_area()); };
  double cost = kWideNodeCost * area({binary[0].lo[0], binary[0].lo[1], binary[0].lo[2]},
                                     {binary[0].hi[0], binary[0].hi[1], binary[0].hi[2]});
  for (const Node& n : wide.nodes)
    for (int i = 0; i < int(std::size(n.child)); ++i) {
      if (n.child[i] == PC_INVALID) continue;
      auto [lo, hi] = lane_box(n, i);
      cost += n.child[i] & PC_BVH4_LEAF ? leaf_cost(area(lo, hi), PC_LEAF_COUNT(n.child[i])) : kWideNodeCost * area(lo, hi);
    }
  return cost;
}

// The least cost of any collapse of the binary subtree at n, by enumeration: n as a leaf (a binary subtree of
// at most 16 primitives), or as a node whose children are a cut of its subtree of at most `width` subtrees,
// each the least cost of itself. (The cuts of a subtree: itself, or a cut of each child together.)
struct BruteForceCollapse {
  const std::vector<BvhNode>& binary;
  size_t width;
  std::vector<uint32_t> count;
  std::vector<double> best;

  BruteForceCollapse(const std::vector<BvhNode>& b, size_t w) : binary(b), width(w), count(b.size()), best(b.size(), -1) {
    for (size_t n = b.size(); n-- > 0;)
      count[n] = interior(uint32_t(n)) ? count[n + 1] + count[b[n].left_first] : b[n].prim_count;
  }
  bool interior(uint32_t n) const { return binary[n].prim_count == 0 && binary[n].left_first != 0; }
  double area(uint32_t n) const {
    const BvhNode& b = binary[n];
    return double(Aabb{{b.lo[0], b.lo[1], b.lo[2]}, {b.hi[0], b.hi[1], b.hi[2]}}.half_area());
  }
  // Every cut of the subtree at n of at most `most` subtrees.
  std::vector<std::vector<uint32_t>> cuts(uint32_t n, size_t most) const {
    std::vector<std::vector<uint32_t>> out = {{n}};
    if (!interior(n) || most < 2) return out;
    for (const auto& a : cuts(n + 1, most - 1))
      for (const auto& b : cuts(binary[n].left_first, most - a.size())) {
        out.push_back(a);
        out.back().insert(out.back().end(), b.begin(), b.end());
      }
    return out;
  }
  double least(uint32_t n) {
    if (best[n] >= 0) return best[n];
    double c = count[n] <= kBvhMaxLeafSize ? leaf_cost(area(n), count[n]) : INFINITY;
    if (interior(n))
      for (const auto& a : cuts(n + 1, width - 1))
        for (const auto& b : cuts(binary[n].left_first, width - a.size())) {
          double sum = kWideNodeCost * area(n);
          for (uint32_t k : a) sum += least(k);
          for (uint32_t k : b) sum += least(k);
          c = std::min(c, sum);
        }
    return best[n] = c;
  }
};

TEST(Bvh, WideTreesHaveTheLeastCostOfAllCollapses) {
  // 16 children a node have far more cuts to enumerate: a smaller soup.
  for (size_t width : {8, 16}) {
    for (uint32_t seed : {1u, 2u, 3u}) {
      std::mt19937 rng(seed);
      std::uniform_real_distribution<float> pos(-10, 10), size(0.05f, 3.0f);
      std::vector<Aabb> boxes(width == 8 ? 200 : 80);
      for (Aabb& b : boxes) {
        glm::vec3 c(pos(rng), pos(rng), pos(rng));
        b = {c - size(rng), c + size(rng)};
      }
      Bvh binary = build_bvh(boxes);
      BruteForceCollapse brute(binary.nodes, width);
      double least = brute.least(0);
      double got = width == 8 ? wide_tree_cost(collapse_to_bvh8(binary.nodes), binary.nodes)
                              : wide_tree_cost(collapse_to_bvh16(binary.nodes), binary.nodes);
      EXPECT_NEAR(got, least, 1e-5 * least) << width << "-wide, seed " << seed;
      // Not merely the binary leaves under greedily filled nodes: leaves merge small subtrees.
      size_t nodes = width == 8 ? collapse_to_bvh8(binary.nodes).nodes.size() : collapse_to_bvh16(binary.nodes).nodes.size();
      EXPECT_LT(nodes, binary.nodes.size() / 4) << width << "-wide, seed " << seed;
    }
  }
}

// A device scene holds the BVH layouts it was built with and no others (a render builds only its devices'):
// each the same bytes as in the scene with all three, the rest empty, the checkpoint key the same; a device
// whose layout it lacks is refused, and so is an empty set of layouts.
TEST(Bvh, ScenesHoldOnlyTheLayoutsAskedFor) {
  SceneDescription description = load_scene(write_temp_file("bvh-layouts.json", random_scene_json(300, 5, 3)));
  DeviceScene all = build_device_scene(description);
  ASSERT_FALSE(all.nodes.empty() || all.bvh8.empty() || all.bvh16.empty());
  auto bytes = [](const auto& v) { return std::vector<char>((const char*)v.data(), (const char*)(v.data() + v.size())); };
  for (uint32_t layouts : {kBvhLayout4, kBvhLayout8, kBvhLayout16, kBvhLayout4 | kBvhLayout16}) {
    DeviceScene some = build_device_scene(description, DeviceOrigin::camera, Instancing::keep, layouts);
    EXPECT_EQ(some.bvh_layouts, layouts);
    EXPECT_EQ(bytes(some.nodes), layouts & kBvhLayout4 ? bytes(all.nodes) : std::vector<char>()) << layouts;
    EXPECT_EQ(bytes(some.bvh8), layouts & kBvhLayout8 ? bytes(all.bvh8) : std::vector<char>()) << layouts;
    EXPECT_EQ(bytes(some.bvh16), layouts & kBvhLayout16 ? bytes(all.bvh16) : std::vector<char>()) << layouts;
    EXPECT_EQ(bytes(some.prims), bytes(all.prims)) << layouts;
    EXPECT_EQ(render_key(some, RenderOptions{}), render_key(all, RenderOptions{})) << layouts;
    bool has_own = layouts & bvh_layout(bvh_width(test_device().info));
    if (has_own) {
      EXPECT_NO_THROW(test_scene_buffers(some)) << layouts;
    } else {
      EXPECT_THROW(test_scene_buffers(some), std::logic_error) << layouts;
    }
  }
  EXPECT_THROW(build_device_scene(description, DeviceOrigin::camera, Instancing::keep, 0), std::logic_error);
}

TEST(Bvh, SmallSceneIsOneLeafUnderTheRoot) {
  DeviceScene scene = load_device_scene(write_temp_file("bvh-small.json", random_scene_json(1, 0, 5)));
  ASSERT_EQ(scene.nodes.size(), 1u);
  const Bvh4Node& root = scene.nodes[0];
  EXPECT_EQ(root.child[0], PC_BVH4_LEAF | 0u);  // slot 0, one primitive
  for (int i = 1; i < 4; ++i) EXPECT_GT(lane_box(root, i).first.x, lane_box(root, i).second.x);
  ASSERT_EQ(scene.wide8_nodes, 1u);
  const Bvh8Node root8 = wide_bvh_node<Bvh8Node>(scene.bvh8, 0);
  EXPECT_EQ(root8.child[0], PC_BVH4_LEAF | uint32_t(sizeof(Bvh8Node) / 8));  // its one block right after it
  for (int i = 1; i < 8; ++i) EXPECT_GT(lane_box(root8, i).first.x, lane_box(root8, i).second.x);
  EXPECT_EQ(scene.bvh8.size() * sizeof(pc_float4), sizeof(Bvh8Node) + sizeof(LeafBlock));
  ASSERT_EQ(scene.wide16_nodes, 1u);
  const Bvh16Node root16 = wide_bvh_node<Bvh16Node>(scene.bvh16, 0);
  EXPECT_EQ(root16.child[0], PC_BVH4_LEAF | uint32_t(sizeof(Bvh16Node) / 8));
  for (int i = 1; i < 16; ++i) EXPECT_GT(lane_box(root16, i).first.x, lane_box(root16, i).second.x);
  EXPECT_EQ(scene.bvh16.size() * sizeof(pc_float4), sizeof(Bvh16Node) + sizeof(LeafBlock));
}

// A random soup, plus a 12 x 12 grid of quads placed twice (two shapes, the same triangles): rays through
// the grid meet two primitives at exactly the same t everywhere, and both triangles of an edge on it.
std::string scene_with_ties_json() {
  std::string soup = random_scene_json(1500, 20, 2);
  std::ostringstream grid;
  grid << R"(, {"type": "triangles", "material": "m", "positions": [)";
  for (int y = 0; y <= 12; ++y)
    for (int x = 0; x <= 12; ++x) grid << (x || y ? "," : "") << "[" << x - 6 << "," << y - 6 << ",12]";
  grid << R"(], "indices": [)";
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 12; ++x) {
      int v = 13 * y + x;
      grid << (x || y ? "," : "") << "[" << v << "," << v + 1 << "," << v + 14 << "],[" << v << "," << v + 14 << ","
           << v + 13 << "]";
    }
  grid << "]}";
  std::string shapes = grid.str() + grid.str();
  return soup.substr(0, soup.size() - 2) + shapes + "]}";
}

// Rays at the grid's vertices, edges and faces from above, and random rays.
std::vector<RayRecord> rays_with_ties(size_t n, uint32_t seed) {
  std::vector<RayRecord> rays = random_rays(n, seed);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> cell(-6, 6), part(0, 3);
  for (size_t i = 0; i < n / 2; ++i) {
    float x = float(cell(rng)), y = float(cell(rng));
    int p = part(rng);  // a vertex, a horizontal edge, a diagonal edge, a face
    if (p == 1) x += 0.5f;
    if (p == 2) x += 0.25f, y += 0.25f;
    if (p == 3) x += 0.75f, y += 0.125f;
    rays[2 * i] = {{x, y, 20}, 0, {0, 0, -1}, INFINITY};
  }
  return rays;
}

// Every layout against brute force: the nearest hit by (t, primitive index) is one total order's minimum,
// so they agree exactly, ties included (kernels/intersect.cl, intersect_prim).
TEST(Bvh, EveryLayoutMatchesBruteForceExactlyTiesIncluded) {
  ClContext& cl = test_device();
  // World origin: the brute-force kernel gets the (world) rays as they are.
  DeviceScene scene = load_device_scene(write_temp_file("bvh-ties.json", scene_with_ties_json()), DeviceOrigin::world);
  std::vector<RayRecord> rays = rays_with_ties(100000, 3);

  std::vector<HitRecord> brute = brute_force_hits(cl, scene, rays);
  size_t hits = 0, grid_hits = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    hits += brute[i].prim != PC_INVALID;
    grid_hits += brute[i].prim != PC_INVALID && brute[i].t == 8.0f;
  }
  EXPECT_GT(hits, rays.size() / 2);  // the test means something only if many rays hit
  EXPECT_LT(hits, rays.size());
  EXPECT_GT(grid_hits, rays.size() / 4);  // and many of them meet the doubled grid
  for (uint32_t width : {4u, 8u, 16u}) {
    BvhWidthScope scope(width);
    TraceTiming timing;
    std::vector<HitRecord> bvh = trace_ray_records(cl, scene, rays, 1, timing);
    size_t mismatches = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      bool same = brute[i].t == bvh[i].t && brute[i].prim == bvh[i].prim &&
                  (brute[i].prim == PC_INVALID || (brute[i].u == bvh[i].u && brute[i].v == bvh[i].v));
      if (!same && ++mismatches < 10)
        ADD_FAILURE() << width << "-wide, ray " << i << ": brute force t=" << brute[i].t << " prim=" << brute[i].prim
                      << ", bvh t=" << bvh[i].t << " prim=" << bvh[i].prim;
    }
    EXPECT_EQ(mismatches, 0u) << width << "-wide";
  }
  // Packets of 8 and 16 rays (kernels/packet.cl, the 8- and 16-wide BVHs): the same records, for packets mixing the
  // grid's parallel rays with random ones as above, and for packets of only one or only the other kind.
  std::vector<size_t> grouped;
  for (size_t start : {0, 1})
    for (size_t i = start; i < rays.size(); i += 2) grouped.push_back(i);
  std::vector<RayRecord> grouped_rays;
  for (size_t i : grouped) grouped_rays.push_back(rays[i]);
  for (uint32_t width : {8u, 16u}) {
    BvhWidthScope scope(width);
    for (uint32_t lanes : {8u, 16u}) {
      for (bool mixed : {true, false}) {
        TraceTiming timing;
        std::vector<HitRecord> packet = trace_ray_records(cl, scene, mixed ? rays : grouped_rays, 1, timing, 0, lanes);
        size_t mismatches = 0;
        for (size_t k = 0; k < rays.size(); ++k) {
          const HitRecord &want = brute[mixed ? k : grouped[k]], &got = packet[k];
          bool same = want.t == got.t && want.prim == got.prim &&
                      (want.prim == PC_INVALID || (want.u == got.u && want.v == got.v));
          if (!same && ++mismatches < 10)
            ADD_FAILURE() << width << "-wide, " << lanes << " lanes, " << (mixed ? "mixed" : "grouped") << ", ray "
                          << k << ": brute force t=" << want.t << " prim=" << want.prim << ", packet t=" << got.t
                          << " prim=" << got.prim;
        }
        EXPECT_EQ(mismatches, 0u) << width << "-wide, " << lanes << " lanes, " << (mixed ? "mixed" : "grouped");
      }
    }
    // Any hit (shadow rays), one ray or packets: a hit exactly where brute force finds the nearest one.
    for (uint32_t lanes : {1u, 8u, 16u}) {
      TraceTiming timing;
      std::vector<HitRecord> any = trace_ray_records(cl, scene, rays, 1, timing, 0, lanes, true);
      size_t mismatches = 0;
      for (size_t k = 0; k < rays.size(); ++k) mismatches += (any[k].prim == PC_INVALID) != (brute[k].prim == PC_INVALID);
      EXPECT_EQ(mismatches, 0u) << width << "-wide, " << lanes << " lanes, any hit";
    }
  }
}

// A ray of the Cornell box render (scenes/cornell-box.json at 256 x 256, seed 1, independent sampler, 1024
// spp: a camera ray of pixel 52942) that meets the floor (primitive 1) and the right wall (primitive 9) on
// their common edge at the same t: the lower index, the floor, is its hit. Both leaves' entry distance
// rounds one ulp beyond that t. In its packet of the render (16 lanes, 256-sample passes), whose companions
// are the other rays here (camera rays of its row, bounce rays), the packet traversal entered the wall's
// leaf first, then dropped the floor's and returned the wall, as it did for a packet of 16 copies of the
// ray; the single ray enters the floor's leaf first. The device coordinates are the render's (around the
// camera), as bits.
std::vector<RayRecord> cornell_edge_packet() {
  const uint32_t r[16][6] = {{0x00000000, 0x00000000, 0x00000000, 0x3e592355, 0xbe5a1e43, 0xbf7429ce},
                             {0x00000000, 0x00000000, 0x00000000, 0x3e59d223, 0xbe596ff4, 0xbf7429cb},
                             {0x3f7fc682, 0xbf7ffff8, 0xc08f9530, 0xbf3d75f4, 0x3f0aef13, 0xbecb5a14},
                             {0x3f7f2598, 0xbf7ffff8, 0xc08ec539, 0x3f051edd, 0x3f50dd9e, 0xbe817601},
                             {0x3f7e08a6, 0xbf7ffff8, 0xc08f2463, 0x3db5ddce, 0x3f6d9ae8, 0xbeb912b5},
                             {0x3c29bec7, 0xbf7a09be, 0xc0696f1e, 0x3f407a6e, 0x3f019f2d, 0xbed834dd},
                             {0x00000000, 0x00000000, 0x00000000, 0x3e5b223a, 0xbe5b223a, 0xbf73feb8},  // the ray
                             {0x00000000, 0x00000000, 0x00000000, 0x3e5a67e5, 0xbe5a9e57, 0xbf74108b},
                             {0xbf7ffff8, 0x3eaf4233, 0xc089c4f7, 0x3e4094ac, 0xbf151979, 0xbf4a7412},
                             {0x3ee204a8, 0xbf7ffff8, 0xc0675903, 0xbf0e2beb, 0x3f4ae523, 0xbe80f279},
                             {0xbde1b2d8, 0xbf4d1412, 0xc0815613, 0x3e54eefc, 0xbf58a528, 0xbefb2256},
                             {0xbdbe1173, 0xbf5f3206, 0xc07f07d1, 0x3efdd7a0, 0xbecd516c, 0xbf453366},
                             {0x3f6ce860, 0xbf7ffff8, 0xc08fa563, 0xbebedb82, 0x3ea163b1, 0x3f5f6c39},
                             {0x00000000, 0x00000000, 0x00000000, 0x3e5a9811, 0xbe5afcba, 0xbf740890},
                             {0x3f5dd9fe, 0xbf69b79c, 0xc08ffffb, 0xbe60f778, 0x3f1ee466, 0x3f40ae75},
                             {0xbd686f87, 0xbd5f0ef0, 0xc0777b62, 0x3f0b3d85, 0xbf3f7cc7, 0xbec2bce0}};
  std::vector<RayRecord> rays(16);
  for (int i = 0; i < 16; ++i)
    rays[i] = {{std::bit_cast<float>(r[i][0]), std::bit_cast<float>(r[i][1]), std::bit_cast<float>(r[i][2])}, 0,
               {std::bit_cast<float>(r[i][3]), std::bit_cast<float>(r[i][4]), std::bit_cast<float>(r[i][5])}, INFINITY};
  return rays;
}

// The same hit record, bit for bit (u and v only for a hit).
bool same_hit(const HitRecord& a, const HitRecord& b) {
  auto bits = [](float x) { return std::bit_cast<uint32_t>(x); };
  return bits(a.t) == bits(b.t) && a.prim == b.prim &&
         (a.prim == PC_INVALID || (bits(a.u) == bits(b.u) && bits(a.v) == bits(b.v)));
}

// A ray's packet hit is its single ray's, bit for bit, whichever rays share its packet: the ray above in
// its render packet, at every place of that packet (the companions rotated) and in a packet of its copies,
// at 8 and 16 lanes in the 8- and 16-wide layouts, and one ray at a time in every layout: all of them the
// brute-force hit (kernels/intersect.cl, pop_subtree).
TEST(Bvh, PacketHitOfACornellBoxEdgeRayIsItsSingleRayHitWhateverItsCompanions) {
  ClContext& cl = test_device();
  DeviceScene scene = load_device_scene(std::string(PATHCL_SOURCE_DIR) + "/scenes/cornell-box.json");
  scene.origin = glm::dvec3(0);  // the rays are in the render's device coordinates already
  const std::vector<RayRecord> packet = cornell_edge_packet();
  std::vector<RayRecord> rays;  // rotation k puts the edge ray (6) at place (6 + k) % 16
  for (int k = 0; k < 16; ++k)
    for (int i = 0; i < 16; ++i) rays.push_back(packet[(i + 16 - k) % 16]);
  std::vector<RayRecord> alone(16, packet[6]);
  rays.insert(rays.end(), alone.begin(), alone.end());

  std::vector<HitRecord> brute = brute_force_hits(cl, scene, rays);
  ASSERT_EQ(brute[6].prim, 1u) << "the floor, at the same t as the wall";
  ASSERT_EQ(std::bit_cast<uint32_t>(brute[6].t), 0x409588c6u);
  // The leaves' entry distance (the floor's y and the wall's x plane, 1 / d.x from the origin): one ulp beyond.
  ASSERT_EQ(std::bit_cast<uint32_t>(1.0f / packet[6].dir[0]), 0x409588c7u);
  for (uint32_t width : {4u, 8u, 16u}) {
    BvhWidthScope scope(width);
    for (uint32_t lanes : {1u, 8u, 16u}) {
      if (width == 4 && lanes > 1) continue;  // packets need the 8- or 16-wide tree
      TraceTiming timing;
      std::vector<HitRecord> hits = trace_ray_records(cl, scene, rays, 1, timing, 0, lanes);
      for (size_t i = 0; i < rays.size(); ++i)
        EXPECT_TRUE(same_hit(hits[i], brute[i]))
            << width << "-wide, " << lanes << " lanes, ray " << i << " (place " << i % 16 << " of packet " << i / 16
            << "): brute force t=" << brute[i].t << " prim=" << brute[i].prim << ", traced t=" << hits[i].t
            << " prim=" << hits[i].prim;
    }
  }
}

TEST(Bvh, EmptySceneMissesEverything) {
  ClContext& cl = test_device();
  DeviceScene scene = load_device_scene(std::string(PATHCL_TEST_SCENES) + "/empty.json");
  ASSERT_EQ(scene.prims.size(), 0u);
  TraceTiming timing;
  auto hits = trace_ray_records(cl, scene, random_rays(1000, 4), 1, timing);
  for (const HitRecord& h : hits) ASSERT_EQ(h.prim, PC_INVALID);
}
