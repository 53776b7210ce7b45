// The bundled example scene, scenes/example.json: a glTF model, a PLY scan and a Radiance HDR sky, whose
// files scripts/make-example-scene writes. The test writes them afresh into its own directory beside a copy
// of the scene file, loads it with the counts the files themselves state (read here from the GLB's JSON,
// the PLY header, the HDR header and the scene JSON), and renders it small with `pathcl render`: a finite,
// lit image.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "runtime/image_io.h"
#include "test_support.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The example's directory in temp_dir(), written once per process: {dir}/example.json (the bundled scene,
// its film made `width` x `height` when given) and {dir}/example/ (the generator's files).
std::string example_dir() {
  static std::string dir;
  if (dir.empty()) {
    dir = temp_dir() + "/example-scene";
    fs::create_directories(dir);
    const std::string command = std::string(PATHCL_PYTHON) + " " + PATHCL_SOURCE_DIR + "/scripts/make-example-scene " + dir + "/example";
    if (std::system(command.c_str()) != 0) throw std::runtime_error("failed: " + command);
  }
  return dir;
}

json bundled_scene() { return json::parse(read_bytes(std::string(PATHCL_SOURCE_DIR) + "/scenes/example.json")); }

std::string write_scene(const std::string& name, const json& scene) {
  const std::string path = example_dir() + "/" + name;
  std::ofstream(path) << scene.dump(2);
  return path;
}

// What the files say: triangles of each shape, materials, textures and lights.
struct Expected {
  size_t ground_triangles = 0, rock_triangles = 0, gltf_triangles = 0, gltf_primitives = 0;
  size_t gltf_materials = 0, gltf_images = 0;
  uint32_t sky_width = 0, sky_height = 0;
};

Expected expected_counts(const json& scene) {
  Expected e;
  const std::string dir = example_dir() + "/";
  for (const json& shape : scene["shapes"]) {
    const std::string type = shape["type"];
    if (type == "triangles") e.ground_triangles += shape["indices"].size();
    if (type == "mesh") {  // the PLY header's face count; the faces are triangles (checked below)
      const std::string ply = read_bytes(dir + shape["file"].get<std::string>());
      const size_t at = ply.find("element face ");
      EXPECT_NE(at, std::string::npos);
      e.rock_triangles = std::stoul(ply.substr(at + 13));
      EXPECT_NE(ply.find("property list uchar int vertex_indices"), std::string::npos);
      EXPECT_NE(ply.find("property float nx"), std::string::npos);  // a scan with vertex normals
      // Every face record (after the vertices) starts with its corner count, 3.
      const size_t body = ply.find("end_header\n") + 11;
      const size_t vertices = std::stoul(ply.substr(ply.find("element vertex ") + 15));
      EXPECT_EQ(ply.size(), body + vertices * 24 + e.rock_triangles * 13);
      size_t not_triangles = 0;
      for (size_t f = 0; f < e.rock_triangles && body + vertices * 24 + f * 13 < ply.size(); ++f)
        not_triangles += ply[body + vertices * 24 + f * 13] != 3;
      EXPECT_EQ(not_triangles, 0u);
    }
    if (type == "gltf") {  // the GLB's JSON chunk: the index counts of every primitive the scene's nodes place
      const std::string glb = read_bytes(dir + shape["file"].get<std::string>());
      EXPECT_EQ(glb.compare(0, 4, "glTF"), 0);
      uint32_t length;
      std::memcpy(&length, glb.data() + 12, 4);
      const json doc = json::parse(glb.substr(20, length));
      std::function<void(size_t)> visit = [&](size_t n) {
        const json& node = doc["nodes"][n];
        if (node.contains("mesh"))
          for (const json& p : doc["meshes"][node["mesh"].get<size_t>()]["primitives"]) {
            ++e.gltf_primitives;
            e.gltf_triangles += doc["accessors"][p["indices"].get<size_t>()]["count"].get<size_t>() / 3;
            EXPECT_EQ(p.value("mode", 4), 4);
          }
        for (const json& c : node.value("children", json::array())) visit(c.get<size_t>());
      };
      for (const json& n : doc["scenes"][doc.value("scene", 0)]["nodes"]) visit(n.get<size_t>());
      e.gltf_materials = doc["materials"].size();
      e.gltf_images = doc["images"].size();
      EXPECT_FALSE(doc.contains("extensions"));  // no KHR_lights_punctual
      for (const json& m : doc["materials"]) EXPECT_FALSE(m.contains("emissiveFactor"));  // and no emitters
      EXPECT_GT(doc["nodes"].size(), 1u);
    }
  }
  for (const json& light : scene["lights"]) {  // the HDR header's resolution line: -Y height +X width
    const std::string hdr = read_bytes(dir + light["file"].get<std::string>());
    EXPECT_EQ(hdr.compare(0, 11, "#?RADIANCE\n"), 0);
    std::istringstream resolution(hdr.substr(hdr.find("\n\n") + 2));
    std::string y, x;
    resolution >> y >> e.sky_height >> x >> e.sky_width;
    EXPECT_EQ(y + x, "-Y+X");
  }
  return e;
}

}  // namespace

