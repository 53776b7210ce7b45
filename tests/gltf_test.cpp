// glTF 2.0 files (scene/gltf_load.cpp) as a "gltf" shape: files this test writes itself, as JSON with
// base64 data-URI buffers and as GLB with the binary chunk packed here, load with the right counts,
// transforms, materials, textures, lights and camera; a quad lit by a KHR_lights_punctual light renders
// the same bits as the scene written in pathcl's JSON; bad files are named and exit with status 2.
#include <cmath>
#include <cstring>
#include <filesystem>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "runtime/image_io.h"
#include "scene/scene_error.h"
#include "test_support.h"

using nlohmann::json;

namespace {

std::string base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t v = uint32_t(uint8_t(bytes[i])) << 16;
    if (i + 1 < bytes.size()) v |= uint32_t(uint8_t(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) v |= uint32_t(uint8_t(bytes[i + 2]));
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? table[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? table[v & 63] : '=';
  }
  return out;
}

template <class T>
void append(std::string& bytes, const std::vector<T>& values) {
  bytes.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

// A unit quad in z = 0 facing +z: positions, normals, uvs (glTF's, v down) and 6 uint16 indices, in one
// buffer of 4*12 + 4*12 + 4*8 + 12 = 140 bytes, with a buffer view and an accessor each.
struct QuadBuffer {
  std::string bytes;
  json views = json::array(), accessors = json::array();
};
QuadBuffer quad_buffer() {
  QuadBuffer q;
  auto add = [&](const std::string& data, int component_type, int count, const char* type) {
    q.views.push_back({{"buffer", 0}, {"byteOffset", q.bytes.size()}, {"byteLength", data.size()}});
    q.accessors.push_back({{"bufferView", q.views.size() - 1}, {"componentType", component_type}, {"count", count}, {"type", type}});
    q.bytes += data;
  };
  std::string p, n, t, i;
  append(p, std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
  append(n, std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1});
  append(t, std::vector<float>{0, 1, 1, 1, 1, 0, 0, 0});
  append(i, std::vector<uint16_t>{0, 1, 2, 0, 2, 3});
  add(p, 5126, 4, "VEC3");
  add(n, 5126, 4, "VEC3");
  add(t, 5126, 4, "VEC2");
  add(i, 5123, 6, "SCALAR");
  q.accessors[0]["min"] = {0, 0, 0};
  q.accessors[0]["max"] = {1, 1, 0};
  return q;
}

json quad_primitive(int material, bool with_normals = true) {
  json attributes = {{"POSITION", 0}, {"TEXCOORD_0", 2}};
  if (with_normals) attributes["NORMAL"] = 1;
  json p = {{"attributes", attributes}, {"indices", 3}};
  if (material >= 0) p["material"] = material;
  return p;
}

// A glTF document around the quad buffer, as a data URI.
json gltf_document(const QuadBuffer& q) {
  return {{"asset", {{"version", "2.0"}}},
          {"buffers", json::array({{{"byteLength", q.bytes.size()},
                                    {"uri", "data:application/octet-stream;base64," + base64(q.bytes)}}})},
          {"bufferViews", q.views},
          {"accessors", q.accessors}};
}

// GLB: header, the JSON chunk (padded with spaces) and the binary chunk (padded with zeros).
std::string pack_glb(json doc, const std::string& bin) {
  doc["buffers"] = json::array({{{"byteLength", bin.size()}}});
  std::string text = doc.dump();
  while (text.size() % 4) text += ' ';
  std::string body = bin;
  while (body.size() % 4) body += '\0';
  auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  uint32_t length = uint32_t(12 + 8 + text.size() + 8 + body.size());
  return "glTF" + u32(2) + u32(length) + u32(uint32_t(text.size())) + "JSON" + text + u32(uint32_t(body.size())) +
         "BIN" + std::string(1, '\0') + body;
}

std::string scene_json(const std::string& shapes, const std::string& camera = "") {
  return R"({"camera": )" +
         (camera.empty() ? R"({"position": [0, 0, 5], "look_at": [0, 0, 0], "width": 16, "height": 16})" : camera) +
         R"(, "materials": {}, "shapes": [)" + shapes + "]}";
}

bool has_position(const TriangleMesh& mesh, glm::dvec3 p) {
  for (const glm::dvec3& q : mesh.positions)
    if (glm::length(q - p) < 1e-9) return true;
  return false;
}

std::string load_error(const std::string& path) { return scene_load_error(path); }

// The hierarchy of HierarchyAndTransforms: a TRS parent (translate, 90 degrees about y, scale 2) with a
// matrix child (translate z by 1) placing the quad, and a second root placing the same mesh untouched.
json hierarchy_document(const QuadBuffer& q) {
  json doc = gltf_document(q);
  doc["meshes"] = json::array({{{"primitives", json::array({quad_primitive(-1)})}}});
  const double h = std::sqrt(0.5);
  doc["nodes"] = json::array({
      {{"translation", {1, 2, 3}}, {"rotation", {0, h, 0, h}}, {"scale", {2, 2, 2}}, {"children", {1}}},
      {{"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1}}, {"mesh", 0}},
      {{"mesh", 0}},
  });
  doc["scenes"] = json::array({{{"nodes", {0, 2}}}});
  return doc;
}

}  // namespace

TEST(Gltf, HierarchyAndTransforms) {
  write_temp_file("hierarchy.gltf", hierarchy_document(quad_buffer()).dump());
  const std::string path = write_temp_file(
      "hierarchy.json", scene_json(R"({"type": "gltf", "file": "hierarchy.gltf", "transform": {"translate": [10, 0, 0]}, "instance": true})"));
  SceneDescription scene = load_scene(path);
  // By default two small copies stay copies (scene_description.h, kMinInstancedTriangles).
  SceneDescription copies = load_scene(write_temp_file(
      "copies.json", scene_json(R"({"type": "gltf", "file": "hierarchy.gltf", "transform": {"translate": [10, 0, 0]}})")));
  ASSERT_EQ(copies.shapes.size(), 2u);
  EXPECT_TRUE(copies.instanced_meshes.empty());
  EXPECT_EQ(copies.shapes[0].mesh.triangles.size(), 2u);
  EXPECT_EQ(copies.shapes[1].mesh.positions, flattened_shape(scene, scene.shapes[1]).mesh.positions);
  // Asked for, the two nodes placing mesh 0 make one instanced mesh, in its own coordinates, placed twice.
  ASSERT_EQ(scene.shapes.size(), 2u);
  ASSERT_EQ(scene.instanced_meshes.size(), 1u);
  EXPECT_EQ(scene.shapes[0].instance_of, 0u);
  EXPECT_EQ(scene.shapes[1].instance_of, 0u);
  EXPECT_TRUE(scene.shapes[0].mesh.triangles.empty());
  EXPECT_EQ(scene.instanced_meshes[0].mesh.triangles.size(), 2u);
  const TriangleMesh child = flattened_shape(scene, scene.shapes[0]).mesh;
  const TriangleMesh root = flattened_shape(scene, scene.shapes[1]).mesh;
  EXPECT_EQ(child.triangles.size(), 2u);
  // p -> child (z + 1) -> scale 2 -> rotate 90 degrees about y ((x, y, z) -> (z, y, -x)) -> translate
  // (1, 2, 3) -> the shape's translate (10, 0, 0).
  auto placed = [](glm::dvec3 p) {
    p.z += 1;
    p *= 2;
    p = glm::dvec3(p.z, p.y, -p.x);
    return p + glm::dvec3(11, 2, 3);
  };
  for (glm::dvec3 p : {glm::dvec3(0, 0, 0), glm::dvec3(1, 0, 0), glm::dvec3(1, 1, 0), glm::dvec3(0, 1, 0)}) {
    EXPECT_TRUE(has_position(child, placed(p))) << p.x << " " << p.y;
    EXPECT_TRUE(has_position(root, p + glm::dvec3(10, 0, 0))) << p.x << " " << p.y;
  }
  // The normal +z turns with the rotation to +x; shading normals per corner.
  ASSERT_EQ(child.normals.size(), 2u);
  for (const auto& corners : child.normals)
    for (const glm::vec3& n : corners) EXPECT_LT(glm::length(n - glm::vec3(1, 0, 0)), 1e-6f);
  // uvs: glTF's v runs down, pathcl's up: the corner at glTF uv (0, 1) (position 0) has (0, 0).
  ASSERT_EQ(child.uvs.size(), 2u);
  for (size_t t = 0; t < 2; ++t)
    for (int k = 0; k < 3; ++k)
      if (glm::length(child.positions[child.triangles[t][k]] - placed(glm::dvec3(0))) < 1e-9) {
        EXPECT_EQ(child.uvs[t][k], glm::vec2(0, 0));
      }
  // No material: glTF's default one (white, metallic 1, roughness 1).
  EXPECT_EQ(scene.materials[scene.shapes[0].material].type_id, uint32_t(PC_MAT_ROUGH_CONDUCTOR));
}

TEST(Gltf, MaterialMapping) {
  QuadBuffer q = quad_buffer();
  json doc = gltf_document(q);
  doc["materials"] = json::array({
      {{"pbrMetallicRoughness", {{"baseColorFactor", {0.8, 0.6, 0.4, 1}}, {"metallicFactor", 1}, {"roughnessFactor", 0.5}}}},
      {{"pbrMetallicRoughness", {{"baseColorFactor", {0.2, 0.3, 0.4, 1}}, {"metallicFactor", 0}, {"roughnessFactor", 0.3}}}},
      {{"pbrMetallicRoughness", {{"metallicFactor", 0}, {"roughnessFactor", 0}}},
       {"extensions", {{"KHR_materials_transmission", {{"transmissionFactor", 1}}}, {"KHR_materials_ior", {{"ior", 1.33}}}}}},
      {{"emissiveFactor", {1, 0.5, 0.25}}, {"doubleSided", true},
       {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4}}}}},
       {"pbrMetallicRoughness", {{"metallicFactor", 0}}}},
      {{"pbrMetallicRoughness", {{"baseColorFactor", {0.9, 0.9, 0.9, 1}}, {"metallicFactor", 1}, {"roughnessFactor", 0}}}},
  });
  json primitives = json::array();
  for (int m = 0; m < 5; ++m) primitives.push_back(quad_primitive(m));
  doc["meshes"] = json::array({{{"primitives", primitives}}});
  doc["nodes"] = json::array({{{"mesh", 0}}});
  doc["scenes"] = json::array({{{"nodes", {0}}}});
  doc["extensionsUsed"] = {"KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_emissive_strength"};
  write_temp_file("materials.gltf", doc.dump());
  SceneDescription scene = load_scene(write_temp_file("materials.json", scene_json(R"({"type": "gltf", "file": "materials.gltf"})")));
  ASSERT_EQ(scene.shapes.size(), 5u);
  auto material = [&](size_t shape) { return scene.materials[scene.shapes[shape].material]; };
  // metallic >= 0.5: rough_conductor reflecting baseColor at normal incidence, alpha = roughness^2.
  EXPECT_EQ(material(0).type_id, uint32_t(PC_MAT_ROUGH_CONDUCTOR));
  EXPECT_FLOAT_EQ(material(0).alpha, 0.25f);
  EXPECT_FLOAT_EQ(material(0).k.x, 2 * std::sqrt(0.8f / 0.2f));
  EXPECT_EQ(material(0).specular, glm::vec3(1));
  // metallic < 0.5: plastic (glTF's dielectric F0 of 0.04 is ior 1.5).
  EXPECT_EQ(material(1).type_id, uint32_t(PC_MAT_PLASTIC));
  EXPECT_EQ(material(1).color, glm::vec3(0.2f, 0.3f, 0.4f));
  EXPECT_FLOAT_EQ(material(1).ior, 1.5f);
  EXPECT_FLOAT_EQ(material(1).alpha, float(0.3 * 0.3));
  // KHR_materials_transmission: dielectric with KHR_materials_ior's index.
  EXPECT_EQ(material(2).type_id, uint32_t(PC_MAT_DIELECTRIC));
  EXPECT_FLOAT_EQ(material(2).ior, 1.33f);
  // emissiveFactor times KHR_materials_emissive_strength; doubleSided emits from both sides.
  EXPECT_EQ(scene.shapes[3].emission, glm::vec3(4, 2, 1));
  EXPECT_TRUE(scene.shapes[3].two_sided);
  EXPECT_FALSE(scene.shapes[0].two_sided);
  EXPECT_EQ(scene.shapes[0].emission, glm::vec3(0));
  // A smooth metal is a mirror.
  EXPECT_EQ(material(4).type_id, uint32_t(PC_MAT_MIRROR));
  EXPECT_EQ(material(4).color, glm::vec3(0.9f));
}

