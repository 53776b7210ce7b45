// OBJ meshes through tinyobjloader, polygons kept whole (CGAL triangulates them in mesh_clean.cpp).
// tinyobjloader does not report line numbers, so one light scan of the file records where each face
// line is, for messages such as "bunny.obj:1043: face index 90211 out of range", and checks first what
// tinyobjloader would fail on or read wrong, so that every message is ours and names its line; the same
// scan follows mtllib and usemtl, which we resolve ourselves (tinyobjloader only warns about an
// unknown material).
#include "scene/obj_load.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string_view>

#include <tbb/parallel_invoke.h>
#include <tiny_obj_loader.h>

#include "scene/input_file.h"
#include "scene/scene_description.h"
#include "scene/scene_error.h"
#include "scene/texture_load.h"

namespace {

// Mesh formats other than OBJ, by extension and by how their files begin. tinyobjloader takes any file
// for OBJ: a PLY file became "igea.ply: no faces", a binary glTF "Failed parse 'l' line". PLY, STL and
// OFF are read by scene/ply_stl_off_load.cpp, chosen by the extension (`readable`): named .obj, they are
// told to be renamed; glTF files are a shape type of their own (scene/gltf_load.cpp); the others are not
// supported.
struct MeshFormat {
  const char* name;
  std::vector<std::string> extensions, starts;
  const char* hint = "";
  bool readable = false;
};
const MeshFormat kOtherMeshFormats[] = {
    {"PLY", {".ply"}, {"ply\n", "ply\r"}, "", true},
    {"glTF", {".gltf", ".glb"}, {"glTF"}},
    {"STL", {".stl"}, {"solid "}, "", true},  // ASCII STL; binary STL is caught as binary
    {"OFF", {".off"}, {"OFF\n", "OFF\r", "OFF ", "COFF", "NOFF"}, "", true},
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

[[noreturn]] void refuse_format(const std::string& path, const MeshFormat& f) {
  if (std::string(f.name) == "glTF")
    throw SceneError(path + ": a glTF file is placed by a shape of its own ({\"type\": \"gltf\", \"file\": ...}), "
                            "not as a mesh");
  if (f.readable)
    throw SceneError(path + (std::string(f.name) == "PLY" ? ": a " : ": an ") + f.name + " file named as OBJ (the reader is chosen by the extension: name it " +
                     f.extensions[0] + ")");
  throw SceneError(path + ": " + f.name + " meshes are not supported (expected " + kMeshInput.expected + f.hint + ")");
}

// Refuses, by extension, a mesh format that is not OBJ (before the file is opened: the format is the
// first thing to fix).
void check_obj_extension(const std::string& path) {
  std::string ext = lower_extension(path);
  for (const MeshFormat& f : kOtherMeshFormats)
    for (const std::string& e : f.extensions)
      if (ext == e && !f.readable) refuse_format(path, f);
}

// Refuses, by its first bytes, a file that is another mesh format, JSON or not text at all.
void check_obj_content(const std::string& path, const std::string& head) {
  for (const MeshFormat& f : kOtherMeshFormats)
    for (const std::string& start : f.starts)
      if (head.rfind(start, 0) == 0) refuse_format(path, f);
  size_t first = head.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && head[first] == '{')
    throw SceneError(path + ": looks like JSON (a glTF mesh or a scene file?), expected " + kMeshInput.expected);
  // UTF-16 text (an exporter's "Unicode"; assimp-testmodels' box_UTF16BE.obj): by its byte order mark.
  if (head.rfind("\xfe\xff", 0) == 0 || head.rfind("\xff\xfe", 0) == 0)
    throw SceneError(path + ": the file is UTF-16 text, expected an OBJ file in ASCII or UTF-8 (convert it, e.g. with iconv)");
  // Control characters other than white space do not occur in text.
  for (unsigned char c : head)
    if (c < 0x20 && c != '\t' && c != '\n' && c != '\v' && c != '\f' && c != '\r')
      throw SceneError(path + ": not a text OBJ file (it has binary content), expected " + kMeshInput.expected);
}

struct LineIndex {
  std::vector<size_t> face_lines;             // per face tinyobjloader keeps (3 or more corners)
  std::vector<std::string> face_material;     // per face: the name of the usemtl in effect, or ""
  std::vector<size_t> face_material_line;     // per face: the line of that usemtl, or 0
  std::vector<std::pair<size_t, std::string>> mtllibs;  // (line, file) for each file an mtllib names
  size_t short_faces = 0, first_short_face = 0, first_short_corners = 0;  // faces with 1 or 2 corners
};

// The words of a line as tinyobjloader separates them: by spaces and tabs. Views into `line`, into a
// vector reused from line to line: the scan reads every line of the file, and allocating a string per
// word was most of its time.
void split_words(const std::string& line, std::vector<std::string_view>& words) {
  words.clear();
  const std::string_view view(line);
  for (size_t a = view.find_first_not_of(" \t"); a != std::string_view::npos; a = view.find_first_not_of(" \t", a)) {
    size_t b = std::min(view.find_first_of(" \t", a), view.size());
    words.push_back(view.substr(a, b - a));
    a = b;
  }
}

// Checks that the first `min` of `words` after the keyword are finite numbers, and the words after them up
// to `max` too if present (tinyobjloader would silently read a bad one as zero); more are not looked at.
// (`where` is made only for a message: building it for every line cost as much as the checks.)
template <class Where>
void check_coordinates(const Where& where, const std::string& line, const std::vector<std::string_view>& words,
                       size_t min, size_t max, const char* what) {
  size_t count = 0;
  for (; count < max && count + 1 < words.size(); ++count) {
    // The word ends at a space, a tab or the end of the line (its terminating NUL), where strtof stops.
    const std::string_view word = words[count + 1];
    char* end = nullptr;
    float value = std::strtof(word.data(), &end);
    if (end != word.data() + word.size() || !std::isfinite(value)) break;
  }
  if (count < std::min(max, words.size() - 1) || count < min)
    throw SceneError(where() + ": expected " + what + ", got \"" + line + "\"");
}

// A non-zero integer that fits an int, as tinyobjloader's atoi reads OBJ indices ("" and "0" are not).
bool is_index(std::string_view text) {
  size_t digits = text.find_first_not_of('-') == 1 ? 1 : 0;
  if (text.size() <= digits || text.find_first_not_of("0123456789", digits) != std::string_view::npos) return false;
  long long value = text.size() - digits > 10 ? 0 : std::stoll(std::string(text));
  return value != 0 && value >= -2147483647 && value <= 2147483647;
}

// Checks the corners of an f, l or p statement: v, v/vt, v//vn or v/vt/vn. tinyobjloader gives up on the
// first bad one with a message of its own ("Failed parse 'f' line(e.g. zero value for face index. ...").
template <class Where>
void check_corners(const Where& where, const std::vector<std::string_view>& words) {
  for (size_t k = 1; k < words.size(); ++k) {
    const std::string_view w = words[k];
    size_t a = w.find('/'), b = a == std::string_view::npos ? a : w.find('/', a + 1);
    bool ok = is_index(w.substr(0, a));
    if (ok && a != std::string_view::npos) {
      std::string_view vt = w.substr(a + 1, b == std::string_view::npos ? b : b - a - 1);
      ok = (vt.empty() ? b != std::string_view::npos : is_index(vt)) &&
           (b == std::string_view::npos || is_index(w.substr(b + 1)));
    }
    if (!ok)
      throw SceneError(where() + ": bad vertex reference \"" + std::string(w) + "\" in \"" + std::string(words[0]) +
                       "\" (expected v, v/vt, v//vn or v/vt/vn: non-zero integers, 1 for the first vertex)");
  }
}

// "mtllib a.mtl my\ lib.mtl": file names separated by spaces, "\ " an escaped space (as exporters write
// names with spaces).
std::vector<std::string> mtllib_names(const std::string& line) {
  std::vector<std::string> names;
  std::string name;
  size_t start = line.find("mtllib") + 6;
  for (size_t i = start; i <= line.size(); ++i) {
    char c = i < line.size() ? line[i] : ' ';
    if (c == '\\' && i + 1 < line.size() && line[i + 1] == ' ') {
      name += ' ';
      ++i;
    } else if (c == ' ' || c == '\t') {
      if (!name.empty()) names.push_back(name);
      name.clear();
    } else {
      name += c;
    }
  }
  return names;
}

// Statements tinyobjloader would fail on are checked here first, so that every error is ours and names
// its line.
LineIndex scan_obj_lines(const std::string& path, std::istream& in) {
  LineIndex index;
  std::string line, material;
  std::vector<std::string_view> words;
  size_t material_line = 0;
  for (size_t number = 1; read_line(in, line); ++number) {
    split_words(line, words);
    if (words.empty()) continue;
    const std::string_view keyword = words[0];
    const auto where = [&] { return path + ":" + std::to_string(number); };
    if (keyword == "f" || keyword == "l" || keyword == "p") check_corners(where, words);
    if (keyword == "f") {
      size_t corners = words.size() - 1;
      // tinyobjloader drops faces of fewer than 3 corners (with a warning we would not see) and stores
      // corner counts in a byte: a face of 300 became one of 44, shifting every face after it.
      if (corners > 255)
        throw SceneError(where() + ": a face with " + std::to_string(corners) +
                         " vertices, more than the 255 the OBJ reader supports (split it)");
      if (corners < 3) {
        if (index.short_faces++ == 0) {
          index.first_short_face = number;
          index.first_short_corners = corners;
        }
        continue;
      }
      index.face_lines.push_back(number);
      index.face_material.push_back(material);
      index.face_material_line.push_back(material_line);
    } else if (keyword == "v") {
      check_coordinates(where, line, words, 3, 3, "3 finite vertex coordinates");
    } else if (keyword == "vn") {
      check_coordinates(where, line, words, 3, 3, "3 finite normal coordinates");
    } else if (keyword == "vt") {
      check_coordinates(where, line, words, 1, 3, "1 to 3 finite texture coordinates");
    } else if (keyword == "usemtl") {
      size_t a = line.find("usemtl") + 6;
      material = line.substr(a);
      size_t first = material.find_first_not_of(" \t"), last = material.find_last_not_of(" \t");
      material = first == std::string::npos ? "" : material.substr(first, last - first + 1);
      material_line = number;
    } else if (keyword == "mtllib") {
      for (const std::string& file : mtllib_names(line)) index.mtllibs.push_back({number, file});
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
    std::string where = path + ":" + std::to_string(line);
    std::string mtl = resolve_written_path(dir, file, where + ": mtllib", warnings);
    if (!std::filesystem::exists(mtl)) throw SceneError(where + ": cannot open the material file " + mtl);
    for (MtlMaterial& m : load_mtl(mtl)) {
      auto [it, added] = by_name.emplace(m.name, uint32_t(materials.size()));
      if (!added)
        throw SceneError(m.where + ": material \"" + m.name + "\" is already defined at " + materials[it->second].where);
      materials.push_back(std::move(m));
    }
  }
  return by_name;
}

// The warnings of the materials some face uses, and per MTL file the statements pathcl ignored in them:
// a library's other materials are not rendered, so what they say does not matter.
void warn_about_used_materials(const std::vector<MtlMaterial>& materials, const std::vector<uint32_t>& face_materials,
                               std::vector<std::string>& warnings) {
  std::vector<bool> used(materials.size(), false);
  for (uint32_t id : face_materials) used[id] = true;
  std::vector<std::pair<std::string, std::set<std::string>>> ignored;  // per MTL file, in file order
  for (size_t i = 0; i < materials.size(); ++i) {
    if (!used[i]) continue;
    const MtlMaterial& m = materials[i];
    warnings.insert(warnings.end(), m.warnings.begin(), m.warnings.end());
    if (ignored.empty() || ignored.back().first != m.file) ignored.push_back({m.file, {}});
    ignored.back().second.insert(m.ignored.begin(), m.ignored.end());
  }
  for (const auto& [file, keys] : ignored) {
    std::string list;
    for (const std::string& k : keys) list += (list.empty() ? "" : ", ") + k;
    if (!list.empty()) warnings.push_back(file + ": ignored statements (not used by pathcl): " + list);
  }
}

}  // namespace

ObjFile load_obj_file(const std::string& path, bool with_materials, std::vector<std::string>& warnings) {
  check_obj_extension(path);
  check_obj_content(path, read_input_file(path, kMeshInput, 512));
  if (!std::ifstream(path)) throw SceneError(path + ": cannot open the mesh file");

  // The scan and tinyobjloader's parse read the file side by side, each through a stream of its own (they
  // took about as long as each other). The scan's errors come first, as if it had run alone before the
  // parse; an exception of the parse (bad_alloc) only after them.
  LineIndex lines;
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  bool ok = false;
  std::exception_ptr scan_error, parse_error;
  tbb::parallel_invoke(
      [&] {
        try {
          std::ifstream in(path);
          lines = scan_obj_lines(path, in);
        } catch (...) {
          scan_error = std::current_exception();
        }
      },
      [&] {
        try {
          std::ifstream in(path);
          // No material reader: the scan resolves mtllib and usemtl.
          // Vertex colours ("v x y z r g b") only when every vertex has them (no white fallback).
          ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, nullptr, /*triangulate=*/false,
                                /*default_vcols_fallback=*/false);
        } catch (...) {
          parse_error = std::current_exception();
        }
      });
  if (scan_error) std::rethrow_exception(scan_error);

