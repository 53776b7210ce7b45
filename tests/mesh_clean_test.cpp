// Tests for clean_mesh (scene/mesh_clean.cpp): merging, degeneracies, duplicates, triangulation,
// orientation and smooth normals. In scripts/sanitize's build with CGAL's own checks on (CMakeLists.txt);
// in Release as users run it, without them.
#include "scene/mesh_clean.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "scene/scene_error.h"

namespace {

using glm::dvec3;
using glm::vec3;

dvec3 d(const dvec3& v) { return v; }

glm::dvec3 tri_normal(const TriangleMesh& m, const std::array<uint32_t, 3>& t) {
  const glm::dvec3 a = d(m.positions[t[0]]), b = d(m.positions[t[1]]), c = d(m.positions[t[2]]);
  return glm::cross(b - a, c - a);  // length = 2 * area
}

double total_area(const TriangleMesh& m) {
  double area = 0;
  for (const auto& t : m.triangles) area += 0.5 * glm::length(tri_normal(m, t));
  return area;
}

// Signed volume by the divergence theorem: positive when a closed mesh's faces point outward.
double signed_volume(const TriangleMesh& m) {
  double v = 0;
  for (const auto& t : m.triangles)
    v += glm::dot(d(m.positions[t[0]]), glm::cross(d(m.positions[t[1]]), d(m.positions[t[2]]))) / 6.0;
  return v;
}

// Every undirected edge is used once in each direction: a consistently oriented closed surface.
bool consistently_oriented_closed(const TriangleMesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const auto& t : m.triangles)
    for (int i = 0; i < 3; ++i) ++directed[{t[i], t[(i + 1) % 3]}];
  for (const auto& [e, n] : directed)
    if (n != 1 || directed.count({e.second, e.first}) == 0) return false;
  return true;
}

// No directed edge used twice: neighbouring faces agree (the surface may be open).
bool consistently_oriented(const TriangleMesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const auto& t : m.triangles)
    for (int i = 0; i < 3; ++i)
      if (++directed[{t[i], t[(i + 1) % 3]}] > 1) return false;
  return true;
}

dvec3 centroid(const TriangleMesh& m, std::size_t tri) {
  const auto& t = m.triangles[tri];
  return (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3.0;
}

// Unit cube [0,1]^3 as 8 shared vertices and 6 outward (CCW seen from outside) quads.
PolygonSoup cube_quads() {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  s.polygons = {
      {0, 3, 2, 1},  // z = 0, normal -z
      {4, 5, 6, 7},  // z = 1, normal +z
      {0, 1, 5, 4},  // y = 0, normal -y
      {3, 7, 6, 2},  // y = 1, normal +y
      {0, 4, 7, 3},  // x = 0, normal -x
      {1, 2, 6, 5},  // x = 1, normal +x
  };
  return s;
}

TEST(MeshClean, ReportsInputSizes) {
  PolygonSoup s = cube_quads();
  CleanReport r;
  clean_mesh(s, {}, r);
  EXPECT_EQ(r.input_vertices, 8u);
  EXPECT_EQ(r.input_polygons, 6u);
}

TEST(MeshClean, MergesDuplicateVertices) {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  s.polygons = {{0, 1, 2}, {3, 4, 5}};
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  EXPECT_EQ(m.positions.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(r.merged_vertices, 2u);
  EXPECT_FALSE(r.closed);
  // The shared edge really is shared now: exactly 5 distinct undirected edges.
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (const auto& t : m.triangles)
    for (int i = 0; i < 3; ++i) ++edges[{std::min(t[i], t[(i + 1) % 3]), std::max(t[i], t[(i + 1) % 3])}];
  EXPECT_EQ(edges.size(), 5u);
  // Positions are kept exactly, in input order (first occurrence).
  EXPECT_EQ(m.positions[0], dvec3(0, 0, 0));
  EXPECT_EQ(m.positions[1], dvec3(1, 0, 0));
  EXPECT_EQ(m.positions[2], dvec3(1, 1, 0));
  EXPECT_EQ(m.positions[3], dvec3(0, 1, 0));
  // Winding kept: both face +z.
  for (const auto& t : m.triangles) EXPECT_GT(tri_normal(m, t).z, 0.0);
}

TEST(MeshClean, RemovesCollinearTriangle) {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}};
  s.polygons = {{0, 1, 2}, {3, 4, 5}};
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(r.degenerate_faces, 1u);
  EXPECT_EQ(r.removed_isolated_vertices, 3u);
  EXPECT_EQ(m.positions.size(), 3u);
}

