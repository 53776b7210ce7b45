// Real sample files nobody here wrote: Debian's assimp-testmodels (assimp's test/models, BSD-3-clause,
// installed by scripts/test). Each file loads with the counts, positions, normals, uvs, transforms,
// materials and textures the file itself states, read here by small readers of the test's own (PLY and
// OFF headers and bodies, STL facets, OBJ statements, glTF JSON and buffers) rather than taken from
// pathcl's output; files that are broken or of something pathcl does not render are refused with
// "FILE: what is wrong" and exit status 2. Without the package the tests are skipped (reported as such by
// CTest, tests/CMakeLists.txt).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "scene/ply_stl_off_load.h"
#include "scene/scene_error.h"
#include "test_support.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const std::string kModels = "/usr/share/assimp/models";

#define REQUIRE_MODELS()                                                                                 \
  if (!fs::is_directory(kModels)) GTEST_SKIP() << kModels << " is missing: install Debian's assimp-testmodels " \
                                                  "(scripts/test does)"

std::string model(const std::string& name) { return kModels + "/" + name; }

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// ---- A PLY reader of the test's own: ASCII and binary little-endian, scalar and list properties -------

struct PlyProperty {
  std::string name, type, count_type;  // count_type non-empty: a list
};
struct PlyElementSpec {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> properties;
};
struct PlyFile {
  std::string format;
  std::vector<PlyElementSpec> elements;
  // Per element name: per item, per property, its values (one, or a list).
  std::map<std::string, std::vector<std::vector<std::vector<double>>>> items;
  const PlyElementSpec* element(const std::string& name) const {
    for (const auto& e : elements)
      if (e.name == name) return &e;
    return nullptr;
  }
  int property(const std::string& element_name, std::initializer_list<const char*> names) const {
    const PlyElementSpec* e = element(element_name);
    for (size_t k = 0; e && k < e->properties.size(); ++k)
      for (const char* n : names)
        if (e->properties[k].name == n) return int(k);
    return -1;
  }
};

size_t ply_size(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "double" || type == "float64") return 8;
  return 4;  // int, uint, float and their sized names
}

double ply_binary_value(const std::string& data, size_t& at, const std::string& type) {
  auto get = [&](auto v) {
    std::memcpy(&v, data.data() + at, sizeof(v));
    at += sizeof(v);
    return double(v);
  };
  if (at + ply_size(type) > data.size()) throw std::runtime_error("PLY body ends early");
  if (type == "char" || type == "int8") return get(int8_t());
  if (type == "uchar" || type == "uint8") return get(uint8_t());
  if (type == "short" || type == "int16") return get(int16_t());
  if (type == "ushort" || type == "uint16") return get(uint16_t());
  if (type == "int" || type == "int32") return get(int32_t());
  if (type == "uint" || type == "uint32") return get(uint32_t());
  if (type == "float" || type == "float32") return get(float());
  return get(double());
}

PlyFile read_ply_file(const std::string& path, bool with_body = true) {
  const std::string data = read_file(path);
  PlyFile ply;
  std::istringstream header(data);
  std::string line;
  while (std::getline(header, line)) {
    std::istringstream words(line);
    std::string word;
    words >> word;
    if (word == "format") {
      words >> ply.format;
    } else if (word == "element") {
      PlyElementSpec e;
      words >> e.name >> e.count;
      ply.elements.push_back(e);
    } else if (word == "property") {
      PlyProperty p;
      words >> p.type;
      if (p.type == "list") words >> p.count_type >> p.type;
      words >> p.name;
      ply.elements.back().properties.push_back(p);
    } else if (word == "end_header") {
      break;
    }
  }
  if (!with_body) return ply;
  size_t at = size_t(header.tellg());
  std::istringstream text(data.substr(at));
  for (const PlyElementSpec& e : ply.elements) {
    auto& items = ply.items[e.name];
    for (size_t i = 0; i < e.count; ++i) {
      std::vector<std::vector<double>> item;
      for (const PlyProperty& p : e.properties) {
        std::vector<double> values;
        auto next = [&](const std::string& type) {
          if (ply.format == "ascii") {
            double v;
            if (!(text >> v)) throw std::runtime_error("PLY body ends early");
            return type == "float" || type == "float32" ? double(float(v)) : v;  // the file's type
          }
          return ply_binary_value(data, at, type);
        };
        size_t n = p.count_type.empty() ? 1 : size_t(next(p.count_type));
        for (size_t k = 0; k < n; ++k) values.push_back(next(p.type));
        item.push_back(values);
      }
      items.push_back(item);
    }
  }
  return ply;
}

