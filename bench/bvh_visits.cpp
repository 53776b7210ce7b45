// How much a closest-hit traversal visits on pathcl's 8- and 16-wide BVHs and on a tree built by Embree's own
// builder, on the same rays (issue 15: is the bounce-ray gap to Embree in the tree?):
//   bvh_visits MESH.obj RAYS [MAX_RAYS]
// RAYS: 32-byte records as `pathcl rays` reads them. pathcl's trees: build_bvh and collapse_to_bvh8 or 16 over the
// triangles' boxes (as the device scene builds it). Embree's: rtcBuildBVH with the settings of Embree 3.13's
// BVH8 + Triangle4 scene builder (kernels/bvh/bvh_builder_sah.cpp: SAH blocks of 4, leaves of 4 to 28,
// traversal and intersection cost 1, binned, no spatial splits). Both are traversed by one rule, pathcl's
// and Embree's (one child hit: descend; two: the nearer, the other pushed; more: all pushed by entry
// distance; popped entries beyond the nearest hit skipped), in double precision, and a leaf of n
// triangles counts ceil(n / 4) blocks. Prints each tree's size and SAH, the visits per ray (all rays,
// those that hit, those that miss), and how many rays hit the same triangle in both. Built by
// CMakeLists.txt where Embree 3 is installed (scripts/bench/layouts installs it).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <embree3/rtcore.h>

#include "scene/bvh_build.h"
#include "scene/mesh_clean.h"
#include "scene/obj_load.h"

namespace {

std::vector<glm::dvec3> g_pos;  // triangle t: g_pos[3 t], g_pos[3 t + 1], g_pos[3 t + 2] (float values)

// Both trees in one form: nodes of n children (interior or leaf) and leaves of the triangles
// prims[first, first + count).
struct WNode {
  float lo[3][16], hi[3][16];
  int32_t child[16];  // >= 0 interior index, < 0 leaf -(leaf+1)
  int n = 0;
};
struct WLeaf { uint32_t first, count; };
struct WTree {
  std::vector<WNode> nodes;
  std::vector<WLeaf> leaves;
  std::vector<uint32_t> prims;
  int32_t root = 0;  // interior index (or leaf code)
  float rlo[3], rhi[3];
};

// Half the surface area of the box lo, hi (Aabb's: 0 for an empty box).
double half_area(const float lo[3], const float hi[3]) {
  return Aabb{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}}.half_area();
}

void stats(const char* name, const WTree& t) {
  size_t blocks = 0, prims = 0;
  for (auto& l : t.leaves) { blocks += (l.count + 3) / 4; prims += l.count; }
  // Embree-style SAH: (sum_nodes A(node) + sum_leaves blocks*A(leaf)) / A(root)
  double sah = half_area(t.rlo, t.rhi);  // root node itself
  for (auto& nd : t.nodes)
    for (int i = 0; i < nd.n; ++i) {
      float lo[3] = {nd.lo[0][i], nd.lo[1][i], nd.lo[2][i]}, hi[3] = {nd.hi[0][i], nd.hi[1][i], nd.hi[2][i]};
      double a = half_area(lo, hi);
      if (nd.child[i] >= 0) sah += a;
      else sah += a * ((t.leaves[-nd.child[i] - 1].count + 3) / 4);
    }
  sah /= half_area(t.rlo, t.rhi);
  printf("[%s] nodes %zu  leaves %zu  blocks %zu  prims %zu  prims/block %.3f (fill %.1f%%)  SAH(node=1,block=1) %.3f\n",
         name, t.nodes.size(), t.leaves.size(), blocks, prims, double(prims) / blocks, 100.0 * prims / (4.0 * blocks), sah);
}

