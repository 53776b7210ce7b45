// The parallel parts of loading (scene/mesh_clean.cpp, scene/mesh_normals.cpp, scene/bvh_build.cpp) give
// the same bits with one thread as with several, run after run: the cleaned mesh, its normals and the BVH's
// nodes and primitive order.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "scene/bvh_build.h"
#include "scene/mesh_clean.h"
#include "scene/obj_load.h"

namespace {

// A wavy height field of n x n quads as a soup that repeats each vertex in every face (so that merging has
// work), with quads (triangulated), duplicate faces, degenerate faces, unused and signed-zero vertices,
// per-corner uvs, and file normals on some faces.
PolygonSoup test_soup(int n) {
  PolygonSoup soup;
  auto height = [](double x, double z) { return 0.3 * std::sin(3.1 * x) * std::cos(2.3 * z) + 0.05 * std::sin(17 * x + 11 * z); };
  auto vertex = [&](int i, int j) {
    double x = double(i) / n - 0.5, z = double(j) / n - 0.5;
    // Signed zeros on the middle row: -0 and +0 are the same point.
    if (i == n / 2) x = (j % 2) ? -0.0 : 0.0;
    soup.positions.push_back({x, height(x, z), z});
    return uint32_t(soup.positions.size() - 1);
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = vertex(i, j), b = vertex(i + 1, j), c = vertex(i + 1, j + 1), d = vertex(i, j + 1);
      std::vector<glm::vec2> uv{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      if ((i + j) % 7 == 0) {
        soup.polygons.push_back({a, d, c, b});  // a quad, triangulated by CGAL
        soup.uvs.push_back(uv);
        soup.normals.push_back({});
      } else {
        soup.polygons.push_back({a, d, c});
        soup.polygons.push_back({a, c, b});
        soup.uvs.push_back({uv[0], uv[3], uv[2]});
        soup.uvs.push_back({uv[0], uv[2], uv[1]});
        if ((i + 2 * j) % 5 == 0) {
          soup.normals.push_back({{0, 1, 0}, {0, 2, 0.1f}, {0.1f, 1, 0}});
          soup.normals.push_back({});
        } else {
          soup.normals.push_back({});
          soup.normals.push_back({});
        }
      }
      if ((i * 3 + j) % 11 == 0) {  // a duplicate in the other orientation
        soup.polygons.push_back({a, b, c});
        soup.uvs.push_back({});
        soup.normals.push_back({});
      }
      if ((i + j * 5) % 13 == 0) {  // a degenerate face
        soup.polygons.push_back({a, a, b});
        soup.uvs.push_back({});
        soup.normals.push_back({});
      }
    }
  soup.positions.push_back({5, 5, 5});  // isolated
  return soup;
}

template <class T>
void expect_same_bits(const std::vector<T>& a, const std::vector<T>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  // (memcmp must not see the null data() of an empty vector.)
  if (!a.empty()) {
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(T)), 0) << what << " differ";
  }
}

void expect_same_mesh(const TriangleMesh& a, const CleanReport& ra, const TriangleMesh& b, const CleanReport& rb) {
  expect_same_bits(a.positions, b.positions, "positions");
  expect_same_bits(a.triangles, b.triangles, "triangles");
  expect_same_bits(a.normals, b.normals, "normals");
  expect_same_bits(a.source_polygon, b.source_polygon, "source polygons");
  expect_same_bits(a.source_corners, b.source_corners, "source corners");
  expect_same_bits(a.uvs, b.uvs, "uvs");
  EXPECT_EQ(ra.merged_vertices, rb.merged_vertices);
  EXPECT_EQ(ra.removed_isolated_vertices, rb.removed_isolated_vertices);
  EXPECT_EQ(ra.degenerate_faces, rb.degenerate_faces);
  EXPECT_EQ(ra.duplicate_faces, rb.duplicate_faces);
  EXPECT_EQ(ra.polygons_triangulated, rb.polygons_triangulated);
  EXPECT_EQ(ra.closed, rb.closed);
}

TriangleMesh clean_with_threads(const PolygonSoup& soup, const CleanOptions& options, size_t threads, CleanReport& report) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  return clean_mesh(soup, options, report);
}

Bvh bvh_with_threads(const std::vector<Aabb>& boxes, size_t threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  return build_bvh(boxes);
}

// Triangle boxes of the mesh, plus a cluster of boxes with one centroid (the count split) and boxes
// at -0 and +0.
std::vector<Aabb> test_boxes(const TriangleMesh& mesh) {
  std::vector<Aabb> boxes;
  for (const auto& t : mesh.triangles) {
    Aabb box;
    for (uint32_t v : t) box.grow(glm::vec3(mesh.positions[v]));
    boxes.push_back(box);
  }
  for (int i = 0; i < 5000; ++i) boxes.push_back({glm::vec3(2.0f - 1e-3f * float(i % 7)), glm::vec3(2.0f + 1e-3f * float(i % 7))});
  for (int i = 0; i < 3000; ++i) {
    const float z = (i % 2) ? -0.0f : 0.0f;
    boxes.push_back({glm::vec3(z, 0.001f * float(i), z), glm::vec3(0.5f, 0.001f * float(i) + 0.01f, z)});
  }
  return boxes;
}