TEST(Gltf, TexturesEmbeddedExternalAndInGlb) {
  // A 2x1 PNG: red, then blue.
  const std::string png_path = write_temp_png("tex.png", 2, 1, {255, 0, 0, 0, 0, 255});
  const std::string png = read_text_file(png_path);
  QuadBuffer q = quad_buffer();
  json doc = gltf_document(q);
  doc["materials"] = json::array({
      {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"baseColorFactor", {1, 0.5, 1, 1}}, {"metallicFactor", 0}}}}});
  doc["textures"] = json::array({{{"source", 0}, {"sampler", 0}}});
  doc["samplers"] = json::array({{{"wrapS", 33071}, {"wrapT", 33071}}});
  doc["meshes"] = json::array({{{"primitives", json::array({quad_primitive(0)})}}});
  doc["nodes"] = json::array({{{"mesh", 0}}});
  doc["scenes"] = json::array({{{"nodes", {0}}}});

  auto check = [&](const std::string& file) {
    SceneDescription scene = load_scene(write_temp_file(file + ".json", scene_json(R"({"type": "gltf", "file": ")" + file + "\"}")));
    ASSERT_EQ(scene.shapes.size(), 1u) << file;
    const MaterialDesc& m = scene.materials[scene.shapes[0].material];
    ASSERT_NE(m.color_texture, PC_INVALID) << file;
    EXPECT_EQ(m.color, glm::vec3(1, 0.5f, 1)) << file;  // the factor multiplies the texture
    const TextureImage& t = scene.textures[m.color_texture];
    EXPECT_EQ(t.width, 2u);
    EXPECT_EQ(t.height, 1u);
    EXPECT_EQ(t.wrap, uint32_t(PC_WRAP_CLAMP));
    EXPECT_EQ(t.format, uint32_t(PC_TEXELS_SRGB8));
    EXPECT_EQ(t.words[0] & 0xffffff, 0x0000ffu) << file;  // red (R in the low byte)
    EXPECT_EQ(t.words[1] & 0xffffff, 0xff0000u) << file;  // blue
  };
  doc["images"] = json::array({{{"uri", "tex.png"}}});
  write_temp_file("external.gltf", doc.dump());
  check("external.gltf");
  doc["images"] = json::array({{{"uri", "data:image/png;base64," + base64(png)}}});
  write_temp_file("embedded.gltf", doc.dump());
  check("embedded.gltf");
  // GLB: the buffer in the binary chunk, the image in a buffer view after the quad's data.
  json glb = doc;
  glb["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", q.bytes.size()}, {"byteLength", png.size()}});
  glb["images"] = json::array({{{"bufferView", glb["bufferViews"].size() - 1}, {"mimeType", "image/png"}}});
  write_temp_file("packed.glb", pack_glb(glb, q.bytes + png));
  check("packed.glb");
}

