// Mesh clean-up with CGAL Polygon Mesh Processing: polygon soup in, indexed triangle mesh out.
//
// Pipeline (each step counted into CleanReport):
//   soup -> merge duplicate points -> drop polygons with < 3 distinct vertices -> triangulate polygons
//   -> drop collinear triangles -> drop duplicate faces -> drop isolated points
//   -> [orient: orient_polygon_soup, outward if closed] -> [smooth normals: scene/mesh_normals.cpp]
//
// CGAL's preconditions and assertions are off in release builds (NDEBUG), where a violated one is
// undefined behaviour; where they are on (debug builds and scripts/sanitize's, which the fuzzers and
// tests/mesh_clean_test there link) a violation
// throws CGAL::Failure_exception. Both are avoided by checking the preconditions we know of first (see
// the orientation step), and any CGAL failure that still happens becomes a SceneError.
//
// Merging duplicate points and duplicate faces are CGAL's merge_duplicate_points_in_polygon_soup and
// merge_duplicate_polygons_in_polygon_soup (CGAL 5.5) done by parallel sorts instead of CGAL's std::map and
// hash set, with the same result: the first occurrence of a point or of a face's vertex set is kept. They
// were a third of the clean-up's time on a million triangles. Every parallel step gives the same bits for
// any number of threads (tests/parallel_build_test.cpp): sorts are by total orders (ties broken by index),
// and no floating-point sum depends on the split.
//
// Two orders matter to the renderer and CGAL does not keep them by itself:
//   * triangle order (the renderer reports primitive indices): duplicate faces are removed in place,
//     keeping the order of the survivors;
//   * vertex order (kept as the input's, after merging): remove_isolated_points_in_polygon_soup fills
//     the holes with points from the back, so we run it on a range of original vertex ids instead of
//     the points themselves, and put the ids back in ascending order afterwards.
//
// Per-corner attributes (uvs, normals) follow each triangle through a Source record: its polygon and, per
// triangle vertex, the polygon corner. Removing repeated corners and triangulating carry the corner
// ids along; the duplicate-face step uses the same order tags; orienting may reverse, rotate or
// re-point a triangle at a duplicated vertex, so afterwards each vertex is matched to its corner by
// position (a surviving triangle is not collinear, so its three positions are distinct).
#include "scene/mesh_clean.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Projection_traits_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/assertions.h>
#include <CGAL/boost/graph/helpers.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "scene/mesh_normals.h"
#include "scene/scene_error.h"

namespace {

namespace PMP = CGAL::Polygon_mesh_processing;

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using Mesh = CGAL::Surface_mesh<Point>;
using Polygon = std::vector<std::size_t>;

// Merges points at the same coordinates (-0 and +0 alike, as CGAL's lexicographic order has them) into
// the first of them, numbers the points left in their input order and renumbers the polygons; returns how
// many points were merged away. CGAL's merge_duplicate_points_in_polygon_soup does the same with a
// std::map; a parallel sort by (point, index) finds each point's first occurrence faster.
std::size_t merge_duplicate_points(std::vector<Point>& points, std::vector<Polygon>& polygons) {
  const std::size_t n = points.size();
  std::vector<std::size_t> sorted(n);
  for (std::size_t i = 0; i < n; ++i) sorted[i] = i;
  tbb::parallel_sort(sorted.begin(), sorted.end(), [&](std::size_t a, std::size_t b) {
    const Point &p = points[a], &q = points[b];
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return a < b;
  });
  std::vector<std::size_t> first(n);  // per point: the first point at its coordinates
  for (std::size_t k = 0; k < n;) {
    std::size_t end = k + 1;
    while (end < n && points[sorted[end]] == points[sorted[k]]) ++end;
    for (std::size_t j = k; j < end; ++j) first[sorted[j]] = sorted[k];
    k = end;
  }
  std::vector<std::size_t> id(n);
  std::vector<Point> unique;
  unique.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (first[i] == i) {
      id[i] = unique.size();
      unique.push_back(points[i]);
    } else {
      id[i] = id[first[i]];  // first[i] < i
    }
  }
  if (unique.size() == n) return 0;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, polygons.size()), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t p = r.begin(); p < r.end(); ++p)
      for (std::size_t& v : polygons[p]) v = id[v];
  });
  points = std::move(unique);
  return n - points.size();
}