TEST(MeshClean, CollinearityIsExactOnFloatCoordinates) {
  // Exactly collinear, with non-integer coordinates: removed.
  PolygonSoup s;
  s.positions = {{0.5f, 0.25f, 0}, {1.0f, 0.5f, 0}, {2.0f, 1.0f, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  s.polygons = {{0, 1, 2}, {3, 4, 5}};
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  EXPECT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(r.degenerate_faces, 1u);

  // A sliver one float step off the line: tiny but not zero area, so it is kept.
  s.positions[2].y = std::nextafter(1.0f, 2.0f);
  m = clean_mesh(s, {}, r);
  EXPECT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(r.degenerate_faces, 0u);
}

TEST(MeshClean, RemovesTriangleWithRepeatedVertex) {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}};
  // Same index twice, and a different index at the same place as vertex 1 (merged, then degenerate).
  s.positions.push_back({1, 0, 0});
  s.polygons = {{0, 1, 2}, {0, 3, 3}, {1, 4, 0}, {2, 2}};
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(r.degenerate_faces, 3u);
  EXPECT_EQ(r.merged_vertices, 1u);
  EXPECT_EQ(r.removed_isolated_vertices, 1u);  // (5, 5, 5)
  EXPECT_EQ(m.positions.size(), 3u);
}

TEST(MeshClean, RemovesDuplicateFacesKeepingTheFirst) {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  s.polygons = {{0, 2, 1},   // first: faces -z
                {0, 1, 3},   // another face
                {1, 2, 0},   // same as the first, reversed orientation
                {1, 0, 2},   // same as the first, rotated
                {3, 1, 0}};  // same as the second, reversed
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(r.duplicate_faces, 3u);
  // The first one is kept with its own winding and order.
  EXPECT_LT(tri_normal(m, m.triangles[0]).z, 0.0);
  EXPECT_LT(tri_normal(m, m.triangles[1]).y, 0.0);
}

// L-shaped hexagon (non-convex at (1, 1)) of area 3 in the plane z = 0, counter-clockwise seen from +z.
PolygonSoup l_shape() {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}, {1, 2, 0}, {0, 2, 0}};
  s.polygons = {{0, 1, 2, 3, 4, 5}};
  return s;
}

TEST(MeshClean, TriangulatesNonConvexPolygon) {
  // Try every starting vertex: a fan from some of them would cover area outside the L.
  for (uint32_t start = 0; start < 6; ++start) {
    PolygonSoup s = l_shape();
    std::rotate(s.polygons[0].begin(), s.polygons[0].begin() + start, s.polygons[0].end());
    CleanReport r;
    TriangleMesh m = clean_mesh(s, {}, r);
    ASSERT_EQ(m.triangles.size(), 4u) << "start " << start;
    EXPECT_EQ(r.polygons_triangulated, 1u);
    EXPECT_EQ(r.triangles_from_polygons, 4u);
    EXPECT_NEAR(total_area(m), 3.0, 1e-5) << "start " << start;
    for (const auto& t : m.triangles) EXPECT_GT(tri_normal(m, t).z, 0.0) << "start " << start;
    // No triangle's centroid lies in the notch [1,2]x[1,2].
    for (std::size_t i = 0; i < m.triangles.size(); ++i) {
      const dvec3 c = centroid(m, i);
      EXPECT_FALSE(c.x > 1 && c.y > 1) << "start " << start;
    }
  }
}

TEST(MeshClean, TriangulationKeepsClockwiseWinding) {
  PolygonSoup s = l_shape();
  std::reverse(s.polygons[0].begin(), s.polygons[0].end());
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_NEAR(total_area(m), 3.0, 1e-5);
  for (const auto& t : m.triangles) EXPECT_LT(tri_normal(m, t).z, 0.0);
}

TEST(MeshClean, TriangulatesTiltedNonConvexPolygon) {
  // The L in a tilted plane (rotated about x by 30 degrees): same area, triangles face the polygon normal.
  PolygonSoup s = l_shape();
  const float c = std::cos(0.5235988f), sn = std::sin(0.5235988f);
  for (dvec3& p : s.positions) p = dvec3(p.x, c * p.y - sn * p.z, sn * p.y + c * p.z);
  const glm::dvec3 normal(0, -sn, c);
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_NEAR(total_area(m), 3.0, 1e-5);
  for (const auto& t : m.triangles) EXPECT_GT(glm::dot(tri_normal(m, t), normal), 0.0);
}

TEST(MeshClean, TriangulatesNonPlanarPolygonFacingItsNormal) {
  // A hexagon zig-zagging in z (too far from planar for CGAL's 2D path): the 3D hole filler is used;
  // every triangle still faces the polygon's side, for both windings.
  for (bool reversed : {false, true}) {
    PolygonSoup s;
    for (int i = 0; i < 6; ++i) {
      const float a = static_cast<float>(i) * 1.04719755f;
      s.positions.push_back({std::cos(a), std::sin(a), (i % 2) ? 0.8f : -0.8f});
    }
    s.polygons = {{0, 1, 2, 3, 4, 5}};
    if (reversed) std::reverse(s.polygons[0].begin(), s.polygons[0].end());
    CleanReport r;
    TriangleMesh m = clean_mesh(s, {}, r);
    ASSERT_EQ(m.triangles.size(), 4u);
    for (const auto& t : m.triangles) EXPECT_GT(tri_normal(m, t).z * (reversed ? -1 : 1), 0.0) << reversed;
  }
}