// The loader's soup, compared with what the file says: every vertex, every face's indices, and the
// normals and uvs at each corner from the vertex they belong to.
void expect_soup_is_the_ply(const std::string& file) {
  SCOPED_TRACE(file);
  const PlyFile ply = read_ply_file(model(file));
  ASSERT_EQ(ply.format == "ascii" || ply.format == "binary_little_endian", true) << ply.format;
  std::vector<std::string> warnings;
  const PolygonSoup soup = load_ply_stl_off(model(file), warnings);
  const auto& vertices = ply.items.at("vertex");
  const auto& faces = ply.items.at("face");
  ASSERT_EQ(soup.positions.size(), ply.element("vertex")->count);
  ASSERT_EQ(soup.polygons.size(), ply.element("face")->count);
  const int x = ply.property("vertex", {"x"}), nx = ply.property("vertex", {"nx"}),
            u = ply.property("vertex", {"u", "s", "texture_u", "texture_s"}),
            index = ply.property("face", {"vertex_indices", "vertex_index"});
  ASSERT_GE(index, 0);
  for (size_t i = 0; i < vertices.size(); ++i)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(soup.positions[i][c], vertices[i][size_t(x + c)][0]) << "vertex " << i;
  EXPECT_EQ(soup.normals.empty(), nx < 0);
  EXPECT_EQ(soup.uvs.empty(), u < 0);
  for (size_t f = 0; f < faces.size(); ++f) {
    const std::vector<double>& corners = faces[f][size_t(index)];
    ASSERT_EQ(soup.polygons[f].size(), corners.size()) << "face " << f;
    for (size_t k = 0; k < corners.size(); ++k) {
      const size_t v = size_t(corners[k]);
      ASSERT_EQ(soup.polygons[f][k], v) << "face " << f;
      for (int c = 0; nx >= 0 && c < 3; ++c)
        ASSERT_EQ(soup.normals[f][k][c], float(vertices[v][size_t(nx + c)][0])) << "face " << f;
      for (int c = 0; u >= 0 && c < 2; ++c)
        ASSERT_EQ(soup.uvs[f][k][c], float(vertices[v][size_t(u + c)][0])) << "face " << f;
    }
  }
}

std::string scene_placing(const std::string& shape, const std::string& camera = "") {
  return R"({"camera": )" +
         (camera.empty() ? R"({"position": [0, 0, 5], "look_at": [0, 0, 0], "width": 8, "height": 8})" : camera) +
         R"(, "materials": {"m": {"type": "diffuse"}}, "shapes": [)" + shape + "]}";
}

SceneDescription load_model(const std::string& file, const std::string& options = "") {
  return load_scene(write_temp_file("model.json", scene_placing(R"({"type": "mesh", "file": ")" + model(file) +
                                                                R"(", "material": "m")" + options + "}")));
}

// Triangles that n-gons give (n - 2 each).
size_t fan_triangles(const std::vector<size_t>& corner_counts) {
  size_t n = 0;
  for (size_t c : corner_counts) n += c - 2;
  return n;
}

// "FILE: message" from load_scene and exit status 2 from `pathcl render`.
void expect_refused(const std::string& shape, const std::string& file, const std::string& message) {
  const std::string scene = write_temp_file("refused.json", scene_placing(shape));
  // The file, then (after a place in it such as "nodes[1] meshes[0].primitives[0]: ") the message.
  auto names = [&](const std::string& text) {
    const size_t at = text.find(file + ": ");
    return at != std::string::npos && text.find(message, at) != std::string::npos;
  };
  const std::string error = scene_load_error(scene);
  EXPECT_TRUE(names(error)) << error;
  std::string err;
  EXPECT_EQ(run_pathcl("render " + scene + " -q -o " + temp_dir() + "/refused.exr", &err), 2) << err;
  EXPECT_TRUE(names(err)) << err;
}

}  // namespace