TEST(ExampleScene, LoadsWithTheFilesCounts) {
  const json scene = bundled_scene();
  const Expected e = expected_counts(scene);
  ASSERT_GT(e.rock_triangles, 0u);
  ASSERT_GT(e.gltf_primitives, 1u);
  const SceneDescription d = load_scene(write_scene("example.json", scene));
  // The ground, the rock, then one shape per glTF primitive.
  ASSERT_EQ(d.shapes.size(), 2 + e.gltf_primitives);
  EXPECT_EQ(d.shapes[0].mesh.triangles.size(), e.ground_triangles);
  EXPECT_EQ(d.shapes[1].mesh.triangles.size(), e.rock_triangles);
  EXPECT_EQ(d.shapes[1].mesh.normals.size(), e.rock_triangles);  // the PLY's normals, per corner
  size_t gltf_triangles = 0;
  std::set<uint32_t> gltf_materials;
  for (size_t s = 2; s < d.shapes.size(); ++s) {
    gltf_triangles += d.shapes[s].mesh.triangles.size();
    gltf_materials.insert(d.shapes[s].material);
    EXPECT_NE(d.shapes[s].label.find("toy.glb"), std::string::npos) << d.shapes[s].label;
  }
  EXPECT_EQ(gltf_triangles, e.gltf_triangles);
  EXPECT_EQ(gltf_materials.size(), e.gltf_materials);
  EXPECT_EQ(d.materials.size(), scene["materials"].size() + e.gltf_materials);
  // Textures: the glTF's base colour image and the sky; the sky at the HDR's resolution, in floats.
  EXPECT_EQ(d.textures.size(), e.gltf_images + scene["lights"].size());
  ASSERT_EQ(d.lights.size(), 1u);
  EXPECT_EQ(d.lights[0].type, uint32_t(PC_LIGHT_ENVIRONMENT));
  ASSERT_LT(d.lights[0].texture, d.textures.size());
  const TextureImage& sky = d.textures[d.lights[0].texture];
  EXPECT_EQ(sky.width, e.sky_width);
  EXPECT_EQ(sky.height, e.sky_height);
  EXPECT_EQ(sky.format, uint32_t(PC_TEXELS_FLOAT));
  // The crate's texture is a base colour: some glTF material takes it.
  size_t textured = 0;
  for (uint32_t m : gltf_materials) textured += d.materials[m].color_texture != PC_INVALID;
  EXPECT_EQ(textured, e.gltf_images);
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
}

// `pathcl render` at 32 x 24 and 4 spp: the statistics count what the files hold, and the image is finite,
// non-negative and lit (every pixel sees the sky, the ground or an object under it).
TEST(ExampleScene, RendersFiniteAndLit) {
  json scene = bundled_scene();
  const Expected e = expected_counts(scene);
  scene["camera"]["width"] = 32;
  scene["camera"]["height"] = 24;
  const std::string path = write_scene("example-small.json", scene);
  const std::string exr = example_dir() + "/example.exr", stats_path = example_dir() + "/example.stats.json";
  std::string err;
  ASSERT_EQ(run_pathcl("render " + path + " -q --spp 4 -o " + exr + " --stats " + stats_path, &err), 0) << err;
  const json stats = json::parse(read_bytes(stats_path));
  EXPECT_EQ(stats["triangles"], e.ground_triangles + e.rock_triangles + e.gltf_triangles);
  EXPECT_EQ(stats["spheres"], 0);
  EXPECT_EQ(stats["lights"], 1);  // the environment: nothing in the files emits
  EXPECT_EQ(stats["nan_samples"], 0);
  EXPECT_EQ(stats["inf_samples"], 0);
  EXPECT_EQ(stats["negative_samples"], 0);
  const Image image = read_exr(exr);
  ASSERT_EQ(image.width, 32u);
  ASSERT_EQ(image.height, 24u);
  double sum = 0;
  size_t black = 0;
  for (size_t p = 0; p < image.rgb.size() / 3; ++p) {
    double pixel = 0;
    for (int c = 0; c < 3; ++c) {
      ASSERT_TRUE(std::isfinite(image.rgb[3 * p + c])) << p;
      ASSERT_GE(image.rgb[3 * p + c], 0.0f) << p;
      pixel += image.rgb[3 * p + c];
    }
    sum += pixel;
    black += pixel == 0;
  }
  EXPECT_GT(sum, 0);
  EXPECT_LT(black, image.rgb.size() / 3 / 10);  // under a sky almost every pixel gets some light
}
