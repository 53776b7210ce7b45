// OBJ meshes through tinyobjloader, polygons kept whole (CGAL triangulates them in mesh_clean.cpp).
// tinyobjloader does not report line numbers, so one light scan of the file records where each vertex
// and face line is, for messages such as "bunny.obj:1043: face index 90211 out of range"; the same
// scan follows mtllib and usemtl, which we resolve ourselves (tinyobjloader only warns about an
// unknown material).
#include "scene/obj_load.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <tiny_obj_loader.h>

#include "scene/scene_description.h"
#include "scene/scene_error.h"

namespace {

// Mesh formats pathcl does not read, by extension and by how their files begin. tinyobjloader takes any
// file for OBJ: a PLY file became "igea.ply: no faces", a binary glTF "Failed parse 'l' line".
struct MeshFormat {
  const char* name;
  std::vector<std::string> extensions, starts;
  const char* hint = "";
};
const MeshFormat kOtherMeshFormats[] = {
    {"PLY", {".ply"}, {"ply\n", "ply\r"}},
    {"glTF", {".gltf", ".glb"}, {"glTF"}},
    {"STL", {".stl"}, {"solid "}},  // ASCII STL; binary STL is caught as binary
    {"OFF", {".off"}, {"OFF\n", "OFF\r", "OFF ", "COFF", "NOFF"}},
    {"FBX", {".fbx"}, {"Kaydara FBX Binary", "; FBX"}},
    {"COLLADA", {".dae"}, {"<?xml", "<COLLADA"}},
    {"3DS", {".3ds"}, {}},
    {"Blender", {".blend"}, {"BLENDER"}},
    {"USD", {".usd", ".usda", ".usdc", ".usdz"}, {"#usda", "PXR-USDC"}},
    {"Alembic", {".abc"}, {}},
    {"X3D", {".x3d"}, {}},
    {"VRML", {".wrl"}, {"#VRML"}},
    {"3MF", {".3mf"}, {}},
    {"LightWave", {".lwo"}, {}},
    {"Maya", {".ma", ".mb"}, {"//Maya"}},
    {"Compressed", {".gz", ".zip", ".xz", ".bz2", ".zst", ".7z"}, {"\x1f\x8b", "PK\x03\x04", "\xfd" "7zXZ"},
     "; decompress it first"},
};

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

[[noreturn]] void refuse_format(const std::string& path, const MeshFormat& f) {
  throw SceneError(path + ": " + f.name + " meshes are not supported (expected a Wavefront OBJ file" + f.hint + ")");
}

// Refuses, by extension, a mesh format that is not OBJ (before the file is opened: the format is the
// first thing to fix).
void check_obj_extension(const std::string& path) {
  std::string ext = lower_extension(path);
  for (const MeshFormat& f : kOtherMeshFormats)
    for (const std::string& e : f.extensions)
      if (ext == e) refuse_format(path, f);
}

// Refuses, by its first bytes, a file that is another mesh format, JSON or not text at all.
void check_obj_content(const std::string& path, const std::string& head) {
  for (const MeshFormat& f : kOtherMeshFormats)
    for (const std::string& start : f.starts)
      if (head.rfind(start, 0) == 0) refuse_format(path, f);
  size_t first = head.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && head[first] == '{')
    throw SceneError(path + ": looks like JSON (a glTF mesh or a scene file?), expected a Wavefront OBJ file");
  // Control characters other than white space do not occur in text.
  for (unsigned char c : head)
    if (c < 0x20 && c != '\t' && c != '\n' && c != '\v' && c != '\f' && c != '\r')
      throw SceneError(path + ": not a text OBJ file (it has binary content), expected a Wavefront OBJ file");
}

struct LineIndex {
  std::vector<size_t> vertex_lines, face_lines;
  std::vector<std::string> face_material;     // per face: the name of the usemtl in effect, or ""
  std::vector<size_t> face_material_line;     // per face: the line of that usemtl, or 0
  std::vector<std::pair<size_t, std::string>> mtllibs;  // (line, file) for each file an mtllib names
};

// Checks that the first `min` words of `words` are finite numbers, and the words after them up to
// `max` too if present (tinyobjloader would silently read a bad one as zero); more are not looked at.
void check_coordinates(const std::string& path, size_t number, const std::string& line, std::istringstream& words,
                       int min, int max, const char* what) {
  int count = 0;
  for (std::string word; count < max && words >> word; ++count) {
    char* end = nullptr;
    float value = std::strtof(word.c_str(), &end);
    if (*end != '\0' || !std::isfinite(value)) {
      count = -1;
      break;
    }
  }
  if (count < min)
    throw SceneError(path + ":" + std::to_string(number) + ": expected " + what + ", got \"" + line + "\"");
}