// ASCII PLY (cube.ply: quads, `vertex_index`, sized type names float32/uint8/int32, trailing blanks;
// Wuson.ply and cube_uv.ply: normals and s, t) and binary little-endian PLY (cube_binary.ply).
TEST(SampleModels, PlyAsciiAndBinaryGiveTheFilesVerticesFacesNormalsAndUvs) {
  REQUIRE_MODELS();
  for (const char* file : {"PLY/cube.ply", "PLY/cube_binary.ply", "PLY/cube_uv.ply", "PLY/Wuson.ply"})
    expect_soup_is_the_ply(file);
  // Through the whole load: the triangles the faces make, less those the clean-up reports dropping.
  for (const char* file : {"PLY/cube.ply", "PLY/cube_binary.ply", "PLY/Wuson.ply"}) {
    SCOPED_TRACE(file);
    const PlyFile ply = read_ply_file(model(file));
    std::vector<size_t> corners;
    for (const auto& face : ply.items.at("face")) corners.push_back(face[size_t(ply.property("face", {"vertex_indices", "vertex_index"}))].size());
    const SceneDescription s_scene = load_model(file);
    const ShapeDesc& s = s_scene.shapes.at(0);
    EXPECT_EQ(s.clean.input_vertices, ply.element("vertex")->count);
    EXPECT_EQ(s.clean.input_polygons, ply.element("face")->count);
    EXPECT_EQ(s.mesh.triangles.size(), fan_triangles(corners) - s.clean.degenerate_faces - s.clean.duplicate_faces);
  }
  // The cubes are closed boxes of 12 triangles whatever their files' layouts.
  for (const char* file : {"PLY/cube.ply", "PLY/cube_binary.ply"}) {
    const SceneDescription s_scene = load_model(file, R"(, "orient": true)");
    const ShapeDesc& s = s_scene.shapes.at(0);
    EXPECT_EQ(s.mesh.triangles.size(), 12u) << file;
    EXPECT_TRUE(s.clean.closed) << file;
  }
}

// PLY files without faces are refused as point clouds by their header, before their body is read:
// pond.0.ply (a scan's 70051 points, whose binary body is damaged after vertex 692 (69 bytes short, as if
// its line ends had been converted) and points.ply.
TEST(SampleModels, PlyPointCloudsAreRefusedAsSuch) {
  REQUIRE_MODELS();
  for (const char* file : {"PLY/pond.0.ply", "PLY/points.ply"}) {
    const PlyFile ply = read_ply_file(model(file), false);
    ASSERT_EQ(ply.element("face"), nullptr) << file;
    expect_refused(R"({"type": "mesh", "file": ")" + model(file) + R"(", "material": "m"})", model(file),
                   "no faces (" + std::to_string(ply.element("vertex")->count) +
                       " vertices: a point cloud? pathcl renders surfaces)");
  }
}

// STL: ASCII (Spider_ascii.stl, and a file of two solids) and binary (Spider_binary.stl, 3DSMaxExport.STL,
// whose 80-byte header starts "STLEXP", not "solid"). Each facet is one triangle of the soup, its corners
// the facet's vertices in order; vertices equal in all three coordinates are one.
TEST(SampleModels, StlAsciiAndBinaryGiveTheFilesFacets) {
  REQUIRE_MODELS();
  struct Facets {
    std::vector<std::array<glm::dvec3, 3>> triangles;
  };
  auto ascii_facets = [](const std::string& path) {
    std::istringstream in(read_file(path));
    Facets f;
    std::string word;
    std::vector<glm::dvec3> loop;
    while (in >> word)
      if (word == "vertex") {
        glm::dvec3 p;
        in >> p.x >> p.y >> p.z;
        loop.push_back(p);
        if (loop.size() == 3) f.triangles.push_back({loop[0], loop[1], loop[2]}), loop.clear();
      }
    return f;
  };
  auto binary_facets = [](const std::string& path) {
    const std::string data = read_file(path);
    uint32_t n;
    std::memcpy(&n, data.data() + 80, 4);
    EXPECT_EQ(data.size(), 84 + 50 * size_t(n)) << path;
    Facets f;
    for (uint32_t t = 0; t < n; ++t) {
      float v[9];
      std::memcpy(v, data.data() + 84 + 50 * size_t(t) + 12, sizeof(v));
      f.triangles.push_back({glm::dvec3(v[0], v[1], v[2]), glm::dvec3(v[3], v[4], v[5]), glm::dvec3(v[6], v[7], v[8])});
    }
    return f;
  };
  // sphereWithHole.stl starts "solid\ttinysphere": ASCII, though no blank follows "solid".
  const std::pair<const char*, bool> files[] = {{"STL/Spider_ascii.stl", true}, {"STL/triangle_with_two_solids.stl", true},
                                                {"STL/sphereWithHole.stl", true},
                                                {"STL/Spider_binary.stl", false}, {"STL/3DSMaxExport.STL", false}};
  for (const auto& [file, ascii] : files) {
    SCOPED_TRACE(file);
    const Facets expected = ascii ? ascii_facets(model(file)) : binary_facets(model(file));
    ASSERT_GT(expected.triangles.size(), 0u);
    std::vector<std::string> warnings;
    const PolygonSoup soup = load_ply_stl_off(model(file), warnings);
    ASSERT_EQ(soup.polygons.size(), expected.triangles.size());
    std::set<std::array<double, 3>> distinct;
    for (size_t t = 0; t < expected.triangles.size(); ++t) {
      ASSERT_EQ(soup.polygons[t].size(), 3u);
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(soup.positions.at(soup.polygons[t][size_t(k)]), expected.triangles[t][size_t(k)]) << "facet " << t;
        const glm::dvec3& p = expected.triangles[t][size_t(k)];
        distinct.insert({p.x, p.y, p.z});
      }
    }
    EXPECT_EQ(soup.positions.size(), distinct.size());
    EXPECT_TRUE(soup.normals.empty());  // facet normals are the faces' own
  }
}