// Marks each triangle with the same vertex set (in either orientation) as an earlier one: what CGAL's
// merge_duplicate_polygons_in_polygon_soup (erase_all_duplicates and require_same_orientation false)
// removes, by a parallel sort instead of its hash set. Needs merged points (the same point, the same
// index) and triangles of three distinct vertices. Returns the number marked.
std::size_t mark_duplicate_triangles(const std::vector<std::array<std::size_t, 3>>& triangles,
                                     std::vector<char>& duplicate) {
  const std::size_t n = triangles.size();
  std::vector<std::array<std::size_t, 3>> key(n);
  std::vector<std::size_t> sorted(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t < r.end(); ++t) {
      key[t] = triangles[t];
      std::sort(key[t].begin(), key[t].end());
      sorted[t] = t;
    }
  });
  tbb::parallel_sort(sorted.begin(), sorted.end(),
                     [&](std::size_t a, std::size_t b) { return key[a] != key[b] ? key[a] < key[b] : a < b; });
  duplicate.assign(n, 0);
  std::size_t count = 0;
  for (std::size_t k = 1; k < n; ++k)
    if (key[sorted[k]] == key[sorted[k - 1]]) duplicate[sorted[k]] = 1, ++count;
  return count;
}

// Newell normal of a polygon (not normalized): robust for non-convex and slightly non-planar polygons.
Vector newell_normal(const std::vector<Point>& pts) {
  double x = 0, y = 0, z = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Point& a = pts[i];
    const Point& b = pts[(i + 1) % pts.size()];
    x += (a.y() - b.y()) * (a.z() + b.z());
    y += (a.z() - b.z()) * (a.x() + b.x());
    z += (a.x() - b.x()) * (a.y() + b.y());
  }
  return Vector(x, y, z);
}

// Where a triangle came from: its polygon in the soup and, per triangle vertex, the polygon's corner.
struct Source {
  std::size_t polygon = 0;
  std::array<std::size_t, 3> corners{};
};

// Removes consecutive repeats (cyclically), keeping the first corner of each run, and the same entries
// of `corners`: {a, a, b, c, a} -> {a, b, c}.
void remove_consecutive_duplicates(Polygon& polygon, std::vector<std::size_t>& corners) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < polygon.size(); ++i)
    if (n == 0 || polygon[i] != polygon[n - 1]) {
      polygon[n] = polygon[i];
      corners[n] = corners[i];
      ++n;
    }
  polygon.resize(n);
  corners.resize(n);
  while (polygon.size() > 1 && polygon.front() == polygon.back()) {
    polygon.pop_back();
    corners.pop_back();
  }
}

std::size_t distinct_count(Polygon polygon) {
  std::sort(polygon.begin(), polygon.end());
  return static_cast<std::size_t>(std::unique(polygon.begin(), polygon.end()) - polygon.begin());
}

// Whether CGAL 5.5's 2D path of triangulate_hole_polyline (triangulate_hole_polyline_with_cdt) may be
// used on the polygon `pts`. That path projects the polygon along an average normal into a constrained
// Delaunay triangulation; when two vertices project onto the same point (a non-planar polygon that still
// passes its planarity and simplicity checks), the triangulation keeps one of them and CGAL then calls
// insert_constraint with a null vertex handle (found by fuzz/fuzz_obj_clean). This repeats CGAL's normal
// computation and its point equality (Triangulation_2::xy_equal under Projection_traits_3) and says no
// when two vertices would coincide.
bool cdt_keeps_vertices_apart(const std::vector<Point>& pts) {
  double x = 0, y = 0, z = 0;
  int normals = 0;
  for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
    if (CGAL::collinear(pts[0], pts[i], pts[i + 1])) continue;
    const Vector n = CGAL::normal(pts[0], pts[i], pts[i + 1]);
    if (n.x() > 0 || (n.x() == 0 && n.y() > 0) || (n.x() == 0 && n.y() == 0 && n.z() > 0)) {
      x += n.x(), y += n.y(), z += n.z();
    } else {
      x -= n.x(), y -= n.y(), z -= n.z();
    }
    ++normals;
  }
  if (normals == 0) return true;  // CGAL skips the 2D path by itself
  const Vector average(x / normals, y / normals, z / normals);
  if (average == CGAL::NULL_VECTOR) return true;  // idem
  const CGAL::Projection_traits_3<Kernel> traits(average);
  const auto compare_x = traits.compare_x_2_object();
  const auto compare_y = traits.compare_y_2_object();
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (std::size_t j = i + 1; j < pts.size(); ++j)
      if (compare_x(pts[i], pts[j]) == CGAL::EQUAL && compare_y(pts[i], pts[j]) == CGAL::EQUAL) return false;
  return true;
}