TEST(MeshClean, KeepsTriangleOrder) {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},                  // triangle A at z = 0
                 {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1},       // quad B at z = 1
                 {0, 0, 2}, {1, 0, 2}, {2, 0, 2},                  // collinear C at z = 2
                 {0, 0, 3}, {1, 0, 3}, {0, 1, 3}};                 // triangle D at z = 3
  // A duplicate of A right after it: CGAL's duplicate removal moves the last triangle into its place.
  s.polygons = {{0, 1, 2}, {2, 1, 0}, {3, 4, 5, 6}, {7, 8, 9}, {10, 11, 12}};
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(r.duplicate_faces, 1u);
  EXPECT_GT(tri_normal(m, m.triangles[0]).z, 0.0);  // A, not its reversed duplicate
  EXPECT_FLOAT_EQ(centroid(m, 0).z, 0.0f);
  EXPECT_FLOAT_EQ(centroid(m, 1).z, 1.0f);
  EXPECT_FLOAT_EQ(centroid(m, 2).z, 1.0f);
  EXPECT_FLOAT_EQ(centroid(m, 3).z, 3.0f);
  // Vertex order: the input's, without the removed (isolated) ones.
  ASSERT_EQ(m.positions.size(), 10u);
  EXPECT_EQ(m.positions[6], dvec3(0, 1, 1));
  EXPECT_EQ(m.positions[7], dvec3(0, 0, 3));
  EXPECT_EQ(r.removed_isolated_vertices, 3u);
}

TEST(MeshClean, OrientFixesInvertedQuadOfCube) {
  PolygonSoup s = cube_quads();
  std::reverse(s.polygons[3].begin(), s.polygons[3].end());
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {.orient = true}, r);
  ASSERT_EQ(m.triangles.size(), 12u);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(consistently_oriented_closed(m));
  EXPECT_NEAR(signed_volume(m), 1.0, 1e-6);
  EXPECT_EQ(r.faces_flipped, 2u);  // the two triangles of the inverted quad
  EXPECT_EQ(r.polygons_triangulated, 6u);
  EXPECT_EQ(r.triangles_from_polygons, 12u);
  EXPECT_EQ(m.positions.size(), 8u);
  // Triangles 6 and 7 come from the (fixed) y = 1 quad: they now face +y.
  EXPECT_GT(tri_normal(m, m.triangles[6]).y, 0.0);
  EXPECT_GT(tri_normal(m, m.triangles[7]).y, 0.0);
}

TEST(MeshClean, OrientTurnsInsideOutCubeOutward) {
  PolygonSoup s = cube_quads();
  for (auto& p : s.polygons) std::reverse(p.begin(), p.end());
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {.orient = true}, r);
  EXPECT_TRUE(r.closed);
  EXPECT_NEAR(signed_volume(m), 1.0, 1e-6);
  EXPECT_EQ(r.faces_flipped, 12u);
}

TEST(MeshClean, WithoutOrientWindingIsKept) {
  PolygonSoup s = cube_quads();
  std::reverse(s.polygons[3].begin(), s.polygons[3].end());
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  ASSERT_EQ(m.triangles.size(), 12u);
  EXPECT_TRUE(r.closed);  // closed is about edge use, not orientation
  EXPECT_EQ(r.faces_flipped, 0u);
  EXPECT_FALSE(consistently_oriented_closed(m));
  EXPECT_LT(tri_normal(m, m.triangles[6]).y, 0.0);
  EXPECT_LT(tri_normal(m, m.triangles[7]).y, 0.0);
  EXPECT_NEAR(signed_volume(m), 1.0 - 2.0 / 3.0, 1e-6);  // the y = 1 face's +1/3 now counts -1/3
}

TEST(MeshClean, OrientOpenBoxIsConsistent) {
  PolygonSoup s = cube_quads();
  s.polygons.erase(s.polygons.begin() + 1);               // open top
  std::reverse(s.polygons[2].begin(), s.polygons[2].end());  // invert the y = 1 side
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {.orient = true}, r);
  ASSERT_EQ(m.triangles.size(), 10u);
  EXPECT_FALSE(r.closed);
  EXPECT_TRUE(consistently_oriented(m));
  // Either the inverted side or the other four were flipped.
  EXPECT_TRUE(r.faces_flipped == 2u || r.faces_flipped == 8u) << r.faces_flipped;
}

// Checks unit shading normals at every corner that point outward (for a shape around the origin).
void expect_outward_unit_normals(const TriangleMesh& m) {
  ASSERT_EQ(m.normals.size(), m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(glm::length(m.normals[t][k]), 1.0f, 1e-5f) << t << " " << k;
      EXPECT_GT(glm::dot(m.normals[t][k], vec3(m.positions[m.triangles[t][k]])), 0.0f) << t << " " << k;
    }
}

