#include "scene/mesh_subdivide.h"

#include <map>
#include <tuple>

#include <glm/glm.hpp>

void subdivide_mesh(TriangleMesh& mesh, uint32_t n) {
  if (n <= 1) return;
  TriangleMesh out;
  out.positions = mesh.positions;
  // An edge's inner points, keyed by (lower vertex, higher vertex, steps from the lower one).
  std::map<std::tuple<uint32_t, uint32_t, uint32_t>, uint32_t> edge_points;
  auto edge_point = [&](uint32_t a, uint32_t b, uint32_t steps_from_a) {
    if (steps_from_a == 0) return a;
    if (steps_from_a == n) return b;
    if (a > b) {
      std::swap(a, b);
      steps_from_a = n - steps_from_a;
    }
    auto [it, added] = edge_points.try_emplace({a, b, steps_from_a}, uint32_t(out.positions.size()));
    if (added) out.positions.push_back(mesh.positions[a] + (mesh.positions[b] - mesh.positions[a]) * (double(steps_from_a) / n));
    return it->second;
  };
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto [ia, ib, ic] = mesh.triangles[t];
    const glm::dvec3 a = mesh.positions[ia], b = mesh.positions[ib], c = mesh.positions[ic];
    // Grid point (i, j), i + j <= n: a + (b - a) i / n + (c - a) j / n.
    std::vector<uint32_t> grid((n + 1) * (n + 1));
    auto at = [&](uint32_t i, uint32_t j) -> uint32_t& { return grid[i * (n + 1) + j]; };
    for (uint32_t i = 0; i <= n; ++i)
      for (uint32_t j = 0; i + j <= n; ++j) {
        if (j == 0) at(i, j) = edge_point(ia, ib, i);
        else if (i == 0) at(i, j) = edge_point(ia, ic, j);
        else if (i + j == n) at(i, j) = edge_point(ib, ic, j);
        else {
          at(i, j) = uint32_t(out.positions.size());
          out.positions.push_back(a + (b - a) * (double(i) / n) + (c - a) * (double(j) / n));
        }
      }
    // The barycentric weights of a grid point's corners a, b, c.
    auto weights = [&](uint32_t i, uint32_t j) { return glm::vec3(float(n - i - j) / n, float(i) / n, float(j) / n); };
    bool normals = !mesh.normals.empty(), smooth = normals;
    if (normals)
      for (const glm::vec3& v : mesh.normals[t]) smooth = smooth && v != glm::vec3(0.0f);
    auto add = [&](std::array<std::pair<uint32_t, uint32_t>, 3> corners) {
      std::array<uint32_t, 3> tri;
      std::array<glm::vec3, 3> w;
      for (int k = 0; k < 3; ++k) {
        tri[k] = at(corners[k].first, corners[k].second);
        w[k] = weights(corners[k].first, corners[k].second);
      }
      out.triangles.push_back(tri);
      auto mix3 = [&](const std::array<glm::vec3, 3>& v, const glm::vec3& wk) { return v[0] * wk.x + v[1] * wk.y + v[2] * wk.z; };
      if (normals) {
        std::array<glm::vec3, 3> nk{};
        for (int k = 0; k < 3; ++k) nk[k] = smooth ? glm::normalize(mix3(mesh.normals[t], w[k])) : glm::vec3(0.0f);
        out.normals.push_back(nk);
      }
      if (!mesh.uvs.empty()) {
        std::array<glm::vec2, 3> uk;
        const auto& uv = mesh.uvs[t];
        for (int k = 0; k < 3; ++k) uk[k] = uv[0] * w[k].x + uv[1] * w[k].y + uv[2] * w[k].z;
        out.uvs.push_back(uk);
      }
      if (!mesh.colors.empty()) {
        std::array<glm::vec3, 3> ck;
        for (int k = 0; k < 3; ++k) ck[k] = mix3(mesh.colors[t], w[k]);
        out.colors.push_back(ck);
      }
      if (!mesh.materials.empty()) out.materials.push_back(mesh.materials[t]);
      if (!mesh.source_polygon.empty()) out.source_polygon.push_back(mesh.source_polygon[t]);
      if (!mesh.source_corners.empty()) out.source_corners.push_back(mesh.source_corners[t]);
    };
    // Each cell of the grid: the triangle (i, j), (i + 1, j), (i, j + 1) and, inside, the one beside it;
    // both wound as the triangle a, b, c.
    for (uint32_t i = 0; i < n; ++i)
      for (uint32_t j = 0; i + j < n; ++j) {
        add({{{i, j}, {i + 1, j}, {i, j + 1}}});
        if (i + j + 1 < n) add({{{i + 1, j}, {i + 1, j + 1}, {i, j + 1}}});
      }
  }
  mesh = std::move(out);
}