// Splits a polygon with more than 3 vertices into triangles, keeping the polygon's winding. Appends them
// to `out` as positions in `polygon` (not vertex indices) and returns how many were added.
std::size_t triangulate_polygon(const std::vector<Point>& points, const Polygon& polygon,
                                std::vector<std::array<std::size_t, 3>>& out) {
  std::vector<Point> pts;
  pts.reserve(polygon.size());
  for (std::size_t v : polygon) pts.push_back(points[v]);

  // The 2D constrained Delaunay path handles (near) planar simple polygons, convex or not, exactly as
  // the polygon's inside; CGAL falls back to its 3D search (min max dihedral angle) for the others.
  // (CGAL 5.5's documentation says this parameter defaults to true, but the code defaults to false.)
  std::vector<CGAL::Triple<int, int, int>> patch;
  PMP::triangulate_hole_polyline(
      pts, std::back_inserter(patch),
      CGAL::parameters::use_2d_constrained_delaunay_triangulation(cdt_keeps_vertices_apart(pts)));

  std::vector<std::array<std::size_t, 3>> tris;
  if (patch.empty()) {
    // CGAL found no triangulation: fall back to a fan, degenerate pieces are removed later.
    for (std::size_t i = 1; i + 1 < polygon.size(); ++i) tris.push_back({0, i, i + 1});
  } else {
    for (const auto& t : patch)
      tris.push_back({static_cast<std::size_t>(t.first), static_cast<std::size_t>(t.second),
                      static_cast<std::size_t>(t.third)});
  }

  // Whatever orientation the hole filler (or the fan on a non-convex polygon) gives, orient every
  // triangle like the polygon; a zero Newell normal (e.g. a figure eight) gives no preference.
  const Vector n = newell_normal(pts);
  for (auto& t : tris) {
    const Vector tn = CGAL::cross_product(pts[t[1]] - pts[t[0]], pts[t[2]] - pts[t[0]]);
    if (tn * n < 0) std::swap(t[1], t[2]);
    out.push_back(t);
  }
  return tris.size();
}

// True if `b` is `a` with the same cyclic vertex order (compared by position, because orienting may
// have replaced a vertex by a duplicate at the same place).
bool same_winding(const std::array<Point, 3>& a, const std::array<Point, 3>& b) {
  for (int r = 0; r < 3; ++r)
    if (a[0] == b[r] && a[1] == b[(r + 1) % 3] && a[2] == b[(r + 2) % 3]) return true;
  return false;
}

// The corners of `before` (a triangle with corners `corners`) at the vertices of `after`, the same
// triangle possibly reversed, rotated or moved to duplicated points, matched by position.
std::array<std::size_t, 3> follow_corners(const std::vector<Point>& points, const Polygon& before,
                                          const std::array<std::size_t, 3>& corners, const Polygon& after) {
  std::array<std::size_t, 3> result{};
  for (std::size_t j = 0; j < 3; ++j) {
    std::size_t k = 0;
    while (k < 3 && points[before[k]] != points[after[j]]) ++k;
    if (k == 3) throw std::logic_error("clean_mesh: orienting moved a triangle vertex");
    result[j] = corners[k];
  }
  return result;
}

// Whether every undirected edge is used by exactly two triangles: the sorted list of edges has runs of two.
bool is_closed_soup(const std::vector<Polygon>& triangles) {
  // An edge as one 64-bit key (the output's vertex indices are 32-bit): half the memory of a pair.
  std::vector<uint64_t> edges(3 * triangles.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles.size()), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t < r.end(); ++t)
      for (std::size_t i = 0; i < 3; ++i) {
        const uint64_t a = triangles[t][i], b = triangles[t][(i + 1) % 3];
        edges[3 * t + i] = std::min(a, b) << 32 | std::max(a, b);
      }
  });
  tbb::parallel_sort(edges.begin(), edges.end());
  for (std::size_t k = 0; k < edges.size(); k += 2)
    if (k + 1 == edges.size() || edges[k + 1] != edges[k] || (k + 2 < edges.size() && edges[k + 2] == edges[k]))
      return false;
  return true;
}