vec3 unit_face_normal(const TriangleMesh& m, std::size_t t) { return vec3(glm::normalize(tri_normal(m, m.triangles[t]))); }

TEST(MeshClean, SmoothNormalsKeepACubesEdgesSharpAtTheDefaultAngle) {
  PolygonSoup s = cube_quads();
  for (dvec3& p : s.positions) p -= dvec3(0.5);  // centre on the origin
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {.smooth_normals = true}, r);
  expect_outward_unit_normals(m);
  // 90 degrees between the sides, more than the default 60: every corner has its own face's normal,
  // also where the two triangles of one side meet (0 degrees, smoothed).
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(glm::dot(m.normals[t][k], unit_face_normal(m, t)), 1.0f, 1e-6f) << t;
}

TEST(MeshClean, SmoothNormalsAtACreaseAngleOf180SmoothEverything) {
  PolygonSoup s = cube_quads();
  for (dvec3& p : s.positions) p -= dvec3(0.5);
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {.smooth_normals = true, .smooth_angle_degrees = 180}, r);
  expect_outward_unit_normals(m);
  // The angle weights make a cube corner's normal the diagonal, however the sides are triangulated.
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(glm::dot(m.normals[t][k], vec3(glm::normalize(m.positions[m.triangles[t][k]]))), 1.0f, 1e-6f);
}

TEST(MeshClean, SmoothNormalsOfOctahedronPointOutward) {
  PolygonSoup s;
  s.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  s.polygons = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  CleanReport r;
  // Neighbouring faces are 70.5 degrees apart.
  TriangleMesh m = clean_mesh(s, {.smooth_normals = true, .smooth_angle_degrees = 75}, r);
  EXPECT_TRUE(r.closed);
  EXPECT_NEAR(signed_volume(m), 4.0 / 3.0, 1e-6);
  expect_outward_unit_normals(m);
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)  // exactly radial by symmetry
      EXPECT_NEAR(glm::dot(m.normals[t][k], vec3(m.positions[m.triangles[t][k]])), 1.0f, 1e-6f);
  m = clean_mesh(s, {.smooth_normals = true, .smooth_angle_degrees = 70}, r);
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(glm::dot(m.normals[t][k], unit_face_normal(m, t)), 1.0f, 1e-6f);
}

// A UV sphere of `rings` x 2 `rings` quads (triangles at the poles), radius 1, outward.
PolygonSoup uv_sphere(int rings) {
  PolygonSoup s;
  const int segments = 2 * rings;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      // Exact poles, so that each pole row merges into one point.
      double theta = M_PI * i / rings, phi = 2 * M_PI * j / segments;
      double sin_theta = i == 0 || i == rings ? 0 : std::sin(theta), cos_theta = i == 0 ? 1 : i == rings ? -1 : std::cos(theta);
      s.positions.push_back({sin_theta * std::cos(phi), cos_theta, -sin_theta * std::sin(phi)});
    }
  auto at = [&](int i, int j) { return uint32_t(i * segments + (j % segments)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) s.polygons.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
  return s;  // the pole rows repeat one point: merged, and their quads become triangles
}

TEST(MeshClean, SmoothNormalsSmoothACoarseSphereAtTheDefaultAngle) {
  // 8 rings: 22.5 degrees between neighbouring faces' normals around the equator, about 32 at the poles.
  PolygonSoup s = uv_sphere(8);
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {.smooth_normals = true}, r);
  EXPECT_TRUE(r.closed);
  expect_outward_unit_normals(m);
  // One normal per vertex (every corner of a vertex has the same), close to the sphere's.
  std::map<uint32_t, vec3> by_vertex;
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      auto [it, added] = by_vertex.emplace(m.triangles[t][k], m.normals[t][k]);
      EXPECT_NEAR(glm::dot(it->second, m.normals[t][k]), 1.0f, 1e-6f) << "vertex " << it->first;
      // Within 2 degrees: the rings above and below a vertex differ in size, and it leans towards the larger.
      EXPECT_GT(glm::dot(m.normals[t][k], vec3(m.positions[m.triangles[t][k]])), std::cos(glm::radians(2.0f)));
    }
  // At 20 degrees the edges at the equator are creases (22.5 degrees between the faces on either side,
  // up and down and around): every corner there has its face's normal.
  m = clean_mesh(s, {.smooth_normals = true, .smooth_angle_degrees = 20}, r);
  std::size_t equator_corners = 0;
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      if (std::abs(m.positions[m.triangles[t][k]].y) < 1e-12) {
        ++equator_corners;
        EXPECT_NEAR(glm::dot(m.normals[t][k], unit_face_normal(m, t)), 1.0f, 1e-6f) << t;
      }
  EXPECT_GE(equator_corners, 16u * 4);
}

// Three triangles on the edge (0, 1): a non-manifold edge.
PolygonSoup three_fins() {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}};
  s.polygons = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  return s;
}