  ObjFile obj;
  std::map<std::string, uint32_t> material_ids;
  if (with_materials) material_ids = read_mtllibs(path, lines, obj.materials, warnings);

  if (parse_error) std::rethrow_exception(parse_error);
  if (!ok) {
    // What the scan does not check (tinyobjloader's own "vw" statement): only its line number is worth
    // passing on.
    size_t at = err.rfind("line ");
    long line = at == std::string::npos ? 0 : std::strtol(err.c_str() + at + 5, nullptr, 10);
    throw SceneError(path + (line > 0 ? ":" + std::to_string(line) + ": cannot read this statement" : ": cannot read the OBJ file"));
  }
  if (lines.short_faces > 0)
    warnings.push_back(path + ":" + std::to_string(lines.first_short_face) + ": face with " +
                       std::to_string(lines.first_short_corners) + " vertices ignored (a face needs at least 3)" +
                       (lines.short_faces > 1 ? ", and " + std::to_string(lines.short_faces - 1) + " more such faces" : ""));

  PolygonSoup& soup = obj.soup;
  size_t vertex_count = attrib.vertices.size() / 3, uv_count = attrib.texcoords.size() / 2;
  size_t normal_count = attrib.normals.size() / 3;
  for (size_t i = 0; i < vertex_count; ++i)
    soup.positions.push_back({attrib.vertices[3 * i], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]});
  // The colour extension's values are display values in [0, 1], sRGB-encoded as in PLY files.
  const bool colored = vertex_count > 0 && attrib.colors.size() == 3 * vertex_count;
  bool any_uvs = false, any_normals = false;
  size_t face = 0;
  for (const tinyobj::shape_t& shape : shapes) {
    size_t offset = 0;
    for (unsigned char arity : shape.mesh.num_face_vertices) {
      size_t line = face < lines.face_lines.size() ? lines.face_lines[face] : 0;
      const auto where = [&] { return path + ":" + (line ? std::to_string(line) : "?"); };
      std::vector<uint32_t> polygon;
      std::vector<glm::vec2> uvs;
      std::vector<glm::vec3> normals, colors;
      for (size_t k = 0; k < arity; ++k) {
        const tinyobj::index_t& corner = shape.mesh.indices[offset + k];
        int index = corner.vertex_index;
        if (index < 0 || size_t(index) >= vertex_count)
          throw SceneError(where() + ": face index " + std::to_string(index + 1) + " out of range (" +
                           std::to_string(vertex_count) + " vertices)");
        polygon.push_back(uint32_t(index));
        if (colored)
          colors.push_back({srgb_to_linear(attrib.colors[3 * index]), srgb_to_linear(attrib.colors[3 * index + 1]),
                            srgb_to_linear(attrib.colors[3 * index + 2])});
        int t = corner.texcoord_index;
        if (t >= 0 && size_t(t) >= uv_count)
          throw SceneError(where() + ": texture coordinate index " + std::to_string(t + 1) + " out of range (" +
                           std::to_string(uv_count) + " texture coordinates)");
        if (t >= 0) uvs.push_back({attrib.texcoords[2 * t], attrib.texcoords[2 * t + 1]});
        int n = corner.normal_index;
        if (n >= 0 && size_t(n) >= normal_count)
          throw SceneError(where() + ": normal index " + std::to_string(n + 1) + " out of range (" +
                           std::to_string(normal_count) + " normals)");
        if (n >= 0) normals.push_back({attrib.normals[3 * n], attrib.normals[3 * n + 1], attrib.normals[3 * n + 2]});
      }
      if (!uvs.empty() && uvs.size() != arity)
        throw SceneError(where() + ": a face needs texture coordinates at all of its corners or at none");
      if (!normals.empty() && normals.size() != arity)
        throw SceneError(where() + ": a face needs normals at all of its corners or at none");
      if (with_materials) {
        const std::string& name = face < lines.face_material.size() ? lines.face_material[face] : "";
        if (name.empty()) throw SceneError(where() + ": face without a material (no usemtl before it)");
        auto it = material_ids.find(name);
        if (it == material_ids.end()) {
          std::string at = path + ":" + std::to_string(lines.face_material_line[face]);
          throw SceneError(at + ": unknown material \"" + name + "\"" +
                           (lines.mtllibs.empty() ? " (the file has no mtllib)" : " (not in its mtllib files)"));
        }
        soup.materials.push_back(it->second);
      }
      any_uvs = any_uvs || !uvs.empty();
      any_normals = any_normals || !normals.empty();
      soup.polygons.push_back(std::move(polygon));
      soup.uvs.push_back(std::move(uvs));
      soup.normals.push_back(std::move(normals));
      if (colored) soup.colors.push_back(std::move(colors));
      obj.face_lines.push_back(line);
      offset += arity;
      ++face;
    }
  }
  if (!any_uvs) soup.uvs.clear();
  if (!any_normals) soup.normals.clear();
  if (with_materials) warn_about_used_materials(obj.materials, soup.materials, warnings);
  if (soup.polygons.empty()) throw SceneError(path + ": no faces");
  return obj;
}

PolygonSoup load_obj(const std::string& path) {
  std::vector<std::string> warnings;
  return load_obj_file(path, false, warnings).soup;
}