// OFF (Cube.off: quads; Wuson.off): the header's counts, the vertices and the faces.
TEST(SampleModels, OffGivesTheFilesVerticesAndFaces) {
  REQUIRE_MODELS();
  for (const char* file : {"OFF/Cube.off", "OFF/Wuson.off"}) {
    SCOPED_TRACE(file);
    std::istringstream in(read_file(model(file)));
    std::string keyword;
    size_t nv, nf, ne;
    in >> keyword >> nv >> nf >> ne;
    ASSERT_EQ(keyword, "OFF");
    std::vector<glm::dvec3> vertices(nv);
    for (auto& v : vertices) in >> v.x >> v.y >> v.z;
    std::vector<std::vector<uint32_t>> faces(nf);
    std::vector<size_t> corners;
    for (auto& f : faces) {
      size_t n;
      in >> n;
      f.resize(n);
      for (auto& i : f) in >> i;
      corners.push_back(n);
    }
    std::vector<std::string> warnings;
    const PolygonSoup soup = load_ply_stl_off(model(file), warnings);
    EXPECT_EQ(soup.positions, vertices);
    EXPECT_EQ(soup.polygons, faces);
    const SceneDescription s_scene = load_model(file);
    const ShapeDesc& s = s_scene.shapes.at(0);
    EXPECT_EQ(s.mesh.triangles.size(), fan_triangles(corners) - s.clean.degenerate_faces - s.clean.duplicate_faces);
  }
  // Cube.off: the 6 quads of a closed cube.
  const SceneDescription cube_scene = load_model("OFF/Cube.off", R"(, "orient": true)");
  const ShapeDesc& cube = cube_scene.shapes.at(0);
  EXPECT_EQ(cube.mesh.triangles.size(), 12u);
  EXPECT_TRUE(cube.clean.closed);
  // invalid.off says 4 faces and gives none: truncated.
  expect_refused(R"({"type": "mesh", "file": ")" + model("OFF/invalid.off") + R"(", "material": "m"})",
                 model("OFF/invalid.off"), "truncated or garbled OFF file");
}