TEST(MeshClean, SmoothNormalsWithoutOrientOnNonManifoldSoup) {
  // The fins 0 and 1 lie in y = 0 and agree along the edge: smoothed, along y. Fin 2 (x = 0) meets them
  // at 90 degrees: its own normal, along x.
  CleanReport r;
  TriangleMesh m = clean_mesh(three_fins(), {.smooth_normals = true}, r);
  ASSERT_EQ(m.triangles.size(), 3u);
  ASSERT_EQ(m.normals.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(std::abs(m.normals[0][k].y), 1.0f, 1e-6f);
    EXPECT_NEAR(std::abs(m.normals[1][k].y), 1.0f, 1e-6f);
    EXPECT_NEAR(std::abs(m.normals[2][k].x), 1.0f, 1e-6f);
    for (int t = 0; t < 3; ++t) EXPECT_GT(glm::dot(m.normals[t][k], unit_face_normal(m, t)), 0.99f);
  }
  // Inconsistently oriented (one side of the cube reversed) and not oriented: at 180 degrees every
  // corner still gets the cube's diagonal, turned to its own face's side.
  PolygonSoup cube = cube_quads();
  for (dvec3& p : cube.positions) p -= dvec3(0.5);
  std::reverse(cube.polygons[0].begin(), cube.polygons[0].end());
  m = clean_mesh(cube, {.smooth_normals = true, .smooth_angle_degrees = 180}, r);
  ASSERT_EQ(m.normals.size(), 12u);
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const vec3 diagonal(glm::normalize(m.positions[m.triangles[t][k]]));
      EXPECT_NEAR(std::abs(glm::dot(m.normals[t][k], diagonal)), 1.0f, 1e-6f) << t;
      EXPECT_GT(glm::dot(m.normals[t][k], unit_face_normal(m, t)), 0.0f) << t;
    }
}

TEST(MeshClean, OrientSplitsNonManifoldEdge) {
  // orient_polygon_soup duplicates vertices here; smooth normals work on the result as on the input.
  CleanReport r;
  TriangleMesh m = clean_mesh(three_fins(), {.orient = true, .smooth_normals = true}, r);
  ASSERT_EQ(m.triangles.size(), 3u);
  EXPECT_GT(m.positions.size(), 5u);
  EXPECT_FALSE(r.closed);
  ASSERT_EQ(m.normals.size(), m.triangles.size());
  for (const auto& corners : m.normals)
    for (const vec3& n : corners) EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
}

// A closed surface folded flat into the plane y = 0: the square (0,0)-(2,2) in x, z covered on one side
// by two triangles and on the other by a fan around its centre.
PolygonSoup folded_square() {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {2, 0, 0}, {2, 0, 2}, {0, 0, 2}, {1, 0, 1}};
  s.polygons = {{0, 1, 2}, {0, 2, 3}, {4, 1, 0}, {4, 2, 1}, {4, 3, 2}, {4, 0, 3}};
  return s;
}

TEST(MeshClean, ZeroLengthNormalsStayZeroNeverNaN) {
  // The folded square lying in z = 0, consistently oriented as given. At each of its four corners the
  // faces of the two sides subtend the same angle (90 degrees), so at a crease angle of 180 (the fold is
  // not a crease) their angle-weighted normals cancel exactly: the normal stays zero (build_device_scene
  // then uses the face normal). At the default angle the fold is a crease and each side keeps its normal.
  PolygonSoup s = folded_square();
  for (dvec3& p : s.positions) p = dvec3(p.x, p.z, 0);
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {.smooth_normals = true, .smooth_angle_degrees = 180}, r);
  ASSERT_EQ(m.normals.size(), 6u);
  for (std::size_t t = 0; t < 6; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.triangles[t][k];
      if (v != 4)
        EXPECT_EQ(m.normals[t][k], vec3(0)) << t << " " << k;
      else
        EXPECT_NEAR(glm::length(m.normals[t][k]), 1.0f, 1e-6f) << t << " " << k;
    }
  m = clean_mesh(s, {.smooth_normals = true}, r);
  for (std::size_t t = 0; t < 6; ++t)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(glm::dot(m.normals[t][k], unit_face_normal(m, t)), 1.0f, 1e-6f);
}

// Two closed unit cubes overlapping in [0.5, 1]^3, in one soup: a self-intersecting closed mesh.
PolygonSoup overlapping_cubes(bool first_inward, bool second_inward) {
  PolygonSoup s = cube_quads(), b = cube_quads();
  if (first_inward)
    for (auto& p : s.polygons) std::reverse(p.begin(), p.end());
  for (auto& p : b.polygons) {
    if (second_inward) std::reverse(p.begin(), p.end());
    for (uint32_t& v : p) v += 8;
    s.polygons.push_back(p);
  }
  for (const dvec3& p : b.positions) s.positions.push_back(p + dvec3(0.5));
  return s;
}