// ---------------- pathcl trees ----------------
template <class Node>
WTree pathcl_tree(const Bvh& bvh, const WideBvh<Node>& wide, const char* name) {
  WTree t;
  t.prims = bvh.prim_order;
  t.nodes.resize(wide.nodes.size());
  for (size_t k = 0; k < wide.nodes.size(); ++k) {
    const Node& s = wide.nodes[k];
    WNode& d = t.nodes[k];
    for (int i = 0; i < int(std::size(s.child)); ++i) {
      if (s.child[i] == 0xffffffffu) break;
      d.lo[0][d.n] = s.lo_x[i]; d.lo[1][d.n] = s.lo_y[i]; d.lo[2][d.n] = s.lo_z[i];
      d.hi[0][d.n] = s.hi_x[i]; d.hi[1][d.n] = s.hi_y[i]; d.hi[2][d.n] = s.hi_z[i];
      uint32_t c = s.child[i];
      if (c & PC_BVH4_LEAF) {
        uint32_t first = PC_LEAF_FIRST(c), count = PC_LEAF_COUNT(c);
        t.leaves.push_back({first, count});
        d.child[d.n] = -int32_t(t.leaves.size());
      } else {
        d.child[d.n] = int32_t(c);
      }
      d.n++;
    }
  }
  for (int a = 0; a < 3; ++a) { t.rlo[a] = 1e30f; t.rhi[a] = -1e30f; }
  for (int i = 0; i < t.nodes[0].n; ++i)
    for (int a = 0; a < 3; ++a) {
      t.rlo[a] = std::min(t.rlo[a], t.nodes[0].lo[a][i]);
      t.rhi[a] = std::max(t.rhi[a], t.nodes[0].hi[a][i]);
    }
  printf("[%s] binary nodes %u, binary SAH %.4f, depth %u\n", name, bvh.node_count, bvh.sah_cost, wide.depth);
  return t;
}

// ---------------- Embree rtcBuildBVH tree ----------------
// What rtcBuildBVH's callbacks build in its allocator; the first field tells a node from a leaf.
struct ENode {
  int leaf;  // 0 interior
  unsigned n;
  void* ch[8];
  RTCBounds b[8];
};
struct ELeaf {
  int leaf;  // 1
  unsigned n;
  unsigned* ids;  // n of them, allocated right after the leaf
};
void* e_create_node(RTCThreadLocalAllocator alloc, unsigned int numChildren, void*) {
  ENode* p = (ENode*)rtcThreadLocalAlloc(alloc, sizeof(ENode), 16);
  p->leaf = 0; p->n = numChildren;
  return p;
}
void e_set_children(void* node, void** children, unsigned int n, void*) {
  ENode* p = (ENode*)node;
  for (unsigned i = 0; i < n; ++i) p->ch[i] = children[i];
  p->n = n;
}
void e_set_bounds(void* node, const RTCBounds** bounds, unsigned int n, void*) {
  ENode* p = (ENode*)node;
  for (unsigned i = 0; i < n; ++i) p->b[i] = *bounds[i];
}
void* e_create_leaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* prims, size_t n, void*) {
  ELeaf* p = (ELeaf*)rtcThreadLocalAlloc(alloc, sizeof(ELeaf) + sizeof(unsigned) * n, 16);
  p->leaf = 1; p->n = unsigned(n);
  p->ids = reinterpret_cast<unsigned*>(p + 1);
  for (size_t i = 0; i < n; ++i) p->ids[i] = prims[i].primID;
  return p;
}

int32_t e_flatten(WTree& t, void* ptr) {
  if (((ENode*)ptr)->leaf) {
    ELeaf* l = (ELeaf*)ptr;
    uint32_t first = uint32_t(t.prims.size());
    for (unsigned i = 0; i < l->n; ++i) t.prims.push_back(l->ids[i]);
    t.leaves.push_back({first, l->n});
    return -int32_t(t.leaves.size());
  }
  ENode* e = (ENode*)ptr;
  int32_t idx = int32_t(t.nodes.size());
  t.nodes.emplace_back();
  int32_t kids[8];
  for (unsigned i = 0; i < e->n; ++i) kids[i] = e_flatten(t, e->ch[i]);
  WNode& d = t.nodes[idx];
  d.n = int(e->n);
  for (unsigned i = 0; i < e->n; ++i) {
    d.lo[0][i] = e->b[i].lower_x; d.lo[1][i] = e->b[i].lower_y; d.lo[2][i] = e->b[i].lower_z;
    d.hi[0][i] = e->b[i].upper_x; d.hi[1][i] = e->b[i].upper_y; d.hi[2][i] = e->b[i].upper_z;
    d.child[i] = kids[i];
  }
  return idx;
}