TEST(Gltf, LightsAndCamera) {
  QuadBuffer q = quad_buffer();
  json doc = gltf_document(q);
  doc["meshes"] = json::array({{{"primitives", json::array({quad_primitive(-1)})}}});
  const double h = std::sqrt(0.5);
  doc["extensionsUsed"] = {"KHR_lights_punctual"};
  doc["extensions"] = {{"KHR_lights_punctual", {{"lights", json::array({
      {{"type", "point"}, {"color", {1, 0.5, 0.5}}, {"intensity", 5}},
      {{"type", "spot"}, {"intensity", 2}, {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.5}}}},
      {{"type", "directional"}, {"intensity", 3}},
  })}}}};
  doc["cameras"] = json::array({{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}, {"aspectRatio", 1.0}}}}});
  doc["nodes"] = json::array({
      {{"mesh", 0}},
      {{"translation", {0, 3, 0}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}},
      // -90 degrees about x: the spot's -z turns to -y.
      {{"translation", {1, 4, 0}}, {"rotation", {-h, 0, 0, h}}, {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}},
      {{"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}},
      {{"translation", {0, 0.5, 4}}, {"camera", 0}},
  });
  doc["scenes"] = json::array({{{"nodes", {0, 1, 2, 3, 4}}}});
  doc["scene"] = 0;
  write_temp_file("lights.gltf", doc.dump());
  SceneDescription scene = load_scene(write_temp_file(
      "lights.json",
      scene_json(R"({"type": "gltf", "file": "lights.gltf", "transform": {"translate": [0, 0, -1]}})",
                 R"({"from_gltf": "lights.gltf", "transform": {"translate": [0, 0, -1]}, "width": 32, "height": 32})")));
  ASSERT_EQ(scene.lights.size(), 3u);
  const LightDesc& point = scene.lights[0];
  EXPECT_EQ(point.type, uint32_t(PC_LIGHT_POINT));
  EXPECT_EQ(point.emission, glm::vec3(5, 2.5f, 2.5f));  // candela: pathcl's intensity
  EXPECT_EQ(point.position, glm::dvec3(0, 3, -1));
  const LightDesc& spot = scene.lights[1];
  EXPECT_EQ(spot.type, uint32_t(PC_LIGHT_SPOT));
  EXPECT_LT(glm::length(spot.direction - glm::vec3(0, -1, 0)), 1e-6f);
  EXPECT_LT(glm::length(spot.position - glm::dvec3(1, 4, -1)), 1e-12);
  EXPECT_FLOAT_EQ(spot.cos_inner, std::cos(0.2f));
  EXPECT_FLOAT_EQ(spot.cos_outer, std::cos(0.5f));
  const LightDesc& sun = scene.lights[2];
  EXPECT_EQ(sun.type, uint32_t(PC_LIGHT_DIRECTIONAL));
  EXPECT_EQ(sun.emission, glm::vec3(3));  // lux: pathcl's irradiance
  EXPECT_EQ(sun.direction, glm::vec3(0, 0, -1));
  // The camera of node 4, moved by the camera's transform: looking along -z with +y up.
  EXPECT_EQ(scene.camera.position, glm::dvec3(0, 0.5, 3));
  EXPECT_LT(glm::length(scene.camera.look_at - glm::dvec3(0, 0.5, 2)), 1e-12);
  EXPECT_EQ(scene.camera.up, glm::dvec3(0, 1, 0));
  EXPECT_FLOAT_EQ(scene.camera.fov_y_degrees, float(0.8 * 180 / M_PI));
  EXPECT_EQ(scene.camera.width, 32u);
}

// The same lit quad as a glTF file (plastic from metallic 0, a KHR_lights_punctual point light) and as
// pathcl's JSON renders the same bits: the loader must produce the same triangles, material and light.
TEST(Gltf, RenderMatchesTheSameSceneInPathclJson) {
  QuadBuffer q = quad_buffer();
  json doc = gltf_document(q);
  doc["materials"] = json::array({
      {{"pbrMetallicRoughness", {{"baseColorFactor", {0.8, 0.5, 0.25, 1}}, {"metallicFactor", 0}, {"roughnessFactor", 0.5}}}}});
  doc["meshes"] = json::array({{{"primitives", json::array({quad_primitive(0, false)})}}});
  doc["extensionsUsed"] = {"KHR_lights_punctual"};
  doc["extensions"] = {{"KHR_lights_punctual", {{"lights", json::array({{{"type", "point"}, {"intensity", 3}}})}}}};
  doc["nodes"] = json::array({{{"mesh", 0}, {"translation", {-0.5, -0.5, 0}}}, {{"translation", {0, 1, 1}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}}});
  doc["scenes"] = json::array({{{"nodes", {0, 1}}}});
  write_temp_file("lit.gltf", doc.dump());
  const std::string camera = R"({"position": [0, 0, 2], "look_at": [0, 0, 0], "width": 24, "height": 24})";
  const std::string render = R"(, "render": {"spp": 16, "max_depth": 3, "seed": 7})";
  const std::string gltf_scene = write_temp_file(
      "lit-gltf.json", R"({"camera": )" + camera + R"(, "materials": {}, "shapes": [{"type": "gltf", "file": "lit.gltf"}])" + render + "}");
  const std::string json_scene = write_temp_file(
      "lit-pathcl.json",
      R"({"camera": )" + camera +
          R"(, "materials": {"m": {"type": "plastic", "diffuse": [0.8, 0.5, 0.25], "ior": 1.5, "roughness": 0.5}},
          "shapes": [{"type": "triangles", "material": "m", "positions": [[-0.5, -0.5, 0], [0.5, -0.5, 0], [0.5, 0.5, 0], [-0.5, 0.5, 0]],
                      "indices": [[0, 1, 2], [0, 2, 3]]}],
          "lights": [{"type": "point", "position": [0, 1, 1], "intensity": [3, 3, 3]}])" + render + "}");
  const std::string a = temp_dir() + "/lit-gltf.exr", b = temp_dir() + "/lit-pathcl.exr";
  std::string err;
  ASSERT_EQ(run_pathcl("render " + gltf_scene + " -q -o " + a, &err), 0) << err;
  ASSERT_EQ(run_pathcl("render " + json_scene + " -q -o " + b, &err), 0) << err;
  Image ia = read_exr(a), ib = read_exr(b);
  ASSERT_EQ(ia.rgb.size(), ib.rgb.size());
  double sum = 0;
  for (float v : ia.rgb) sum += v;
  EXPECT_GT(sum, 0);  // lit, not black
  EXPECT_EQ(std::memcmp(ia.rgb.data(), ib.rgb.data(), ia.rgb.size() * sizeof(float)), 0);
}

