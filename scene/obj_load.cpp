// OBJ meshes through tinyobjloader, polygons kept whole (CGAL triangulates them in mesh_clean.cpp).
// tinyobjloader does not report line numbers, so one light scan of the file records where each vertex
// and face line is, for messages such as "bunny.obj:1043: face index 90211 out of range".
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <tiny_obj_loader.h>

#include "scene/scene_description.h"
#include "scene/scene_error.h"

namespace {

struct LineIndex {
  std::vector<size_t> vertex_lines, face_lines;
};

// Records the line of every `v` and `f` statement and rejects non-finite coordinates, which
// tinyobjloader would silently read as zero.
LineIndex scan_obj_lines(const std::string& path, std::istream& in) {
  LineIndex index;
  std::string line;
  for (size_t number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "f") index.face_lines.push_back(number);
    if (keyword != "v") continue;
    index.vertex_lines.push_back(number);
    for (int k = 0; k < 3; ++k) {
      std::string word;
      words >> word;
      char* end = nullptr;
      float value = std::strtof(word.c_str(), &end);
      if (word.empty() || *end != '\0' || !std::isfinite(value))
        throw SceneError(path + ":" + std::to_string(number) + ": expected 3 finite vertex coordinates, got \"" +
                         line + "\"");
    }
  }
  return index;
}

}  // namespace

PolygonSoup load_obj(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open the mesh file");
  LineIndex lines = scan_obj_lines(path, in);
  in.clear();
  in.seekg(0);

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  // No material reader: MTL files are not used yet, shapes name their material in the scene file.
  bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, nullptr, /*triangulate=*/false);
  if (!ok) throw SceneError(path + ": " + (err.empty() ? "cannot parse the OBJ file" : err));

  PolygonSoup soup;
  size_t vertex_count = attrib.vertices.size() / 3;
  for (size_t i = 0; i < vertex_count; ++i)
    soup.positions.push_back({attrib.vertices[3 * i], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]});
  size_t face = 0;
  for (const tinyobj::shape_t& shape : shapes) {
    size_t offset = 0;
    for (unsigned char arity : shape.mesh.num_face_vertices) {
      std::string where = path + ":" + (face < lines.face_lines.size() ? std::to_string(lines.face_lines[face]) : "?");
      std::vector<uint32_t> polygon;
      for (size_t k = 0; k < arity; ++k) {
        int index = shape.mesh.indices[offset + k].vertex_index;
        if (index < 0 || size_t(index) >= vertex_count)
          throw SceneError(where + ": face index " + std::to_string(index + 1) + " out of range (" +
                           std::to_string(vertex_count) + " vertices)");
        polygon.push_back(uint32_t(index));
      }
      if (arity < 3) throw SceneError(where + ": a face needs at least 3 vertices");
      soup.polygons.push_back(std::move(polygon));
      offset += arity;
      ++face;
    }
  }
  if (soup.polygons.empty()) throw SceneError(path + ": no faces");
  return soup;
}