WTree embree_tree(const std::vector<Aabb>& boxes) {
  RTCDevice dev = rtcNewDevice(nullptr);
  RTCBVH bvh = rtcNewBVH(dev);
  std::vector<RTCBuildPrimitive> prims(boxes.size());
  WTree t;
  for (int a = 0; a < 3; ++a) { t.rlo[a] = 1e30f; t.rhi[a] = -1e30f; }
  for (size_t i = 0; i < boxes.size(); ++i) {
    RTCBuildPrimitive& p = prims[i];
    p.lower_x = boxes[i].lo.x; p.lower_y = boxes[i].lo.y; p.lower_z = boxes[i].lo.z; p.geomID = 0;
    p.upper_x = boxes[i].hi.x; p.upper_y = boxes[i].hi.y; p.upper_z = boxes[i].hi.z; p.primID = unsigned(i);
    for (int a = 0; a < 3; ++a) { t.rlo[a] = std::min(t.rlo[a], boxes[i].lo[a]); t.rhi[a] = std::max(t.rhi[a], boxes[i].hi[a]); }
  }
  RTCBuildArguments args = rtcDefaultBuildArguments();
  // Embree 3.13.5 internal BVH8Triangle4SceneBuilderSAH (kernels/bvh/bvh_builder_sah.cpp):
  //   BVHNBuilderSAH<8,Triangle4>(bvh, scene, sahBlockSize=4, intCost=1.0, minLeafSize=4, maxLeafSize=inf)
  //   maxLeafSize clamped to Triangle4::max_size() * BVH::maxLeafBlocks = 4 * 7 = 28
  //   travCost = 1.0 (kernels/builders/bvh_builder_sah.h), branchingFactor = N = 8,
  //   maxDepth = BVH::maxBuildDepthLeaf = 40 (kernels/bvh/bvh_builder.cpp, bvh.h)
  args.buildQuality = RTC_BUILD_QUALITY_MEDIUM;
  args.maxBranchingFactor = 8;
  args.maxDepth = 40;
  args.sahBlockSize = 4;
  args.minLeafSize = 4;
  args.maxLeafSize = 28;
  args.traversalCost = 1.0f;
  args.intersectionCost = 1.0f;
  args.bvh = bvh;
  args.primitives = prims.data();
  args.primitiveCount = prims.size();
  args.primitiveArrayCapacity = prims.size();
  args.createNode = e_create_node;
  args.setNodeChildren = e_set_children;
  args.setNodeBounds = e_set_bounds;
  args.createLeaf = e_create_leaf;
  void* root = rtcBuildBVH(&args);
  if (!root) { fprintf(stderr, "rtcBuildBVH failed: %d\n", rtcGetDeviceError(dev)); exit(1); }
  t.root = e_flatten(t, root);
  if (t.root != 0) { fprintf(stderr, "embree root is a leaf\n"); exit(1); }
  rtcReleaseBVH(bvh);
  rtcReleaseDevice(dev);
  return t;
}

// ---------------- traversal ----------------
using Ray = RayRecord;  // the ray file's records (kernels/shared/types.h)
struct Counts { uint64_t nodes = 0, leaves = 0, blocks = 0; };