// Bad files: each names the file and what is wrong; `pathcl info` exits with status 2.
TEST(Gltf, BadFilesAreNamedAndExitWithStatus2) {
  QuadBuffer q = quad_buffer();
  json good = gltf_document(q);
  good["meshes"] = json::array({{{"primitives", json::array({quad_primitive(-1)})}}});
  good["nodes"] = json::array({{{"mesh", 0}}});
  good["scenes"] = json::array({{{"nodes", {0}}}});
  const std::string glb = pack_glb(good, q.bytes);

  json required = good;
  required["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  required["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  json missing_buffer = good;
  missing_buffer["buffers"][0]["uri"] = "missing.bin";
  json accessor_out_of_range = good;
  accessor_out_of_range["accessors"][0]["count"] = 40;
  json lines = good;
  lines["meshes"][0]["primitives"][0]["mode"] = 1;
  json index_out_of_range = good;
  // Indices read from the positions from the second vertex on: 1.0f is 0x3f800000, uint16 0 then 16256.
  index_out_of_range["accessors"][3]["bufferView"] = 0;
  index_out_of_range["accessors"][3]["byteOffset"] = 12;
  json cycle = good;
  cycle["nodes"] = json::array({{{"mesh", 0}, {"children", {1}}}, {{"children", {0}}}});

  struct Case {
    const char* file;
    std::string content, message;
  };
  const std::vector<Case> cases = {
      {"truncated.glb", glb.substr(0, glb.size() / 2), "truncated GLB file: its header says " + std::to_string(glb.size())},
      {"broken.gltf", good.dump().substr(0, 40), "broken.gltf:1:41: malformed JSON: syntax error"},
      {"draco.gltf", required.dump(), "requires the extension KHR_draco_mesh_compression, which pathcl does not support"},
      {"nobuffer.gltf", missing_buffer.dump(), "buffers[0]: " + temp_dir() + "/missing.bin: cannot open the buffer file: no such file"},
      {"accessor.gltf", accessor_out_of_range.dump(), "accessors[0] (POSITION of nodes[0] meshes[0].primitives[0]): 40 elements from byte 0 reach beyond the end of bufferViews[0] (48 bytes)"},
      {"lines.gltf", lines.dump(), "nodes[0] meshes[0].primitives[0]: LINES is not supported"},
      {"index.gltf", index_out_of_range.dump(), "nodes[0] meshes[0].primitives[0]: index 16256 out of range (4 vertices)"},
      {"cycle.gltf", cycle.dump(), "nodes[0] is its own ancestor"},
      {"lfs.glb", "version https://git-lfs.github.com/spec/v1\noid sha256:0123\nsize 4096\n", "looks like a Git LFS pointer"},
  };
  for (const Case& c : cases) {
    const std::string file = write_temp_file(c.file, c.content);
    const std::string scene = write_temp_file(std::string(c.file) + ".json", scene_json(R"({"type": "gltf", "file": ")" + std::string(c.file) + "\"}"));
    const std::string message = load_error(scene);
    // FILE: shapes[0].file: GLTF-FILE[:LINE:COLUMN]: what is wrong.
    EXPECT_EQ(message.rfind(scene + ": shapes[0].file: " + file + (c.file == std::string("broken.gltf") ? ":1:41: " : ": "), 0), 0u) << c.file << ": " << message;
    EXPECT_NE(message.find(c.message), std::string::npos) << c.file << ": " << message;
    std::string err;
    EXPECT_EQ(run_pathcl("info " + scene, &err), 2) << c.file << ": " << err;
    EXPECT_NE(err.find(c.message), std::string::npos) << c.file << ": " << err;
  }
  // A glTF file named as a mesh is pointed to its shape type.
  write_temp_file("good.glb", glb);
  EXPECT_NE(load_error(write_temp_file("as-mesh.json", R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
      "materials": {"m": {"type": "diffuse"}}, "shapes": [{"type": "mesh", "file": "good.glb", "material": "m"}]})"))
                .find("good.glb: a glTF file is placed by a shape of its own"),
            std::string::npos);
}