void expect_same_bvh(const Bvh& a, const Bvh& b) {
  expect_same_bits(a.nodes, b.nodes, "BVH nodes");
  expect_same_bits(a.prim_order, b.prim_order, "primitive order");
  EXPECT_EQ(std::memcmp(&a.sah_cost, &b.sah_cost, sizeof a.sah_cost), 0) << a.sah_cost << " " << b.sah_cost;
  EXPECT_EQ(a.depth, b.depth);
  EXPECT_EQ(a.leaf_count, b.leaf_count);
  EXPECT_EQ(a.max_leaf_size, b.max_leaf_size);
  EXPECT_EQ(a.node_count, b.node_count);
}

// Large enough for the parallel paths: the duplicate points, faces and edges sorts, more than 2 x 32768
// primitives at the BVH's root (its chunked bins) and subtrees of more than 8192 (its tasks).
constexpr int kGrid = 200;

TEST(ParallelBuild, CleanUpIsTheSameForAnyThreadCount) {
  const PolygonSoup soup = test_soup(kGrid);
  for (bool smooth : {false, true}) {
    CleanOptions options;
    options.smooth_normals = smooth;
    CleanReport one_report;
    const TriangleMesh one = clean_with_threads(soup, options, 1, one_report);
    EXPECT_GT(one_report.merged_vertices, soup.positions.size() / 2);
    EXPECT_GT(one_report.duplicate_faces, 0u);
    EXPECT_GT(one_report.degenerate_faces, 0u);
    EXPECT_GT(one_report.polygons_triangulated, 0u);
    EXPECT_EQ(one_report.removed_isolated_vertices, 1u);
    for (size_t threads : {2, 3, 8, 8, 8}) {
      SCOPED_TRACE("smooth " + std::to_string(smooth) + ", " + std::to_string(threads) + " threads");
      CleanReport report;
      const TriangleMesh many = clean_with_threads(soup, options, threads, report);
      expect_same_mesh(one, one_report, many, report);
    }
  }
}

TEST(ParallelBuild, OrientedCleanUpIsTheSameForAnyThreadCount) {
  const PolygonSoup soup = test_soup(40);
  CleanOptions options;
  options.orient = true;
  options.smooth_normals = true;
  CleanReport one_report;
  const TriangleMesh one = clean_with_threads(soup, options, 1, one_report);
  for (size_t threads : {2, 8}) {
    CleanReport report;
    expect_same_mesh(one, one_report, clean_with_threads(soup, options, threads, report), report);
  }
}

TEST(ParallelBuild, BvhIsTheSameForAnyThreadCount) {
  CleanReport report;
  const TriangleMesh mesh = clean_with_threads(test_soup(kGrid), CleanOptions{}, 1, report);
  const std::vector<Aabb> boxes = test_boxes(mesh);
  ASSERT_GT(boxes.size(), 2u * 32768);
  const Bvh one = bvh_with_threads(boxes, 1);
  EXPECT_GT(one.depth, 10u);
  for (size_t threads : {2, 3, 8, 8, 8}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    expect_same_bvh(one, bvh_with_threads(boxes, threads));
  }
}

// The same OBJ file read with one thread and with several gives the same soup.
TEST(ParallelBuild, ObjParseIsTheSameForAnyThreadCount) {
  const PolygonSoup soup = test_soup(60);
  const std::string path = testing::TempDir() + "parallel_build_test.obj";
  {
    std::ofstream out(path);
    out << "# test\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\n";
    char line[160];
    for (const glm::dvec3& p : soup.positions) {
      std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
      out << line;
    }
    for (size_t f = 0; f < soup.polygons.size(); ++f) {
      out << (f % 1000 == 0 ? "\r\n" : "") << "f";
      for (size_t k = 0; k < soup.polygons[f].size(); ++k) {
        out << ' ' << soup.polygons[f][k] + 1;
        if (f % 3 == 1) out << '/' << (k % 4) + 1;
        else if (f % 3 == 2) out << '/' << (k % 4) + 1 << "/1";
      }
      out << (f % 2 ? "\r\n" : "\n");
    }
  }
  std::vector<std::string> warnings;
  ObjFile one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = load_obj_file(path, false, warnings);
  }
  for (size_t threads : {2, 8}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    const ObjFile many = load_obj_file(path, false, warnings);
    expect_same_bits(one.soup.positions, many.soup.positions, "positions");
    EXPECT_EQ(one.soup.polygons, many.soup.polygons);
    EXPECT_EQ(one.face_lines, many.face_lines);
    ASSERT_EQ(one.soup.uvs.size(), many.soup.uvs.size());
    for (size_t f = 0; f < one.soup.uvs.size(); ++f) expect_same_bits(one.soup.uvs[f], many.soup.uvs[f], "uvs");
    ASSERT_EQ(one.soup.normals.size(), many.soup.normals.size());
    for (size_t f = 0; f < one.soup.normals.size(); ++f) expect_same_bits(one.soup.normals[f], many.soup.normals[f], "normals");
  }
  EXPECT_EQ(one.soup.polygons.size(), soup.polygons.size());
  EXPECT_EQ(one.face_lines.back(), 6 + soup.positions.size() + soup.polygons.size() + (soup.polygons.size() + 999) / 1000);
  std::remove(path.c_str());
}

}  // namespace
