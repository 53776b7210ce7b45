// Crease-angle smooth normals over the fan of triangles around each vertex; see mesh_normals.h.
#include "scene/mesh_normals.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace {

// Union-find over the corners of one vertex's fan that also keeps, for each corner, whether its face is
// reversed relative to its group's root (the parity of the path to it).
struct OrientedUnionFind {
  std::vector<uint32_t> parent;
  std::vector<uint8_t> flipped;  // relative to parent

  // n singletons (reusing the arrays: one per task, not one per vertex).
  void reset(size_t n) {
    parent.resize(n);
    flipped.assign(n, 0);
    for (size_t i = 0; i < n; ++i) parent[i] = uint32_t(i);
  }
  // The root of x, with x's parity relative to it in `parity`; compresses the path.
  uint32_t find(uint32_t x, uint8_t& parity) {
    uint8_t p = 0;
    uint32_t root = x;
    while (parent[root] != root) p ^= flipped[root], root = parent[root];
    parity = p;
    // Second pass: point every node on the path at the root with its own parity.
    while (parent[x] != root) {
      uint32_t next = parent[x];
      uint8_t next_parity = p ^ flipped[x];
      parent[x] = root;
      flipped[x] = p;
      x = next;
      p = next_parity;
    }
    return root;
  }
  // Joins the groups of a and b with b's face reversed relative to a's when `reversed`; a loop of
  // faces that cannot be oriented (a Möbius strip) keeps the parity found first.
  void unite(uint32_t a, uint32_t b, bool reversed) {
    uint8_t pa, pb;
    uint32_t ra = find(a, pa), rb = find(b, pb);
    if (ra == rb) return;
    parent[rb] = ra;
    flipped[rb] = uint8_t(pa ^ pb ^ uint8_t(reversed));
  }
};

// One edge of a fan at its vertex v: the other end, the corner whose face has it, and whether that face
// runs along it away from v (v -> other) or towards v.
struct FanEdge {
  uint32_t other, corner;
  bool outgoing;
};

// Above this many faces on one edge (a degenerate input), only neighbours in the sorted list are tested
// against each other, so that the work stays linear.
constexpr size_t kAllPairsLimit = 8;

}  // namespace

void generate_smooth_normals(const std::vector<glm::dvec3>& positions,
                             const std::vector<std::array<uint32_t, 3>>& triangles, float crease_degrees,
                             const std::vector<bool>& fill, std::vector<std::array<glm::vec3, 3>>& normals) {
  const size_t count = triangles.size();
  // Unit face normals and the angle of each corner, in double like the positions.
  std::vector<glm::dvec3> face(count);
  std::vector<std::array<double, 3>> angle(count);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t t = range.begin(); t < range.end(); ++t) {
      const auto& tri = triangles[t];
      glm::dvec3 n = glm::cross(positions[tri[1]] - positions[tri[0]], positions[tri[2]] - positions[tri[0]]);
      double length = glm::length(n);
      face[t] = length > 0 ? n / length : glm::dvec3(0);
      for (int k = 0; k < 3; ++k) {
        glm::dvec3 e1 = positions[tri[(k + 1) % 3]] - positions[tri[k]];
        glm::dvec3 e2 = positions[tri[(k + 2) % 3]] - positions[tri[k]];
        angle[t][k] = std::atan2(glm::length(glm::cross(e1, e2)), glm::dot(e1, e2));  // accurate at any angle
      }
    }
  });
  // cos(pi) rounds to -1 exactly, but a dot product of unit normals may round below it.
  const double min_cos = crease_degrees >= 180 ? -2.0 : std::cos(double(crease_degrees) * M_PI / 180.0);

  // The corners (3 t + k) around each vertex, as offsets into one array.
  std::vector<uint32_t> first(positions.size() + 1, 0), corners(3 * count);
  for (const auto& tri : triangles)
    for (uint32_t v : tri) ++first[v + 1];
  for (size_t v = 0; v < positions.size(); ++v) first[v + 1] += first[v];
  {
    std::vector<uint32_t> next(first.begin(), first.end() - 1);
    for (size_t t = 0; t < count; ++t)
      for (int k = 0; k < 3; ++k) corners[next[triangles[t][k]]++] = uint32_t(3 * t + k);
  }

  // Each vertex's fan is done by one task, in the same order as a serial loop: the result does not depend
  // on the number of threads.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, positions.size()), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<FanEdge> edges;
    std::vector<glm::dvec3> sums;
    OrientedUnionFind groups;
    for (size_t v = range.begin(); v < range.end(); ++v) {
      const uint32_t* fan = corners.data() + first[v];
      const size_t size = first[v + 1] - first[v];
      bool needed = false;
      for (size_t i = 0; i < size && !needed; ++i) needed = fill.empty() || fill[fan[i] / 3];
      if (!needed) continue;

      edges.clear();
      for (uint32_t i = 0; i < size; ++i) {
        const auto& tri = triangles[fan[i] / 3];
        const uint32_t k = fan[i] % 3;
        edges.push_back({tri[(k + 1) % 3], i, true});   // the face runs v -> next
        edges.push_back({tri[(k + 2) % 3], i, false});  // and previous -> v
      }
      std::sort(edges.begin(), edges.end(), [](const FanEdge& a, const FanEdge& b) { return a.other < b.other; });
      groups.reset(size);
      for (size_t a = 0; a < edges.size();) {
        size_t b = a;
        while (b < edges.size() && edges[b].other == edges[a].other) ++b;
        for (size_t i = a; i < b; ++i)
          for (size_t j = i + 1; j < (b - a <= kAllPairsLimit ? b : std::min(b, i + 2)); ++j) {
            const FanEdge &e = edges[i], &f = edges[j];
            if (e.corner == f.corner) continue;
            // Faces that agree run along the shared edge in opposite directions.
            const bool reversed = e.outgoing == f.outgoing;
            const double cos_between = glm::dot(face[fan[e.corner] / 3], face[fan[f.corner] / 3]) * (reversed ? -1 : 1);
            if (cos_between >= min_cos) groups.unite(e.corner, f.corner, reversed);
          }
        a = b;
      }
      sums.assign(size, glm::dvec3(0));
      for (uint32_t i = 0; i < size; ++i) {
        uint8_t parity;
        const uint32_t root = groups.find(i, parity);
        const uint32_t t = fan[i] / 3, k = fan[i] % 3;
        sums[root] += (parity ? -1.0 : 1.0) * angle[t][k] * face[t];
      }
      for (uint32_t i = 0; i < size; ++i) {
        const uint32_t t = fan[i] / 3, k = fan[i] % 3;
        if (!fill.empty() && !fill[t]) continue;
        uint8_t parity;
        const uint32_t root = groups.find(i, parity);  // before parity is read: operands of * are unsequenced
        const glm::dvec3 sum = sums[root] * (parity ? -1.0 : 1.0);
        // Normalized in double, then again in float so that the stored normal is unit there.
        const double length = glm::length(sum);
        glm::vec3 n = length > 0 && std::isfinite(length) ? glm::vec3(sum / length) : glm::vec3(0);
        const float float_length = glm::length(n);
        // Corner 3 t + k is in v's fan only: no other task writes this entry.
        normals[t][k] = float_length > 0 ? n / float_length : glm::vec3(0);
      }
    }
  });
}