// Moeller-Trumbore in double (counting visits needs no watertightness).
bool tri_hit(uint32_t tri, const double o[3], const double d[3], double tmin, double tmax, double& tout) {
  const glm::dvec3 &a = g_pos[3 * tri], &b = g_pos[3 * tri + 1], &c = g_pos[3 * tri + 2];
  double e1[3] = {b.x - a.x, b.y - a.y, b.z - a.z}, e2[3] = {c.x - a.x, c.y - a.y, c.z - a.z};
  double p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
  double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
  if (det == 0) return false;
  double inv = 1.0 / det;
  double s[3] = {o[0] - a.x, o[1] - a.y, o[2] - a.z};
  double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) * inv;
  if (u < 0 || u > 1) return false;
  double q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
  double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
  if (v < 0 || u + v > 1) return false;
  double t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
  if (t < tmin || t > tmax) return false;
  tout = t;
  return true;
}

int64_t trace(const WTree& t, const Ray& r, Counts& c) {
  double o[3] = {r.org[0], r.org[1], r.org[2]}, d[3] = {r.dir[0], r.dir[1], r.dir[2]}, inv[3];
  for (int a = 0; a < 3; ++a) inv[a] = 1.0 / d[a];
  const double tmin = r.tmin;
  double best = r.tmax;
  int64_t hit = -1;
  struct E { int32_t ref; double t; };
  E stack[512];
  int sp = 0;
  int32_t cur = t.root;
  for (;;) {
    if (cur >= 0) {
      c.nodes++;
      const WNode& nd = t.nodes[cur];
      E h[16];
      int nh = 0;
      for (int i = 0; i < nd.n; ++i) {
        double tn = tmin, tf = best;
        bool ok = true;
        for (int a = 0; a < 3 && ok; ++a) {
          double lo = nd.lo[a][i], hi = nd.hi[a][i];
          if (d[a] == 0) {
            if (o[a] < lo || o[a] > hi) ok = false;
            continue;
          }
          double t0 = (lo - o[a]) * inv[a], t1 = (hi - o[a]) * inv[a];
          if (t0 > t1) std::swap(t0, t1);
          tn = std::max(tn, t0);
          tf = std::min(tf, t1);
        }
        if (ok && tn <= tf) h[nh++] = {nd.child[i], tn};
      }
      if (nh == 0) goto pop;
      if (nh == 1) { cur = h[0].ref; continue; }
      if (nh == 2) {
        if (h[1].t < h[0].t) std::swap(h[0], h[1]);
        stack[sp++] = h[1];
        cur = h[0].ref;
        continue;
      }
      std::stable_sort(h, h + nh, [](const E& x, const E& y) { return x.t > y.t; });  // farthest first
      for (int i = 0; i < nh; ++i) stack[sp++] = h[i];
      goto pop;
    } else {
      const WLeaf& l = t.leaves[-cur - 1];
      c.leaves++;
      c.blocks += (l.count + 3) / 4;
      for (uint32_t k = 0; k < l.count; ++k) {
        uint32_t tri = t.prims[l.first + k];
        double th;
        if (tri_hit(tri, o, d, tmin, best, th)) {
          if (th < best || (th == best && (hit < 0 || tri < hit))) { best = th; hit = tri; }
        }
      }
    }
  pop:
    for (;;) {
      if (sp == 0) return hit;
      E e = stack[--sp];
      if (e.t > best) continue;
      cur = e.ref;
      break;
    }
  }
}

struct Agg { Counts all, hit, miss; uint64_t nhit = 0, nmiss = 0; };