LineIndex scan_obj_lines(const std::string& path, std::istream& in) {
  LineIndex index;
  std::string line, material;
  size_t material_line = 0;
  for (size_t number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "f") {
      index.face_lines.push_back(number);
      index.face_material.push_back(material);
      index.face_material_line.push_back(material_line);
    } else if (keyword == "v") {
      index.vertex_lines.push_back(number);
      check_coordinates(path, number, line, words, 3, 3, "3 finite vertex coordinates");
    } else if (keyword == "vt") {
      check_coordinates(path, number, line, words, 1, 3, "1 to 3 finite texture coordinates");
    } else if (keyword == "usemtl") {
      std::getline(words, material);
      size_t a = material.find_first_not_of(" \t\r"), b = material.find_last_not_of(" \t\r");
      material = a == std::string::npos ? "" : material.substr(a, b - a + 1);
      material_line = number;
    } else if (keyword == "mtllib") {
      for (std::string file; words >> file;) index.mtllibs.push_back({number, file});
    }
  }
  return index;
}

// The MTL files named by mtllib, their materials concatenated; name -> index.
std::map<std::string, uint32_t> read_mtllibs(const std::string& path, const LineIndex& lines,
                                             std::vector<MtlMaterial>& materials, std::vector<std::string>& warnings) {
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  std::map<std::string, uint32_t> by_name;
  for (const auto& [line, file] : lines.mtllibs) {
    std::string mtl = (dir / file).string();
    std::string where = path + ":" + std::to_string(line);
    if (!std::filesystem::exists(mtl)) throw SceneError(where + ": cannot open the material file " + mtl);
    for (MtlMaterial& m : load_mtl(mtl, warnings)) {
      auto [it, added] = by_name.emplace(m.name, uint32_t(materials.size()));
      if (!added)
        throw SceneError(m.where + ": material \"" + m.name + "\" is already defined at " + materials[it->second].where);
      materials.push_back(std::move(m));
    }
  }
  return by_name;
}

}  // namespace

ObjFile load_obj_file(const std::string& path, bool with_materials, std::vector<std::string>& warnings) {
  check_obj_extension(path);
  check_obj_content(path, read_input_file(path, kMeshInput, 512));
  std::ifstream in(path);
  if (!in) throw SceneError(path + ": cannot open the mesh file");
  LineIndex lines = scan_obj_lines(path, in);
  in.clear();
  in.seekg(0);

  ObjFile obj;
  std::map<std::string, uint32_t> material_ids;
  if (with_materials) material_ids = read_mtllibs(path, lines, obj.materials, warnings);

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  // No material reader: the scan above resolved mtllib and usemtl.
  bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, nullptr, /*triangulate=*/false);
  if (!ok) throw SceneError(path + ": " + (err.empty() ? "cannot parse the OBJ file" : err));

  PolygonSoup& soup = obj.soup;
  size_t vertex_count = attrib.vertices.size() / 3, uv_count = attrib.texcoords.size() / 2;
  for (size_t i = 0; i < vertex_count; ++i)
    soup.positions.push_back({attrib.vertices[3 * i], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]});
  bool any_uvs = false;
  size_t face = 0;
  for (const tinyobj::shape_t& shape : shapes) {
    size_t offset = 0;
    for (unsigned char arity : shape.mesh.num_face_vertices) {
      size_t line = face < lines.face_lines.size() ? lines.face_lines[face] : 0;
      std::string where = path + ":" + (line ? std::to_string(line) : "?");
      std::vector<uint32_t> polygon;
      std::vector<glm::vec2> uvs;
      for (size_t k = 0; k < arity; ++k) {
        const tinyobj::index_t& corner = shape.mesh.indices[offset + k];
        int index = corner.vertex_index;
        if (index < 0 || size_t(index) >= vertex_count)
          throw SceneError(where + ": face index " + std::to_string(index + 1) + " out of range (" +
                           std::to_string(vertex_count) + " vertices)");
        polygon.push_back(uint32_t(index));
        int t = corner.texcoord_index;
        if (t >= 0 && size_t(t) >= uv_count)
          throw SceneError(where + ": texture coordinate index " + std::to_string(t + 1) + " out of range (" +
                           std::to_string(uv_count) + " texture coordinates)");
        if (t >= 0) uvs.push_back({attrib.texcoords[2 * t], attrib.texcoords[2 * t + 1]});
      }
      if (!uvs.empty() && uvs.size() != arity)
        throw SceneError(where + ": a face needs texture coordinates at all of its corners or at none");
      if (arity < 3) throw SceneError(where + ": a face needs at least 3 vertices");
      if (with_materials) {
        const std::string& name = face < lines.face_material.size() ? lines.face_material[face] : "";
        if (name.empty()) throw SceneError(where + ": face without a material (no usemtl before it)");
        auto it = material_ids.find(name);
        if (it == material_ids.end()) {
          std::string at = path + ":" + std::to_string(lines.face_material_line[face]);
          throw SceneError(at + ": unknown material \"" + name + "\"" +
                           (lines.mtllibs.empty() ? " (the file has no mtllib)" : " (not in its mtllib files)"));
        }
        soup.materials.push_back(it->second);
      }
      any_uvs = any_uvs || !uvs.empty();
      soup.polygons.push_back(std::move(polygon));
      soup.uvs.push_back(std::move(uvs));
      obj.face_lines.push_back(line);
      offset += arity;
      ++face;
    }
  }
  if (!any_uvs) soup.uvs.clear();
  if (soup.polygons.empty()) throw SceneError(path + ": no faces");
  return obj;
}

PolygonSoup load_obj(const std::string& path) {
  std::vector<std::string> warnings;
  return load_obj_file(path, false, warnings).soup;
}