TEST(MeshClean, OrientSelfIntersectingClosedMeshTurnsEachPartOutward) {
  for (int inward = 0; inward < 4; ++inward) {
    const bool first = inward & 1, second = inward & 2;
    CleanReport r;
    TriangleMesh m = clean_mesh(overlapping_cubes(first, second), {.orient = true}, r);
    ASSERT_EQ(m.triangles.size(), 24u);
    EXPECT_TRUE(r.closed);
    EXPECT_TRUE(r.self_intersecting);
    EXPECT_TRUE(consistently_oriented_closed(m));
    EXPECT_NEAR(signed_volume(m), 2.0, 1e-6) << inward;  // +1 for each cube: both outward
    EXPECT_EQ(r.faces_flipped, 12u * (first + second)) << inward;
  }
  // Without self-intersections CGAL's own orientation is used and nothing is reported.
  PolygonSoup apart = overlapping_cubes(true, true);
  for (std::size_t i = 8; i < 16; ++i) apart.positions[i] += dvec3(2);
  CleanReport r;
  TriangleMesh m = clean_mesh(apart, {.orient = true}, r);
  EXPECT_FALSE(r.self_intersecting);
  EXPECT_NEAR(signed_volume(m), 2.0, 1e-6);
}

TEST(MeshClean, OrientFoldedClosedMeshNeverTripsCgal) {
  // Every face is vertical, which trips CGAL's assertion "p1p2p3_2d!=COLLINEAR || p2p1p4_2d!=COLLINEAR
  // // no self-intersection" in orient_to_bound_a_volume (is_outward_oriented).
  CleanReport r;
  TriangleMesh m;
  ASSERT_NO_THROW(m = clean_mesh(folded_square(), {.orient = true, .smooth_normals = true}, r));
  ASSERT_EQ(m.triangles.size(), 6u);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.self_intersecting);
  EXPECT_TRUE(consistently_oriented_closed(m));
  EXPECT_EQ(r.faces_flipped, 0u);  // zero volume: no side is the outside, the winding stays
  ASSERT_EQ(m.normals.size(), m.triangles.size());
  for (const auto& corners : m.normals)
    for (const vec3& n : corners) {
      const float len = glm::length(n);
      EXPECT_TRUE(len == 0 || std::abs(len - 1) < 1e-6f) << len;  // never NaN
    }
}

TEST(MeshClean, OutOfRangeIndexThrows) {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  s.polygons = {{0, 1, 2}, {0, 1, 7}};
  CleanReport r;
  try {
    clean_mesh(s, {}, r);
    FAIL() << "expected SceneError";
  } catch (const SceneError& e) {
    EXPECT_STREQ(e.what(), "polygon 1: vertex index 7 out of range");
  }
}

TEST(MeshClean, EmptyAndFullyDegenerateInput) {
  CleanReport r;
  TriangleMesh m = clean_mesh(PolygonSoup{}, {.orient = true, .smooth_normals = true}, r);
  EXPECT_TRUE(m.triangles.empty());
  EXPECT_TRUE(m.positions.empty());
  EXPECT_FALSE(r.closed);

  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  s.polygons = {{0, 1, 2}, {0, 1}};
  m = clean_mesh(s, {.orient = true}, r);
  EXPECT_TRUE(m.triangles.empty());
  EXPECT_TRUE(m.positions.empty());
  EXPECT_EQ(r.degenerate_faces, 2u);
  EXPECT_EQ(r.removed_isolated_vertices, 3u);
}

// Per-corner attributes. Every corner gets a uv that names its position and its polygon, so that a uv
// that stayed with the wrong vertex, or came from another polygon, shows.
glm::vec2 uv_of(const glm::dvec3& p, std::size_t polygon) {
  return {float(p.x + 2 * p.z + 10.0 * polygon), float(p.y + 4 * p.z)};
}

void add_position_uvs(PolygonSoup& s) {
  s.uvs.clear();
  for (std::size_t p = 0; p < s.polygons.size(); ++p) {
    std::vector<glm::vec2> uvs;
    for (uint32_t v : s.polygons[p]) uvs.push_back(uv_of(s.positions[v], p));
    s.uvs.push_back(uvs);
  }
}

// Each triangle vertex carries the uv of its source corner, which is at the vertex's position.
void expect_uvs_follow_vertices(const PolygonSoup& s, const TriangleMesh& m) {
  ASSERT_EQ(m.uvs.size(), m.triangles.size());
  ASSERT_EQ(m.source_polygon.size(), m.triangles.size());
  ASSERT_EQ(m.source_corners.size(), m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const uint32_t p = m.source_polygon[t];
    ASSERT_LT(p, s.polygons.size());
    for (int j = 0; j < 3; ++j) {
      const glm::dvec3 at = m.positions[m.triangles[t][j]];
      ASSERT_LT(m.source_corners[t][j], s.polygons[p].size());
      EXPECT_EQ(s.positions[s.polygons[p][m.source_corners[t][j]]], at) << "triangle " << t << " vertex " << j;
      EXPECT_EQ(m.uvs[t][j], uv_of(at, p)) << "triangle " << t << " vertex " << j;
    }
  }
}