// OBJ: box.obj (quads) and concave_polygon.obj (one concave polygon) count as their v and f lines say;
// spider.obj takes its materials and textures from spider.mtl ("from_mtl"), whose map_Kd paths are written
// Windows-style (.\SpiderTex.jpg): one material per usemtl name, one texture per distinct image of them.
TEST(SampleModels, ObjCountsMaterialsAndTextures) {
  REQUIRE_MODELS();
  struct ObjCounts {
    size_t vertices = 0, uvs = 0;
    std::vector<size_t> corners;
    std::set<std::string> materials;
  };
  auto count = [](const std::string& path) {
    std::istringstream in(read_file(path));
    ObjCounts c;
    std::string line;
    while (std::getline(in, line)) {
      std::istringstream words(line);
      std::string word;
      words >> word;
      if (word == "v") ++c.vertices;
      if (word == "vt") ++c.uvs;
      if (word == "usemtl") words >> word, c.materials.insert(word);
      if (word == "f") {
        size_t n = 0;
        while (words >> word) ++n;
        c.corners.push_back(n);
      }
    }
    return c;
  };
  for (const char* file : {"OBJ/box.obj", "OBJ/concave_polygon.obj", "OBJ/spider.obj"}) {
    SCOPED_TRACE(file);
    const ObjCounts c = count(model(file));
    ASSERT_FALSE(c.corners.empty());
    const SceneDescription scene = load_model(file);
    const ShapeDesc& s = scene.shapes.at(0);
    EXPECT_EQ(s.clean.input_vertices, c.vertices);
    EXPECT_EQ(s.clean.input_polygons, c.corners.size());
    EXPECT_EQ(s.mesh.triangles.size(), fan_triangles(c.corners) - s.clean.degenerate_faces - s.clean.duplicate_faces);
  }
  // The spider's materials from its MTL file: the map_Kd image of each used material.
  std::map<std::string, std::string> map_kd;
  {
    std::istringstream in(read_file(model("OBJ/spider.mtl")));
    std::string line, current;
    while (std::getline(in, line)) {
      std::istringstream words(line);
      std::string word;
      words >> word;
      if (word == "newmtl") words >> current;
      if (word == "map_Kd") words >> map_kd[current];
    }
  }
  const ObjCounts c = count(model("OBJ/spider.obj"));
  std::set<std::string> images;
  for (const std::string& m : c.materials) images.insert(map_kd.at(m));
  const SceneDescription scene = load_scene(write_temp_file("spider.json", scene_placing(
      R"({"type": "mesh", "file": ")" + model("OBJ/spider.obj") + R"(", "material": "from_mtl"})")));
  const ShapeDesc& spider = scene.shapes.at(0);
  std::set<uint32_t> used(spider.triangle_materials.begin(), spider.triangle_materials.end());
  EXPECT_EQ(used.size(), c.materials.size());
  std::set<std::string> names, textures;
  for (uint32_t m : used) {
    names.insert(scene.materials[m].name);
    ASSERT_NE(scene.materials[m].color_texture, PC_INVALID) << scene.materials[m].name;
    textures.insert(fs::path(scene.textures[scene.materials[m].color_texture].file).filename().string());
  }
  std::set<std::string> expected_textures;
  for (const std::string& image : images) expected_textures.insert(image.substr(image.find_last_of('\\') + 1));
  EXPECT_EQ(textures, expected_textures);
  EXPECT_EQ(scene.textures.size(), expected_textures.size());
  // Every used material's name appears in what pathcl calls it.
  for (const std::string& m : c.materials)
    EXPECT_TRUE(std::any_of(names.begin(), names.end(), [&](const std::string& n) { return n.find(m) != std::string::npos; }))
        << m;
}