void run(const char* name, const WTree& t, const std::vector<Ray>& rays, std::vector<int64_t>& hits) {
  hits.assign(rays.size(), -1);
  unsigned nt = std::max(1u, std::thread::hardware_concurrency());
  std::vector<Agg> aggs(nt);
  std::vector<std::thread> th;
  for (unsigned w = 0; w < nt; ++w)
    th.emplace_back([&, w] {
      Agg& g = aggs[w];
      for (size_t i = w; i < rays.size(); i += nt) {
        Counts c;
        int64_t h = trace(t, rays[i], c);
        hits[i] = h;
        Counts& dst = h >= 0 ? g.hit : g.miss;
        (h >= 0 ? g.nhit : g.nmiss)++;
        dst.nodes += c.nodes; dst.leaves += c.leaves; dst.blocks += c.blocks;
      }
    });
  for (auto& x : th) x.join();
  Agg a;
  for (auto& g : aggs) {
    a.nhit += g.nhit; a.nmiss += g.nmiss;
    a.hit.nodes += g.hit.nodes; a.hit.leaves += g.hit.leaves; a.hit.blocks += g.hit.blocks;
    a.miss.nodes += g.miss.nodes; a.miss.leaves += g.miss.leaves; a.miss.blocks += g.miss.blocks;
  }
  a.all.nodes = a.hit.nodes + a.miss.nodes; a.all.leaves = a.hit.leaves + a.miss.leaves; a.all.blocks = a.hit.blocks + a.miss.blocks;
  auto pr = [&](const char* k, const Counts& c, uint64_t n) {
    printf("[%s] %-4s rays %8llu  nodes/ray %7.3f  leaves/ray %7.3f  blocks/ray %7.3f\n", name, k, (unsigned long long)n,
           n ? double(c.nodes) / n : 0.0, n ? double(c.leaves) / n : 0.0, n ? double(c.blocks) / n : 0.0);
  };
  pr("all", a.all, a.nhit + a.nmiss);
  pr("hit", a.hit, a.nhit);
  pr("miss", a.miss, a.nmiss);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || argc > 4) {
    std::fprintf(stderr, "usage: bvh_visits MESH.obj RAYS [MAX_RAYS]\n");
    return 2;
  }
  const size_t max_rays = argc == 4 ? std::strtoull(argv[3], nullptr, 10) : SIZE_MAX;
  std::vector<std::string> warnings;
  PolygonSoup soup;
  try {
    soup = load_obj_file(argv[1], false, warnings).soup;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  std::vector<Aabb> boxes;
  for (const std::vector<uint32_t>& poly : soup.polygons)
    for (size_t k = 1; k + 1 < poly.size(); ++k) {  // a fan, as the loaders triangulate
      Aabb box;
      for (uint32_t v : {poly[0], poly[k], poly[k + 1]}) {
        glm::vec3 p(soup.positions[v]);
        box.grow(p);
        g_pos.push_back(glm::dvec3(p));
      }
      boxes.push_back(box);
    }
  std::printf("mesh: %zu triangles\n", boxes.size());

  std::vector<Ray> rays;
  FILE* f = std::fopen(argv[2], "rb");
  if (!f) {
    std::perror(argv[2]);
    return 2;
  }
  Ray r;
  while (rays.size() < max_rays && std::fread(&r, sizeof r, 1, f) == 1) rays.push_back(r);
  std::fclose(f);
  std::printf("rays: %zu\n", rays.size());

  Bvh bvh = build_bvh(boxes);
  WTree tp = pathcl_tree(bvh, collapse_to_bvh8(bvh.nodes), "pathcl");
  stats("pathcl", tp);
  WTree t16 = pathcl_tree(bvh, collapse_to_bvh16(bvh.nodes), "pathcl16");
  stats("pathcl16", t16);
  WTree te = embree_tree(boxes);
  stats("embree", te);
  std::vector<int64_t> hp, he;
  run("pathcl", tp, rays, hp);
  run("embree", te, rays, he);
  std::vector<int64_t> h16;
  run("pathcl16", t16, rays, h16);
  size_t same = 0;
  for (size_t i = 0; i < rays.size(); ++i) same += hp[i] == he[i] && h16[i] == he[i];
  std::printf("same hit (triangle index or both miss): %zu / %zu = %.6f\n", same, rays.size(), double(same) / rays.size());
  return 0;
}