TEST(MeshCleanAttributes, UvsFollowTriangulatedQuad) {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  s.polygons = {{0, 1, 2, 3}};
  add_position_uvs(s);
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(r.polygons_triangulated, 1u);
  expect_uvs_follow_vertices(s, m);
  for (uint32_t p : m.source_polygon) EXPECT_EQ(p, 0u);
}

TEST(MeshCleanAttributes, UvsFollowTriangulatedNonConvexPolygonFromEveryStart) {
  for (uint32_t start = 0; start < 6; ++start) {
    PolygonSoup s = l_shape();
    std::rotate(s.polygons[0].begin(), s.polygons[0].begin() + start, s.polygons[0].end());
    add_position_uvs(s);
    CleanReport r;
    TriangleMesh m = clean_mesh(s, {}, r);
    ASSERT_EQ(m.triangles.size(), 4u) << "start " << start;
    expect_uvs_follow_vertices(s, m);
  }
}

TEST(MeshCleanAttributes, RepeatedCornersKeepTheFirstCornersUv) {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  s.polygons = {{0, 0, 1, 2, 0}};  // corners 1 and 4 repeat corner 0
  s.uvs = {{{0.5f, 0.5f}, {9, 9}, {1, 0}, {0, 1}, {8, 8}}};
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.source_corners[0], (std::array<uint32_t, 3>{0, 2, 3}));
  EXPECT_EQ(m.uvs[0][0], glm::vec2(0.5f, 0.5f));
  EXPECT_EQ(m.uvs[0][1], glm::vec2(1, 0));
  EXPECT_EQ(m.uvs[0][2], glm::vec2(0, 1));
}

TEST(MeshCleanAttributes, MergedVerticesKeepTheirCornersUvs) {
  // Two triangles of a square with separate vertices on their shared edge and different uvs there (a
  // texture seam): the positions merge, the uvs stay with their corners.
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  s.polygons = {{0, 1, 2}, {3, 4, 5}};
  add_position_uvs(s);
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  EXPECT_EQ(r.merged_vertices, 2u);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[0][0], m.triangles[1][0]);  // (0, 0, 0) is one vertex now
  EXPECT_NE(m.uvs[0][0], m.uvs[1][0]);             // with two uvs
  expect_uvs_follow_vertices(s, m);
}

TEST(MeshCleanAttributes, UvsFollowFacesThatOrientFlips) {
  PolygonSoup s = cube_quads();
  std::reverse(s.polygons[3].begin(), s.polygons[3].end());
  add_position_uvs(s);
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {.orient = true}, r);
  ASSERT_EQ(m.triangles.size(), 12u);
  EXPECT_EQ(r.faces_flipped, 2u);
  expect_uvs_follow_vertices(s, m);
  // The flipped triangles (of the y = 1 quad) list their corners in an order the quad did not.
  for (int t : {6, 7}) {
    EXPECT_EQ(m.source_polygon[t], 3u);
    EXPECT_GT(tri_normal(m, m.triangles[t]).y, 0.0);
  }

  PolygonSoup inside_out = cube_quads();
  for (auto& p : inside_out.polygons) std::reverse(p.begin(), p.end());
  add_position_uvs(inside_out);
  m = clean_mesh(inside_out, {.orient = true, .smooth_normals = true}, r);
  EXPECT_EQ(r.faces_flipped, 12u);
  expect_uvs_follow_vertices(inside_out, m);
}

TEST(MeshCleanAttributes, UvsFollowVerticesThatOrientDuplicates) {
  PolygonSoup s = three_fins();
  add_position_uvs(s);
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {.orient = true}, r);
  ASSERT_EQ(m.triangles.size(), 3u);
  EXPECT_GT(m.positions.size(), 5u);
  expect_uvs_follow_vertices(s, m);
}

// Every corner gets a normal (not unit: clean_mesh normalizes) that names its position and its polygon.
vec3 normal_of(const glm::dvec3& p, std::size_t polygon) {
  return {float(1 + p.x + 2 * p.z), float(3 + polygon), float(p.y - 2)};
}

void add_position_normals(PolygonSoup& s) {
  s.normals.clear();
  for (std::size_t p = 0; p < s.polygons.size(); ++p) {
    std::vector<vec3> normals;
    for (uint32_t v : s.polygons[p]) normals.push_back(normal_of(s.positions[v], p));
    s.normals.push_back(normals);
  }
}

void expect_normals_follow_vertices(const TriangleMesh& m) {
  ASSERT_EQ(m.normals.size(), m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int j = 0; j < 3; ++j) {
      const vec3 expected = glm::normalize(normal_of(m.positions[m.triangles[t][j]], m.source_polygon[t]));
      EXPECT_NEAR(glm::distance(m.normals[t][j], expected), 0.0f, 1e-6f) << "triangle " << t << " vertex " << j;
    }
}