// Turns every connected part of a closed mesh so that its signed volume is positive (outward), leaving
// parts of zero volume (flat or folded) as they are. Unlike orient_to_bound_a_volume this needs no
// freedom from self-intersections: the signed volume of a closed surface is the integral of its winding
// number, positive for outward overlapping boxes as for a single one.
void orient_parts_by_signed_volume(Mesh& mesh) {
  auto part = mesh.add_property_map<Mesh::Face_index, std::size_t>("f:part", 0).first;
  const std::size_t parts = PMP::connected_components(mesh, part);
  // Six times the volume, with each part's first vertex as the apex: far from the origin, apexes at
  // the origin would sum huge terms that cancel.
  std::vector<double> volume(parts, 0.0);
  std::vector<Point> apex(parts);
  std::vector<bool> has_apex(parts, false);
  for (Mesh::Face_index f : mesh.faces()) {
    const std::size_t k = part[f];
    const Mesh::Halfedge_index h = mesh.halfedge(f);
    const Point& a = mesh.point(mesh.target(h));
    const Point& b = mesh.point(mesh.target(mesh.next(h)));
    const Point& c = mesh.point(mesh.target(mesh.next(mesh.next(h))));
    if (!has_apex[k]) apex[k] = a, has_apex[k] = true;
    volume[k] += CGAL::scalar_product(a - apex[k], CGAL::cross_product(b - apex[k], c - apex[k]));
  }
  std::vector<Mesh::Face_index> flip;
  for (Mesh::Face_index f : mesh.faces())
    if (volume[part[f]] < 0) flip.push_back(f);
  PMP::reverse_face_orientations(flip, mesh);
  mesh.remove_property_map(part);
}

// Checks per-corner attributes laid out as PolygonSoup's uvs and normals: none, or per polygon one per
// corner or nothing, all finite.
template <class Vec>
void check_corner_attributes(const PolygonSoup& soup, const std::vector<std::vector<Vec>>& values, const char* plural,
                             const char* singular) {
  if (values.empty()) return;
  if (values.size() != soup.polygons.size())
    throw SceneError(std::to_string(values.size()) + " polygons with " + plural + " for " +
                     std::to_string(soup.polygons.size()) + " polygons");
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!values[i].empty() && values[i].size() != soup.polygons[i].size())
      throw SceneError("polygon " + std::to_string(i) + ": " + std::to_string(values[i].size()) + " " + plural +
                       " for " + std::to_string(soup.polygons[i].size()) + " corners");
    for (const Vec& value : values[i])
      for (int c = 0; c < Vec::length(); ++c)
        if (!std::isfinite(value[c])) throw SceneError("polygon " + std::to_string(i) + ": " + singular + " is not finite");
  }
}