// An emissive texture is taken per triangle at its uv centroid: the quad's first triangle has its centroid
// at u = 2/3 (the blue texel of a red | blue image), the second at u = 1/3 (red).
TEST(Gltf, EmissiveTexturePerTriangle) {
  write_temp_png("glow.png", 2, 1, {255, 0, 0, 0, 0, 255});
  json doc = gltf_document(quad_buffer());
  doc["materials"] = json::array({{{"emissiveFactor", {2, 2, 2}}, {"emissiveTexture", {{"index", 0}}}, {"pbrMetallicRoughness", {{"metallicFactor", 0}}}}});
  doc["textures"] = json::array({{{"source", 0}}});
  doc["images"] = json::array({{{"uri", "glow.png"}}});
  doc["meshes"] = json::array({{{"primitives", json::array({quad_primitive(0)})}}});
  doc["nodes"] = json::array({{{"mesh", 0}}});
  doc["scenes"] = json::array({{{"nodes", {0}}}});
  write_temp_file("glow.gltf", doc.dump());
  SceneDescription scene = load_scene(write_temp_file("glow.json", scene_json(R"({"type": "gltf", "file": "glow.gltf"})")));
  ASSERT_EQ(scene.shapes.size(), 1u);
  ASSERT_EQ(scene.shapes[0].triangle_emission.size(), 2u);
  EXPECT_EQ(scene.shapes[0].triangle_emission[0], glm::vec3(0, 0, 2));
  EXPECT_EQ(scene.shapes[0].triangle_emission[1], glm::vec3(2, 0, 0));
}

