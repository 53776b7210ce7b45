// Mesh clean-up with CGAL Polygon Mesh Processing. CGAL stays inside mesh_clean.cpp; this header only
// speaks in our own plain types.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

// Polygons of any size (>= 1 index each, not validated yet) over a shared vertex list, with optional
// attributes that belong to polygons and their corners rather than to vertices (an OBJ vertex may have
// different texture coordinates in the faces around it, e.g. on a seam). Positions are world
// coordinates in double: far from the origin, float would already have moved them (at 1e6 its spacing
// is 0.0625); they become float only relative to the camera (scene/device_scene_build.cpp).
struct PolygonSoup {
  std::vector<glm::dvec3> positions;
  std::vector<std::vector<uint32_t>> polygons;
  // Texture coordinates: empty (none at all), or one entry per polygon holding either one uv per corner
  // of that polygon or nothing (that polygon has none).
  std::vector<std::vector<glm::vec2>> uvs;
  // Shading normals from the file (OBJ vn, PLY/OFF vertex normals), laid out like uvs: empty, or per
  // polygon one normal per corner or nothing. A zero normal is a corner without one (it takes the face
  // normal); they need not be unit length (they are normalized after the transform).
  std::vector<std::vector<glm::vec3>> normals;
  // Vertex colours (PLY red/green/blue, glTF COLOR_0, OBJ "v x y z r g b"), linear RGB in [0, 1], laid out
  // like uvs: empty, or per polygon one colour per corner or nothing (that polygon is white). They
  // multiply the material's colour.
  std::vector<std::vector<glm::vec3>> colors;
  // Material ids in the caller's numbering: empty, or one per polygon.
  std::vector<uint32_t> materials;
};

// Faces whose normals differ by more than this are not smoothed across (the shape option
// smooth_angle_degrees): a cube's 90-degree edges stay sharp, the 30 to 45 degrees between the faces of
// coarse spheres and cylinders (12 or 8 segments) are smoothed. Unity's model importer uses 60 as well.
constexpr float kDefaultSmoothAngleDegrees = 60.0f;

struct CleanOptions {
  bool orient = false;          // make orientation consistent (outward if closed); otherwise kept as given
  bool smooth_normals = false;  // generate shading normals (scene/mesh_normals.h) where the soup has none
  float smooth_angle_degrees = kDefaultSmoothAngleDegrees;  // crease angle for smooth_normals, [0, 180]
};

// What cleaning changed, for `pathcl info`.
struct CleanReport {
  size_t input_vertices = 0, input_polygons = 0;
  size_t merged_vertices = 0;        // duplicate positions merged into one vertex
  size_t removed_isolated_vertices = 0;
  size_t degenerate_faces = 0;       // polygons with < 3 distinct vertices, collinear or zero-area triangles
  size_t duplicate_faces = 0;        // faces with the same vertex set as an earlier one
  size_t polygons_triangulated = 0;  // polygons with more than 3 vertices
  size_t triangles_from_polygons = 0;
  size_t faces_flipped = 0;          // only when CleanOptions::orient
  bool closed = false;               // every edge shared by exactly two faces
  // Only checked with CleanOptions::orient on a closed mesh: its faces intersect each other (e.g. two
  // overlapping boxes in one file, or a fold), so CGAL's orient_to_bound_a_volume does not apply and each
  // connected part is turned to a positive signed volume instead.
  bool self_intersecting = false;
};

struct TriangleMesh {
  std::vector<glm::dvec3> positions;               // world coordinates, as in PolygonSoup
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise = front
  // Shading normals per triangle corner (in the triangle's final vertex order): empty when the soup has
  // none and smooth_normals is off; otherwise unit, or zero where a corner has none (the renderer then
  // uses the face normal there: a face without file normals when smooth_normals is off, a zero file
  // normal, or generated normals that cancel).
  std::vector<std::array<glm::vec3, 3>> normals;
  // Where each triangle came from, whatever merging, triangulation and orienting did to it: the index
  // of its soup polygon, and for each of its three vertices (in the triangle's final order) the corner
  // of that polygon it is.
  std::vector<uint32_t> source_polygon;
  std::vector<std::array<uint32_t, 3>> source_corners;
  // The soup's attributes carried through by those sources: per triangle, the uvs of its three
  // vertices when the soup has uvs ((0, 0) for a polygon without), and the material id when the soup
  // has material ids, and likewise the colours. (The soup's normals go into `normals` above.)
  std::vector<std::array<glm::vec2, 3>> uvs;
  // The vertex colours of each triangle's corners when the soup has colours (white for a polygon without).
  std::vector<std::array<glm::vec3, 3>> colors;
  std::vector<uint32_t> materials;
};

// Throws SceneError (scene_error.h) with a message that the caller prefixes with the file/JSON place
// when the input cannot be cleaned (a failed CGAL check where CGAL's checks are compiled in) or its
// attributes do not match its polygons; never CGAL's own exceptions.
TriangleMesh clean_mesh(const PolygonSoup& soup, const CleanOptions& options, CleanReport& report);