TriangleMesh clean_soup(const PolygonSoup& soup, const CleanOptions& options, CleanReport& report) {
  report = CleanReport{};
  report.input_vertices = soup.positions.size();
  report.input_polygons = soup.polygons.size();

  // 1. CGAL polygon soup, in the soup's double coordinates (they come back unchanged).
  std::vector<Point> points;
  points.reserve(soup.positions.size());
  for (std::size_t i = 0; i < soup.positions.size(); ++i) {
    const glm::dvec3& p = soup.positions[i];
    // NaN would break the lexicographic order CGAL merges points with.
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw SceneError("vertex " + std::to_string(i) + ": coordinate is not finite");
    points.emplace_back(p.x, p.y, p.z);
  }
  std::vector<Polygon> polygons;
  polygons.reserve(soup.polygons.size());
  for (std::size_t i = 0; i < soup.polygons.size(); ++i) {
    for (uint32_t v : soup.polygons[i])
      if (v >= points.size())
        throw SceneError("polygon " + std::to_string(i) + ": vertex index " + std::to_string(v) +
                         " out of range");
    polygons.emplace_back(soup.polygons[i].begin(), soup.polygons[i].end());
  }
  check_corner_attributes(soup, soup.uvs, "texture coordinates", "texture coordinate");
  check_corner_attributes(soup, soup.normals, "normals", "normal");
  check_corner_attributes(soup, soup.colors, "colours", "colour");
  if (!soup.materials.empty() && soup.materials.size() != soup.polygons.size())
    throw SceneError(std::to_string(soup.materials.size()) + " material ids for " +
                     std::to_string(soup.polygons.size()) + " polygons");

  // 2. Merge duplicate points (keeps the first occurrence, in input order). Polygons left with fewer
  // than 3 distinct vertices are dropped in the loop below.
  report.merged_vertices = merge_duplicate_points(points, polygons);

  // 3. Triangulate, keeping the polygon order: a polygon's triangles replace it in place.
  std::vector<std::array<std::size_t, 3>> triangles;
  std::vector<Source> sources;  // per entry of triangles
  triangles.reserve(polygons.size());
  std::vector<std::array<std::size_t, 3>> pieces;
  for (std::size_t p = 0; p < polygons.size(); ++p) {
    Polygon& polygon = polygons[p];
    std::vector<std::size_t> corners(polygon.size());
    for (std::size_t k = 0; k < corners.size(); ++k) corners[k] = k;
    remove_consecutive_duplicates(polygon, corners);
    if (distinct_count(polygon) < 3) {
      ++report.degenerate_faces;
      continue;
    }
    pieces.clear();
    if (polygon.size() == 3) {
      pieces.push_back({0, 1, 2});
    } else {
      ++report.polygons_triangulated;
      report.triangles_from_polygons += triangulate_polygon(points, polygon, pieces);
    }
    for (const auto& t : pieces) {
      triangles.push_back({polygon[t[0]], polygon[t[1]], polygon[t[2]]});
      sources.push_back({p, {corners[t[0]], corners[t[1]], corners[t[2]]}});
    }
  }

  polygons = {};  // one allocation per polygon: freed early (see below)

  // 4. Degenerate triangles: exact collinearity test on the coordinates as given (also catches a
  // repeated vertex).
  std::vector<std::array<std::size_t, 3>> kept;
  std::vector<Source> kept_sources;
  kept.reserve(triangles.size());
  kept_sources.reserve(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const auto& t = triangles[i];
    if (CGAL::collinear(points[t[0]], points[t[1]], points[t[2]])) {
      ++report.degenerate_faces;
      continue;
    }
    kept.push_back(t);
    kept_sources.push_back(sources[i]);
  }
  // Freed as soon as they are dead, here, above and below: on a million triangles each of these arrays is
  // tens of megabytes, and the peak memory of loading is reached in the clean-up.
  triangles = {};
  sources = {};

  // 5. Duplicate faces, in either orientation: the first of each group stays.
  std::vector<char> duplicate;
  report.duplicate_faces = mark_duplicate_triangles(kept, duplicate);
  std::vector<Polygon> tris;
  tris.reserve(kept.size() - report.duplicate_faces);
  sources.reserve(kept.size() - report.duplicate_faces);
  for (std::size_t i = 0; i < kept.size(); ++i) {
    if (duplicate[i]) continue;
    tris.push_back({kept[i][0], kept[i][1], kept[i][2]});
    sources.push_back(kept_sources[i]);
  }
  kept = {};
  kept_sources = {};
  duplicate = {};

  // 6. Isolated points. Run on the vertex ids rather than the points: CGAL only moves the range's
  // elements around and renumbers the polygons, so afterwards ids[k] is the old index of new vertex k.
  std::vector<std::size_t> ids(points.size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = i;
  report.removed_isolated_vertices = PMP::remove_isolated_points_in_polygon_soup(ids, tris);
  {
    // Put the kept vertices back in their original (merged) order.
    std::vector<std::size_t> by_old(ids.size());  // new slot -> rank of its old index
    std::vector<std::size_t> slots(ids.size());
    for (std::size_t k = 0; k < slots.size(); ++k) slots[k] = k;
    std::sort(slots.begin(), slots.end(), [&](std::size_t a, std::size_t b) { return ids[a] < ids[b]; });
    std::vector<Point> kept(ids.size());
    for (std::size_t rank = 0; rank < slots.size(); ++rank) {
      by_old[slots[rank]] = rank;
      kept[rank] = points[ids[slots[rank]]];
    }
    for (Polygon& t : tris)
      for (std::size_t& v : t) v = by_old[v];
    points = std::move(kept);
  }

  // 8. Orientation.
  const std::vector<Polygon> before_orient = options.orient ? tris : std::vector<Polygon>{};
  if (options.orient && !tris.empty()) {
    // Makes neighbouring faces agree; may append duplicates of non-manifold points (fine for us).
    // Polygons keep their place in the list, only their index order may be reversed.
    PMP::orient_polygon_soup(points, tris);
  }

  if (options.orient && !tris.empty() && PMP::is_polygon_soup_a_polygon_mesh(tris)) {
    // polygon_soup_to_polygon_mesh adds vertex i for point i and face j for polygon j, in order, so
    // the Surface_mesh indices are the soup's indices.
    Mesh mesh;
    PMP::polygon_soup_to_polygon_mesh(points, tris, mesh);
    if (CGAL::is_closed(mesh)) {
      // orient_to_bound_a_volume requires a mesh without self-intersections: on a folded one CGAL's
      // is_outward_oriented trips an assertion (or, with assertions off, decides at random).
      report.self_intersecting = PMP::does_self_intersect(mesh);
      if (report.self_intersecting)
        orient_parts_by_signed_volume(mesh);
      else
        PMP::orient_to_bound_a_volume(mesh);  // outward normals; reverses faces in place
      for (Mesh::Face_index f : mesh.faces()) {
        Polygon& t = tris[f.idx()];
        t.clear();
        for (Mesh::Vertex_index v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) t.push_back(v.idx());
      }
    }
  }

  if (options.orient) {
    for (std::size_t i = 0; i < tris.size(); ++i) {
      const Polygon& a = before_orient[i];
      const Polygon& b = tris[i];
      if (!same_winding({points[a[0]], points[a[1]], points[a[2]]}, {points[b[0]], points[b[1]], points[b[2]]}))
        ++report.faces_flipped;
      sources[i].corners = follow_corners(points, a, sources[i].corners, b);
    }
  }

  // 7. Closed: every undirected edge used by exactly two triangles, measured on the final output.
  report.closed = !tris.empty() && is_closed_soup(tris);

  TriangleMesh result;
  result.positions.reserve(points.size());
  for (const Point& p : points) result.positions.emplace_back(p.x(), p.y(), p.z());
  result.triangles.reserve(tris.size());
  for (const Polygon& t : tris)
    result.triangles.push_back({static_cast<uint32_t>(t[0]), static_cast<uint32_t>(t[1]), static_cast<uint32_t>(t[2])});
  for (const Source& s : sources) {
    result.source_polygon.push_back(static_cast<uint32_t>(s.polygon));
    result.source_corners.push_back(
        {static_cast<uint32_t>(s.corners[0]), static_cast<uint32_t>(s.corners[1]), static_cast<uint32_t>(s.corners[2])});
    if (!soup.uvs.empty()) {
      const std::vector<glm::vec2>& uvs = soup.uvs[s.polygon];
      std::array<glm::vec2, 3> corner_uvs{};
      if (!uvs.empty())
        for (int k = 0; k < 3; ++k) corner_uvs[k] = uvs[s.corners[k]];
      result.uvs.push_back(corner_uvs);
    }
    if (!soup.colors.empty()) {
      const std::vector<glm::vec3>& colors = soup.colors[s.polygon];
      std::array<glm::vec3, 3> corner_colors{glm::vec3(1), glm::vec3(1), glm::vec3(1)};
      if (!colors.empty())
        for (int k = 0; k < 3; ++k) corner_colors[k] = colors[s.corners[k]];
      result.colors.push_back(corner_colors);
    }
    if (!soup.materials.empty()) result.materials.push_back(soup.materials[s.polygon]);
  }

  // 9. Shading normals: the soup's where its polygon has them (normalized; zero stays zero, the face
  // normal), generated (with smooth normals) for the triangles of the other polygons.
  if (!soup.normals.empty() || options.smooth_normals) {
    result.normals.assign(result.triangles.size(), {});
    std::vector<bool> generate(result.triangles.size(), options.smooth_normals);
    for (std::size_t t = 0; t < sources.size(); ++t) {
      const Source& s = sources[t];
      if (soup.normals.empty() || soup.normals[s.polygon].empty()) continue;
      generate[t] = false;
      for (int k = 0; k < 3; ++k) {
        // In double: the squared length of a float normal of 1e20 would overflow float.
        const glm::dvec3 n(soup.normals[s.polygon][s.corners[k]]);
        const double length = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
        result.normals[t][k] = length > 0 ? glm::vec3(n / length) : glm::vec3(0);
      }
    }
    if (options.smooth_normals)
      generate_smooth_normals(result.positions, result.triangles, options.smooth_angle_degrees, generate,
                              result.normals);
  }
  return result;
}

}  // namespace

TriangleMesh clean_mesh(const PolygonSoup& soup, const CleanOptions& options, CleanReport& report) {
  try {
    return clean_soup(soup, options, report);
  } catch (const CGAL::Failure_exception& e) {
    // Only where CGAL's checks are compiled in; a violated precondition is a property of the input.
    const std::string file = e.filename();
    throw SceneError("CGAL cannot process this mesh: " + e.expression() + " (" +
                     file.substr(file.find_last_of('/') + 1) + ":" + std::to_string(e.line_number()) + ")");
  }
}