namespace {

// The glTF JSON of a .gltf file or of a GLB's first chunk, and the binary chunk.
struct GltfFile {
  json doc;
  std::string bin;
};
GltfFile read_gltf_file(const std::string& path) {
  const std::string data = read_file(path);
  GltfFile g;
  if (data.compare(0, 4, "glTF") == 0) {
    uint32_t json_length, bin_length;
    std::memcpy(&json_length, data.data() + 12, 4);
    g.doc = json::parse(data.substr(20, json_length));
    if (20 + json_length + 8 <= data.size()) {
      std::memcpy(&bin_length, data.data() + 20 + json_length, 4);
      g.bin = data.substr(20 + json_length + 8, bin_length);
    }
  } else {
    g.doc = json::parse(data);
  }
  return g;
}

glm::dmat4 node_matrix(const json& node) {
  if (node.contains("matrix")) {
    glm::dmat4 m;
    for (int i = 0; i < 16; ++i) m[i / 4][i % 4] = node["matrix"][i].get<double>();  // column-major
    return m;
  }
  glm::dmat4 t(1), r(1), s(1);
  if (node.contains("translation"))
    for (int c = 0; c < 3; ++c) t[3][c] = node["translation"][c].get<double>();
  if (node.contains("rotation")) {
    const json& q = node["rotation"];
    r = glm::mat4_cast(glm::dquat(q[3].get<double>(), q[0].get<double>(), q[1].get<double>(), q[2].get<double>()));
  }
  if (node.contains("scale"))
    for (int c = 0; c < 3; ++c) s[c][c] = node["scale"][c].get<double>();
  return t * r * s;
}

// Every (node, primitive) the default scene places, with the node's world matrix.
struct Placed {
  size_t node, primitive;
  glm::dmat4 world;
  const json* prim;
};
std::vector<Placed> placed_primitives(const json& doc) {
  std::vector<Placed> out;
  std::function<void(size_t, glm::dmat4)> visit = [&](size_t n, glm::dmat4 parent) {
    const json& node = doc["nodes"][n];
    const glm::dmat4 world = parent * node_matrix(node);
    if (node.contains("mesh")) {
      const json& prims = doc["meshes"][node["mesh"].get<size_t>()]["primitives"];
      for (size_t p = 0; p < prims.size(); ++p) out.push_back({n, p, world, &prims[p]});
    }
    if (node.contains("children"))
      for (const json& c : node["children"]) visit(c.get<size_t>(), world);
  };
  const size_t scene = doc.value("scene", 0);
  for (const json& n : doc["scenes"][scene]["nodes"]) visit(n.get<size_t>(), glm::dmat4(1));
  return out;
}

// The shape pathcl made of nodes[node] ... primitives[primitive], by its label.
const ShapeDesc* shape_of(const SceneDescription& scene, size_t node, size_t primitive) {
  const std::regex pattern("nodes\\[" + std::to_string(node) + "\\].*primitives\\[" + std::to_string(primitive) + "\\]");
  for (const ShapeDesc& s : scene.shapes)
    if (std::regex_search(s.label, pattern)) return &s;
  return nullptr;
}

// Checks every placed primitive: one shape each, its triangle count from the index accessor, and its
// positions, taken back through the inverse of the node's world matrix, within the POSITION accessor's
// min and max (which glTF requires to be exact) and reaching them on every axis.
void expect_gltf_scene(const std::string& file, const SceneDescription& scene) {
  SCOPED_TRACE(file);
  const GltfFile g = read_gltf_file(model(file));
  const std::vector<Placed> placed = placed_primitives(g.doc);
  ASSERT_FALSE(placed.empty());
  EXPECT_EQ(scene.shapes.size(), placed.size());
  for (const Placed& p : placed) {
    const ShapeDesc* placed_shape = shape_of(scene, p.node, p.primitive);
    ASSERT_NE(placed_shape, nullptr) << "nodes[" << p.node << "] primitives[" << p.primitive << "]";
    // An instance as its placed copy: the instanced mesh's clean-up and triangles, placed by the shape.
    const ShapeDesc flat = flattened_shape(scene, *placed_shape);
    const ShapeDesc* s = &flat;
    ASSERT_EQ(p.prim->value("mode", 4), 4);
    const json& position = g.doc["accessors"][(*p.prim)["attributes"]["POSITION"].get<size_t>()];
    const size_t corners = p.prim->contains("indices") ? g.doc["accessors"][(*p.prim)["indices"].get<size_t>()]["count"].get<size_t>()
                                                       : position["count"].get<size_t>();
    EXPECT_EQ(s->clean.input_polygons, corners / 3) << s->label;
    EXPECT_EQ(s->mesh.triangles.size(), corners / 3 - s->clean.degenerate_faces - s->clean.duplicate_faces) << s->label;
    const glm::dmat4 inverse = glm::inverse(p.world);
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::dvec3& q : s->mesh.positions) {
      const glm::dvec3 local = glm::dvec3(inverse * glm::dvec4(q, 1));
      lo = glm::min(lo, local);
      hi = glm::max(hi, local);
    }
    for (int c = 0; c < 3; ++c) {
      const double min = position["min"][c].get<double>(), max = position["max"][c].get<double>();
      const double tol = 1e-5 * std::max({1.0, std::abs(min), std::abs(max)});
      EXPECT_NEAR(lo[c], min, tol) << s->label << " axis " << c;
      EXPECT_NEAR(hi[c], max, tol) << s->label << " axis " << c;
    }
  }
}

std::string gltf_shape(const std::string& file) { return R"({"type": "gltf", "file": ")" + model(file) + "\"}"; }

SceneDescription load_gltf_model(const std::string& file) {
  return load_scene(write_temp_file("gltf-model.json", scene_placing(gltf_shape(file))));
}