TEST(MeshCleanAttributes, NormalsFollowTheirCornersThroughEveryStep) {
  // Triangulation, merging, orienting (flipping one side, and all sides of an inside-out cube), and
  // duplicating vertices at a non-manifold edge; smooth normals do not replace the soup's.
  PolygonSoup s = cube_quads();
  std::reverse(s.polygons[3].begin(), s.polygons[3].end());
  s.positions.push_back(s.positions[0]);  // a duplicate that merges
  s.polygons[0][0] = uint32_t(s.positions.size() - 1);
  add_position_normals(s);
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {.orient = true, .smooth_normals = true}, r);
  EXPECT_EQ(r.faces_flipped, 2u);
  EXPECT_EQ(r.merged_vertices, 1u);
  expect_normals_follow_vertices(m);

  PolygonSoup inside_out = cube_quads();
  for (auto& p : inside_out.polygons) std::reverse(p.begin(), p.end());
  add_position_normals(inside_out);
  m = clean_mesh(inside_out, {.orient = true}, r);
  EXPECT_EQ(r.faces_flipped, 12u);
  expect_normals_follow_vertices(m);

  PolygonSoup fins = three_fins();
  add_position_normals(fins);
  m = clean_mesh(fins, {.orient = true}, r);
  EXPECT_GT(m.positions.size(), 5u);
  expect_normals_follow_vertices(m);
}

TEST(MeshCleanAttributes, PolygonsWithoutNormalsAreFlatOrSmoothedAndMismatchesThrow) {
  // Two triangles of a flat square: the first has file normals (one of them zero), the second none.
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  s.polygons = {{0, 1, 2}, {0, 2, 3}};
  s.normals = {{{0, 0, 2}, {0, 0, 0}, {1, 0, 1}}, {}};
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  ASSERT_EQ(m.normals.size(), 2u);
  EXPECT_EQ(m.normals[0][0], vec3(0, 0, 1));
  EXPECT_EQ(m.normals[0][1], vec3(0));  // the face normal, on the device
  EXPECT_NEAR(m.normals[0][2].x, std::sqrt(0.5f), 1e-6f);
  for (const vec3& n : m.normals[1]) EXPECT_EQ(n, vec3(0));  // flat
  m = clean_mesh(s, {.smooth_normals = true}, r);
  EXPECT_EQ(m.normals[0][1], vec3(0));  // the file's zero stays
  for (const vec3& n : m.normals[1]) EXPECT_EQ(n, vec3(0, 0, 1));  // generated

  PolygonSoup bad = s;
  bad.normals[0].pop_back();
  EXPECT_THROW(clean_mesh(bad, {}, r), SceneError);
  bad = s;
  bad.normals.pop_back();
  EXPECT_THROW(clean_mesh(bad, {}, r), SceneError);
  bad = s;
  bad.normals[0][0].x = NAN;
  EXPECT_THROW(clean_mesh(bad, {}, r), SceneError);
}

TEST(MeshCleanAttributes, MaterialsFollowSurvivingFaces) {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {2, 0, 0},
                 {0, 0, 5}, {1, 0, 5}, {1, 1, 5}, {0, 1, 5}};
  s.polygons = {{0, 1, 4},      // collinear: removed
                {0, 2, 1},      // kept
                {1, 2, 0},      // duplicate of the previous: removed
                {5, 6, 7, 8},   // quad: two triangles
                {0, 1, 3}};     // kept
  s.materials = {10, 11, 12, 13, 14};
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  EXPECT_TRUE(m.uvs.empty());
  EXPECT_EQ(m.source_polygon, (std::vector<uint32_t>{1, 3, 3, 4}));
  EXPECT_EQ(m.materials, (std::vector<uint32_t>{11, 13, 13, 14}));
}

TEST(MeshCleanAttributes, PolygonsWithoutUvsGetZeroAndMismatchesThrow) {
  PolygonSoup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  s.polygons = {{0, 1, 2}, {0, 1, 3}};
  s.uvs = {{}, {{0.1f, 0.2f}, {0.3f, 0.4f}, {0.5f, 0.6f}}};
  CleanReport r;
  TriangleMesh m = clean_mesh(s, {}, r);
  ASSERT_EQ(m.uvs.size(), 2u);
  EXPECT_EQ(m.uvs[0][1], glm::vec2(0));
  EXPECT_EQ(m.uvs[1][2], glm::vec2(0.5f, 0.6f));

  PolygonSoup bad = s;
  bad.uvs[1].pop_back();
  EXPECT_THROW(clean_mesh(bad, {}, r), SceneError);
  bad = s;
  bad.uvs.pop_back();
  EXPECT_THROW(clean_mesh(bad, {}, r), SceneError);
  bad = s;
  bad.materials = {1};
  EXPECT_THROW(clean_mesh(bad, {}, r), SceneError);
}

}  // namespace
