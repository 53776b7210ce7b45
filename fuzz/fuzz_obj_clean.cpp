// libFuzzer target: a mesh file through its reader and clean_mesh (CGAL repair, triangulation,
// orientation, normals). The first input byte selects the options (bit 0: orient, bit 1: smooth normals;
// the seeds start with '0' to '3' for that) and the format (bits 2 and 3: 0 OBJ through load_obj,
// tinyobjloader plus our line checks; 1 PLY, 2 OFF, 3 STL through CGAL's readers, scene/ply_stl_off_load;
// seeds '4' to '7' are PLY, '8' to ';' OFF; bit 6 set: glTF or GLB through scene/gltf_load, each primitive's
// soup cleaned, seeds '@' to 'C'), the rest is the file. Bad input must end in SceneError; any other exception, crash, sanitizer report or broken
// invariant below is a bug. Run by scripts/fuzz.
#include <cmath>
#include <cstdint>

#include "fuzz/fuzz_common.h"
#include "scene/gltf_load.h"
#include "scene/mesh_clean.h"
#include "scene/ply_stl_off_load.h"
#include "scene/scene_description.h"
#include "scene/scene_error.h"

namespace {
// Bounds on the CGAL work per input (triangulating a polygon of n vertices costs up to O(n^3)).
constexpr size_t kMaxPolygons = 2000;
constexpr size_t kMaxPolygonVertices = 64;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > fuzz::kMaxInputBytes) return 0;
  CleanOptions options;
  options.orient = (data[0] & 1) != 0;
  options.smooth_normals = (data[0] & 2) != 0;
  const char* names[] = {"f.obj", "f.ply", "f.off", "f.stl"};
  const bool gltf = (data[0] & 0x40) != 0;
  const std::string path = fuzz::scratch().write(gltf ? "f.gltf" : names[(data[0] >> 2) & 3], data + 1, size - 1);
  try {
    std::vector<std::string> warnings;
    std::vector<PolygonSoup> soups;
    if (gltf) {
      GltfScene scene = load_gltf(path, warnings);
      for (GltfPrimitive& p : scene.primitives) soups.push_back(std::move(p.soup));
      for (const GltfPrimitive& p : scene.primitives)
        if (p.material >= scene.materials.size()) fuzz::invariant_failed("primitive material out of range");
    } else {
      soups.push_back((data[0] >> 2) & 3 ? load_ply_stl_off(path, warnings) : load_obj(path));
    }
    size_t polygons = 0;
    for (const PolygonSoup& soup : soups) {
      polygons += soup.polygons.size();
      for (const auto& polygon : soup.polygons)
        if (polygon.size() > kMaxPolygonVertices) return 0;
    }
    if (polygons > kMaxPolygons) return 0;
    for (const PolygonSoup& soup : soups) {
      CleanReport report;
      const TriangleMesh mesh = clean_mesh(soup, options, report);

      // What build_device_scene relies on.
      for (const auto& t : mesh.triangles)
        for (uint32_t v : t)
          if (v >= mesh.positions.size()) fuzz::invariant_failed("triangle index out of range");
      const bool normals = options.smooth_normals || !soup.normals.empty();
      if (mesh.normals.size() != (normals ? mesh.triangles.size() : 0)) fuzz::invariant_failed("one normal triple per triangle");
      for (const auto& corners : mesh.normals)
        for (const glm::vec3& n : corners) {
          const float length = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
          if (!(length == 0 || std::abs(length - 1) < 1e-5f)) fuzz::invariant_failed("normal neither unit nor zero");
        }
      // Per-corner attributes follow the triangles: sources name a real corner at the vertex's position.
      if (mesh.source_polygon.size() != mesh.triangles.size() || mesh.source_corners.size() != mesh.triangles.size())
        fuzz::invariant_failed("one source per triangle");
      if (mesh.uvs.size() != (soup.uvs.empty() ? 0 : mesh.triangles.size())) fuzz::invariant_failed("one uv triple per triangle");
      for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        if (mesh.source_polygon[t] >= soup.polygons.size()) fuzz::invariant_failed("source polygon out of range");
        const auto& polygon = soup.polygons[mesh.source_polygon[t]];
        for (int j = 0; j < 3; ++j) {
          if (mesh.source_corners[t][j] >= polygon.size()) fuzz::invariant_failed("source corner out of range");
          if (soup.positions[polygon[mesh.source_corners[t][j]]] != mesh.positions[mesh.triangles[t][j]])
            fuzz::invariant_failed("source corner elsewhere than its vertex");
        }
      }
    }
  } catch (const SceneError&) {
    // Rejected input: expected.
  }
  return 0;
}