// Width and height from a PNG's IHDR.
std::pair<uint32_t, uint32_t> png_size(const std::string& bytes) {
  auto be32 = [&](size_t at) {
    return uint32_t(uint8_t(bytes[at])) << 24 | uint32_t(uint8_t(bytes[at + 1])) << 16 | uint32_t(uint8_t(bytes[at + 2])) << 8 |
           uint32_t(uint8_t(bytes[at + 3]));
  };
  return {be32(16), be32(20)};
}

}  // namespace

// glTF's BoxTextured in its three packings (external .bin and .png, data URIs, GLB): a node matrix that
// turns the box (z up to y up) above a child with the mesh, a metallic-0 material with a base-colour
// texture (CesiumLogoFlat.png): a plastic with the texture, its size as the PNG's header says.
TEST(SampleModels, GltfBoxTexturedInEveryPackingHasItsTransformMaterialAndTexture) {
  REQUIRE_MODELS();
  const auto [width, height] = png_size(read_file(model("glTF2/BoxTextured-glTF/CesiumLogoFlat.png")));
  for (const char* file : {"glTF2/BoxTextured-glTF/BoxTextured.gltf", "glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf",
                           "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb"}) {
    SCOPED_TRACE(file);
    const SceneDescription scene = load_gltf_model(file);
    expect_gltf_scene(file, scene);
    const GltfFile g = read_gltf_file(model(file));
    ASSERT_EQ(scene.shapes.size(), 1u);
    const json& pbr = g.doc["materials"][0]["pbrMetallicRoughness"];
    ASSERT_EQ(pbr.value("metallicFactor", 1.0), 0.0);
    const MaterialDesc& m = scene.materials[scene.shapes[0].material];
    EXPECT_EQ(m.type_id, uint32_t(PC_MAT_PLASTIC));
    ASSERT_NE(m.color_texture, PC_INVALID);
    EXPECT_EQ(scene.textures[m.color_texture].width, width);
    EXPECT_EQ(scene.textures[m.color_texture].height, height);
    // The file's normals are the shading normals: the box's faces are flat, so each corner's normal is its
    // face's, turned by the matrix like the positions.
    const TriangleMesh& mesh = scene.shapes[0].mesh;
    ASSERT_EQ(mesh.normals.size(), mesh.triangles.size());
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& tri = mesh.triangles[t];
      const glm::dvec3 n = glm::normalize(glm::cross(mesh.positions[tri[1]] - mesh.positions[tri[0]],
                                                     mesh.positions[tri[2]] - mesh.positions[tri[0]]));
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(glm::dot(glm::dvec3(mesh.normals[t][k]), n), 1.0, 1e-5) << t;
    }
  }
}

// 2CylinderEngine.glb: 82 nodes deep, matrices with rotations and large translations, 34 meshes; every
// primitive where its node chain puts it.
TEST(SampleModels, GltfEngineNodeHierarchyPlacesEveryPrimitive) {
  REQUIRE_MODELS();
  const std::string file = "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb";
  const SceneDescription scene = load_gltf_model(file);
  expect_gltf_scene(file, scene);
  // Materials: one per glTF material the primitives use.
  const GltfFile g = read_gltf_file(model(file));
  std::set<size_t> used;
  for (const Placed& p : placed_primitives(g.doc)) used.insert(p.prim->value("material", size_t(0)));
  std::set<uint32_t> pathcl_materials;
  for (const ShapeDesc& s : scene.shapes) pathcl_materials.insert(s.material);
  EXPECT_EQ(pathcl_materials.size(), used.size());
  // Instances: every primitive that several nodes place, with at least kMinInstancedTriangles triangles
  // in all its copies, is one instanced mesh (the engine's materials emit nothing).
  std::map<const json*, size_t> placements;
  for (const Placed& p : placed_primitives(g.doc)) placements[p.prim]++;
  size_t expected = 0;
  for (const auto& [prim, count] : placements) {
    const size_t triangles = g.doc["accessors"][(*prim)["indices"].get<size_t>()]["count"].get<size_t>() / 3;
    expected += count > 1 && count * triangles >= kMinInstancedTriangles ? 1 : 0;
  }
  EXPECT_GT(expected, 0u);
  EXPECT_EQ(scene.instanced_meshes.size(), expected);
}