// alphaMode: BLEND makes the base colour's alpha (factor times texture) the opacity; MASK thresholds it at
// alphaCutoff, texel by texel; OPAQUE ignores it (scene/gltf_load.cpp, kernels/cutout.cl).
TEST(Gltf, AlphaModesBecomeCutOuts) {
  // A 2x1 RGBA PNG: alpha 64 and 200.
  const std::string png_path = write_temp_png("alpha.png", 2, 1, {255, 255, 255, 64, 255, 255, 255, 200});
  QuadBuffer q = quad_buffer();
  json doc = gltf_document(q);
  auto material = [](const char* mode, bool textured, double factor) {
    json pbr = {{"baseColorFactor", {1, 1, 1, factor}}, {"metallicFactor", 0}};
    if (textured) pbr["baseColorTexture"] = {{"index", 0}};
    return json{{"pbrMetallicRoughness", pbr}, {"alphaMode", mode}, {"alphaCutoff", 0.4}};
  };
  doc["materials"] = json::array({material("BLEND", false, 0.3), material("MASK", false, 0.3), material("OPAQUE", true, 0.3),
                                  material("BLEND", true, 0.5), material("MASK", true, 1.0)});
  doc["textures"] = json::array({{{"source", 0}}});
  doc["images"] = json::array({{{"uri", "alpha.png"}}});
  json primitives = json::array();
  for (int m = 0; m < 5; ++m) primitives.push_back(quad_primitive(m));
  doc["meshes"] = json::array();
  doc["nodes"] = json::array();
  for (int m = 0; m < 5; ++m) {
    doc["meshes"].push_back({{"primitives", json::array({quad_primitive(m)})}});
    doc["nodes"].push_back({{"mesh", m}, {"translation", {2 * m, 0, 0}}});
  }
  doc["scenes"] = json::array({{{"nodes", {0, 1, 2, 3, 4}}}});
  write_temp_file("alpha.gltf", doc.dump());
  SceneDescription scene = load_scene(write_temp_file("alpha.json", scene_json(R"({"type": "gltf", "file": "alpha.gltf"})")));
  ASSERT_EQ(scene.shapes.size(), 5u);
  auto m = [&](int i) { return scene.materials[scene.shapes[size_t(i)].material]; };
  EXPECT_FLOAT_EQ(m(0).opacity, 0.3f);  // BLEND without a texture: the factor
  EXPECT_EQ(m(0).opacity_texture, PC_INVALID);
  EXPECT_EQ(m(1).opacity, 0.0f);  // MASK: 0.3 < 0.4
  EXPECT_EQ(m(2).opacity, 1.0f);  // OPAQUE
  EXPECT_EQ(m(2).opacity_texture, PC_INVALID);
  // BLEND with the texture: alpha times 0.5 in every byte: round(64 * 0.5) = 32, 100.
  ASSERT_NE(m(3).opacity_texture, PC_INVALID);
  const TextureImage& blend = scene.textures[m(3).opacity_texture];
  EXPECT_EQ(blend.words[0], 0x20202020u);
  EXPECT_EQ(blend.words[1], 0x64646464u);
  // MASK with the texture at 0.4: 64 / 255 = 0.25 is cut, 200 / 255 = 0.78 stays.
  ASSERT_NE(m(4).opacity_texture, PC_INVALID);
  const TextureImage& mask = scene.textures[m(4).opacity_texture];
  EXPECT_EQ(mask.words[0], 0u);
  EXPECT_EQ(mask.words[1], 0xffffffffu);
  DeviceScene d = build_device_scene(scene);
  EXPECT_TRUE(d.features & kFeatureCutouts);
}