// Cameras.gltf: the first camera (perspective, yfov 0.7) of the node at (0.5, 0.5, 3) looking along -z;
// the mesh turned by its node's rotation.
TEST(SampleModels, GltfCameraFromTheFile) {
  REQUIRE_MODELS();
  const std::string file = "glTF2/cameras/Cameras.gltf";
  const GltfFile g = read_gltf_file(model(file));
  const SceneDescription scene = load_scene(write_temp_file("camera.json", scene_placing(
      gltf_shape(file), R"({"from_gltf": ")" + model(file) + R"(", "width": 16, "height": 16})")));
  expect_gltf_scene(file, scene);
  const json& node = g.doc["nodes"][1];
  ASSERT_EQ(node["camera"], 0);
  const glm::dvec3 position(node["translation"][0].get<double>(), node["translation"][1].get<double>(),
                            node["translation"][2].get<double>());
  EXPECT_EQ(scene.camera.position, position);
  EXPECT_LT(glm::length(glm::normalize(scene.camera.look_at - position) - glm::dvec3(0, 0, -1)), 1e-12);
  EXPECT_NEAR(scene.camera.fov_y_degrees, g.doc["cameras"][0]["perspective"]["yfov"].get<double>() * 180 / M_PI, 1e-4);
}

// The broken and unsupported glTF files of the set: each is named with what is wrong, exit status 2. The
// Draco file is refused for its required extension, not for what tinygltf makes of its accessors without
// buffer views ("accessor[0] invalid bufferView").
TEST(SampleModels, BrokenAndUnsupportedGltfFilesAreNamed) {
  REQUIRE_MODELS();
  struct Case {
    std::string file, message;
  } cases[] = {
      {"glTF2/draco/2CylinderEngine.gltf", "requires the extension KHR_draco_mesh_compression, which pathcl does not support"},
      {"glTF2/BoxTextured-glTF-techniqueWebGL/BoxTextured.gltf", "requires the extension KHR_technique_webgl, which pathcl does not support"},
      {"glTF2/RecursiveNodes/RecursiveNodes.gltf", "nodes[0] is its own ancestor"},
      {"glTF2/MissingBin/BoxTextured.gltf", "buffers[0]: " + model("glTF2/MissingBin/BoxTextured0.bin") + ": cannot open the buffer file: no such file"},
      {"glTF2/TestNoRootNode/NoScene.gltf", "no scenes: nothing to place"},
      {"glTF2/IncorrectVertexArrays/Cube.gltf", "LINES is not supported"},
      {"glTF2/IndexOutOfRange/IndexOutOfRange.gltf", "meshes[0].primitives[0]: index "},
      {"glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb", "is not finite"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    expect_refused(gltf_shape(c.file), model(c.file), c.message);
  }
  // The index out of range is named against the POSITION accessor's count.
  const GltfFile g = read_gltf_file(model("glTF2/IndexOutOfRange/IndexOutOfRange.gltf"));
  const size_t vertices = g.doc["accessors"][g.doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<size_t>()]["count"];
  EXPECT_NE(scene_load_error(write_temp_file("range.json", scene_placing(gltf_shape("glTF2/IndexOutOfRange/IndexOutOfRange.gltf"))))
                .find("out of range (" + std::to_string(vertices) + " vertices)"),
            std::string::npos);
}

// OBJ files pathcl does not read, each named for what is wrong: UTF-16 text (by its byte order mark), a
// number that is none ("3.1+e2" on line 11 of number_formats.obj), points without faces.
TEST(SampleModels, ObjFilesPathclRefusesAreNamed) {
  REQUIRE_MODELS();
  auto shape = [](const std::string& file) { return R"({"type": "mesh", "file": ")" + model(file) + R"(", "material": "m"})"; };
  ASSERT_EQ(read_file(model("OBJ/box_UTF16BE.obj")).substr(0, 2), "\xfe\xff");
  expect_refused(shape("OBJ/box_UTF16BE.obj"), model("OBJ/box_UTF16BE.obj"), "the file is UTF-16 text, expected an OBJ file in ASCII or UTF-8");
  std::istringstream lines(read_file(model("OBJ/number_formats.obj")));
  std::string line;
  for (int i = 0; i < 11; ++i) std::getline(lines, line);
  ASSERT_NE(line.find("3.1+e2"), std::string::npos);
  expect_refused(shape("OBJ/number_formats.obj"), model("OBJ/number_formats.obj") + ":11", "expected 3 finite vertex coordinates");
  expect_refused(shape("OBJ/point_cloud.obj"), model("OBJ/point_cloud.obj"), "no faces");
}