// COLOR_0 (normalized unsigned bytes, VEC4) multiplies the base colour: each corner keeps its vertex's
// colour, linear as glTF says (no sRGB decoding), the alpha not read; "vertex_colors": false drops it.
TEST(Gltf, VertexColorsFollowTheirVertices) {
  QuadBuffer q = quad_buffer();
  std::string c;
  const std::vector<uint8_t> rgba = {255, 0, 0, 10, 0, 255, 0, 20, 0, 0, 255, 30, 51, 102, 204, 40};
  append(c, rgba);
  q.views.push_back({{"buffer", 0}, {"byteOffset", q.bytes.size()}, {"byteLength", c.size()}});
  q.accessors.push_back({{"bufferView", q.views.size() - 1}, {"componentType", 5121}, {"normalized", true}, {"count", 4}, {"type", "VEC4"}});
  q.bytes += c;
  json doc = gltf_document(q);
  json primitive = quad_primitive(-1);
  primitive["attributes"]["COLOR_0"] = 4;
  doc["meshes"] = json::array({{{"primitives", json::array({primitive})}}});
  doc["nodes"] = json::array({{{"mesh", 0}}});
  doc["scenes"] = json::array({{{"nodes", {0}}}});
  const std::string file = write_temp_file("colors.gltf", doc.dump());
  const glm::dvec3 corners[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  SceneDescription d = load_scene(write_temp_file("colors.json", scene_json(R"({"type": "gltf", "file": ")" + file + R"("})")));
  const TriangleMesh& mesh = d.shapes.at(0).mesh;
  ASSERT_EQ(mesh.triangles.size(), 2u);
  ASSERT_EQ(mesh.colors.size(), 2u);
  for (size_t t = 0; t < 2; ++t)
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 p = mesh.positions[mesh.triangles[t][k]];
      int v = 0;
      while (v < 4 && glm::length(corners[v] - p) > 1e-9) ++v;
      ASSERT_LT(v, 4);
      for (int ch = 0; ch < 3; ++ch) EXPECT_FLOAT_EQ(mesh.colors[t][k][ch], rgba[4 * v + ch] / 255.0f) << t << " " << k;
    }
  DeviceScene device = build_device_scene(d);
  EXPECT_TRUE(device.features & kFeatureVertexColors);
  SceneDescription plain = load_scene(write_temp_file(
      "plain.json", scene_json(R"({"type": "gltf", "file": ")" + file + R"(", "vertex_colors": false})")));
  EXPECT_TRUE(plain.shapes.at(0).mesh.colors.empty());
  EXPECT_FALSE(build_device_scene(plain).features & kFeatureVertexColors);
}

// A file that places no triangles says so (tinygltf reads some malformed files as an empty scene).
TEST(Gltf, AFileThatPlacesNoTrianglesWarns) {
  json doc = {{"asset", {{"version", "2.0"}}}, {"scenes", json::array({json::object()})}};
  const std::string file = write_temp_file("empty.gltf", doc.dump());
  SceneDescription d = load_scene(write_temp_file(
      "empty.json", R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "width": 8, "height": 8}, "materials": {"m": {"type": "diffuse"}},
                       "shapes": [{"type": "gltf", "file": ")" + file + R"("}, {"type": "sphere", "radius": 1, "material": "m", "emission": [1, 1, 1]}]})"));
  bool warned = false;
  for (const std::string& w : d.warnings) warned = warned || w.find("places no triangles") != std::string::npos;
  EXPECT_TRUE(warned);
}
