// Vertex colours (PLY red/green/blue, OBJ "v x y z r g b", inline "colors"; glTF COLOR_0 in gltf_test):
// read with the right encoding, kept with their corners through clean-up, triangulation and mirroring,
// and multiplying the material's colour on the device exactly as an analytic furnace predicts.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "kernels/shared/srgb_table.h"
#include "scene/texture_load.h"
#include "test_support.h"

namespace {

const float kSrgbTable[256] = PC_SRGB_TO_LINEAR_TABLE;

std::string camera_json(int width = 8, int height = 8) {
  return R"({"position": [0, 0, 5], "look_at": [0, 0, 0], "width": )" + std::to_string(width) +
         R"(, "height": )" + std::to_string(height) + "}";
}

SceneDescription load_shape(const std::string& shape) {
  return load_scene(write_temp_file("scene.json", R"({"camera": )" + camera_json() +
                                                      R"(, "materials": {"m": {"type": "diffuse"}}, "shapes": [)" + shape + "]}"));
}

// Every corner of every triangle has the colour of its vertex's position (`by_position`, exact).
void expect_colors_follow_positions(const TriangleMesh& mesh, const std::map<std::array<double, 3>, glm::vec3>& by_position) {
  ASSERT_EQ(mesh.colors.size(), mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 p = mesh.positions[mesh.triangles[t][k]];
      auto it = by_position.find({p.x, p.y, p.z});
      ASSERT_NE(it, by_position.end()) << p.x << " " << p.y << " " << p.z;
      EXPECT_EQ(mesh.colors[t][k], it->second) << "triangle " << t << " corner " << k;
    }
}

}  // namespace

// The host's sRGB decoding of vertex colours agrees with the 8-bit table the textures use.
TEST(VertexColors, SrgbDecodingMatchesTheTextureTable) {
  for (int v = 0; v < 256; ++v) EXPECT_NEAR(srgb_to_linear(v / 255.0), kSrgbTable[v], 2e-7 * kSrgbTable[v] + 1e-12) << v;
  EXPECT_EQ(srgb_to_linear(-1), 0.0f);
  EXPECT_EQ(srgb_to_linear(2), 1.0f);
  EXPECT_EQ(srgb_to_linear(NAN), 0.0f);
}

// PLY: 8-bit vertex colours through a quad's triangulation; float and 16-bit colours; face colours;
// vertex colours win over face colours.
TEST(VertexColors, PlyColorsInEveryEncoding) {
  const std::string header = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string quad_face = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string positions[4] = {"0 0 0", "1 0 0", "1 1 0", "0 1 0"};
  {
    std::string ply = header + "property uchar red\nproperty uchar green\nproperty uchar blue\n" + quad_face;
    const int bytes[4][3] = {{255, 0, 0}, {0, 128, 0}, {0, 0, 64}, {10, 20, 30}};
    std::map<std::array<double, 3>, glm::vec3> expected;
    for (int v = 0; v < 4; ++v) {
      ply += positions[v] + " " + std::to_string(bytes[v][0]) + " " + std::to_string(bytes[v][1]) + " " +
             std::to_string(bytes[v][2]) + "\n";
      expected[{double(v == 1 || v == 2), double(v >= 2), 0.0}] =
          glm::vec3(srgb_to_linear(bytes[v][0] / 255.0), srgb_to_linear(bytes[v][1] / 255.0), srgb_to_linear(bytes[v][2] / 255.0));
    }
    ply += "4 0 1 2 3\n";
    SceneDescription d = load_shape(R"({"type": "mesh", "file": ")" + write_temp_file("bytes.ply", ply) + R"(", "material": "m"})");
    expect_colors_follow_positions(d.shapes.at(0).mesh, expected);
  }
  {
    std::string ply = header + "property float red\nproperty float green\nproperty float blue\nproperty ushort alpha\n" +
                      "element face 2\nproperty list uchar int vertex_indices\nproperty ushort red\nproperty ushort green\nproperty ushort blue\nend_header\n";
    for (int v = 0; v < 4; ++v) ply += positions[v] + " 0.5 0.25 1 7\n";
    ply += "3 0 1 2 65535 0 0\n3 0 2 3 0 65535 0\n";
    SceneDescription d = load_shape(R"({"type": "mesh", "file": ")" + write_temp_file("floats.ply", ply) + R"(", "material": "m"})");
    const glm::vec3 c(srgb_to_linear(0.5), srgb_to_linear(0.25), 1.0f);
    for (const auto& corners : d.shapes.at(0).mesh.colors)
      for (const glm::vec3& v : corners) EXPECT_EQ(v, c);  // the vertices' colours, not the faces'
  }
  {
    std::string ply = header + "element face 2\nproperty list uchar int vertex_indices\nproperty ushort red\nproperty ushort green\nproperty ushort blue\nend_header\n";
    for (int v = 0; v < 4; ++v) ply += positions[v] + "\n";
    ply += "3 0 1 2 65535 0 0\n3 0 2 3 0 65535 0\n";
    SceneDescription d = load_shape(R"({"type": "mesh", "file": ")" + write_temp_file("faces.ply", ply) + R"(", "material": "m"})");
    const TriangleMesh& mesh = d.shapes.at(0).mesh;
    ASSERT_EQ(mesh.colors.size(), 2u);
    for (size_t t = 0; t < 2; ++t)
      for (const glm::vec3& v : mesh.colors[t])
        EXPECT_EQ(v, mesh.source_polygon[t] == 0 ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0)) << t;
  }
}

// OFF face colours: CGAL's reader reads past them without returning them, so they are named as ignored.
TEST(VertexColors, OffFaceColorsAreNamedAsIgnored) {
  const std::string off = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2 255 0 0\n3 0 2 3 0 128 0\n";
  const std::string path = write_temp_file("faces.off", off);
  SceneDescription d = load_shape(R"({"type": "mesh", "file": ")" + path + R"(", "material": "m"})");
  EXPECT_EQ(d.shapes.at(0).mesh.triangles.size(), 2u);
  EXPECT_EQ(std::count(d.warnings.begin(), d.warnings.end(),
                       path + ": face colours ignored (CGAL's OFF reader does not return them; a PLY file keeps them)"), 1);
  SceneDescription plain = load_shape(R"({"type": "mesh", "file": ")" +
                                      write_temp_file("plain.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n") +
                                      R"(", "material": "m"})");
  for (const std::string& w : plain.warnings) EXPECT_EQ(w.find("colours"), std::string::npos) << w;
}

// OBJ's colour extension (sRGB display values, as MeshLab writes them); a file where only some vertices
// have colours has none (no white fallback inventing them).
TEST(VertexColors, ObjColorExtension) {
  const std::string obj = "v 0 0 0 1 0 0\nv 1 0 0 0 0.5 0\nv 1 1 0 0 0 1\nv 0 1 0 0.2 0.2 0.2\nf 1 2 3 4\n";
  SceneDescription d = load_shape(R"({"type": "mesh", "file": ")" + write_temp_file("colors.obj", obj) + R"(", "material": "m"})");
  expect_colors_follow_positions(d.shapes.at(0).mesh,
                                 {{{0, 0, 0}, {1, 0, 0}},
                                  {{1, 0, 0}, {0, srgb_to_linear(0.5), 0}},
                                  {{1, 1, 0}, {0, 0, 1}},
                                  {{0, 1, 0}, glm::vec3(srgb_to_linear(0.2))}});
  const std::string partly = "v 0 0 0 1 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
  SceneDescription p = load_shape(R"({"type": "mesh", "file": ")" + write_temp_file("partly.obj", partly) + R"(", "material": "m"})");
  EXPECT_TRUE(p.shapes.at(0).mesh.colors.empty());
}

// Inline colours stay with their corners under a mirroring transform (which reverses the winding) and
// when an instance is flattened; bad values name their JSON place.
TEST(VertexColors, InlineColorsFollowMirroringAndInstances) {
  const std::string quad = R"("positions": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], "indices": [[0, 1, 2], [0, 2, 3]],
                              "colors": [[1, 0, 0], [0, 1, 0], [0, 0, 1], [0.5, 0.5, 0.5]], "material": "m")";
  const std::map<std::array<double, 3>, glm::vec3> mirrored = {
      {{0, 0, 0}, {1, 0, 0}}, {{-1, 0, 0}, {0, 1, 0}}, {{-1, 1, 0}, {0, 0, 1}}, {{0, 1, 0}, glm::vec3(0.5f)}};
  SceneDescription d = load_shape(R"({"type": "triangles", )" + quad + R"(, "transform": {"scale": [-1, 1, 1]}})");
  expect_colors_follow_positions(d.shapes.at(0).mesh, mirrored);
  EXPECT_TRUE(build_device_scene(d).features & kFeatureVertexColors);

  SceneDescription inst = load_shape(R"({"type": "triangles", )" + quad + R"(, "instance": true, "transform": {"scale": [-1, 1, 1]}},
                                        {"type": "triangles", )" + quad + R"(, "instance": true, "transform": {"translate": [0, 0, -3]}})");
  ASSERT_EQ(inst.instanced_meshes.size(), 1u);
  expect_colors_follow_positions(flattened_shape(inst, inst.shapes.at(0)).mesh, mirrored);

  SceneDescription plain = load_shape(R"({"type": "triangles", )" + quad + R"(, "vertex_colors": false})");
  EXPECT_TRUE(plain.shapes.at(0).mesh.colors.empty());
  EXPECT_FALSE(build_device_scene(plain).features & kFeatureVertexColors);

  auto error = [](const std::string& shape) {
    return scene_load_error(write_temp_file("bad.json", R"({"camera": )" + camera_json() +
                                                            R"(, "materials": {"m": {"type": "diffuse"}}, "shapes": [)" + shape + "]}"));
  };
  const std::string bright = error(R"({"type": "triangles", "positions": [[0, 0, 0], [1, 0, 0], [1, 1, 0]], "indices": [[0, 1, 2]],
                                       "colors": [[1, 0, 0], [0, 2, 0], [0, 0, 1]], "material": "m"})");
  EXPECT_NE(bright.find("shapes[0].colors[1]"), std::string::npos) << bright;
  EXPECT_NE(bright.find("[0, 1]"), std::string::npos) << bright;
  const std::string short_list = error(R"({"type": "triangles", "positions": [[0, 0, 0], [1, 0, 0], [1, 1, 0]], "indices": [[0, 1, 2]],
                                           "colors": [[1, 0, 0]], "material": "m"})");
  EXPECT_NE(short_list.find("shapes[0].colors"), std::string::npos) << short_list;
  EXPECT_NE(short_list.find("one [r, g, b] per position"), std::string::npos) << short_list;
}

// The device multiplies the material's colour by the interpolated vertex colour. A diffuse wall in a
// uniform environment of radiance 1, seen head-on, at max_depth 1 (light that scattered once): its
// radiance is its albedo exactly, here red (4 - x) / 8 across x in [-4, 4] (from vertex colours), green
// 0.5 (vertex colours) and blue 0.5 (the material's). A linear albedo averages over a pixel's symmetric
// filter to its value at the pixel's centre, which the pinhole maps linearly onto the wall.
TEST(VertexColors, DeviceMultipliesTheMaterialColor) {
  const int width = 16, height = 8;
  const double fov_y = 40, distance = 5;
  const std::string scene = R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y_degrees": 40, "width": 16, "height": 8},
    "materials": {"m": {"type": "diffuse", "reflectance": [1, 1, 0.5]}},
    "lights": [{"type": "environment", "radiance": [1, 1, 1]}],
    "shapes": [{"type": "triangles", "positions": [[-4, -4, 0], [4, -4, 0], [4, 4, 0], [-4, 4, 0]], "indices": [[0, 1, 2], [0, 2, 3]],
                "colors": [[1, 0.5, 1], [0, 0.5, 1], [0, 0.5, 1], [1, 0.5, 1]], "material": "m"}]})";
  DeviceScene device = load_device_scene(write_temp_file("wall.json", scene));
  ASSERT_TRUE(device.features & kFeatureVertexColors);
  RenderOptions opt;
  opt.spp = 256;
  opt.max_depth = 1;
  opt.seed = 5;
  RenderResult r = render(test_device(), device, opt);
  const double half_width = std::tan(fov_y * M_PI / 360) * distance * width / height;
  size_t outliers = 0;
  double sum = 0, expected_sum = 0, variance = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double wall_x = ((x + 0.5) / width * 2 - 1) * half_width;
      const double expected[3] = {(4 - wall_x) / 8, 0.5, 0.5};
      for (int c = 0; c < 3; ++c) {
        const size_t i = 3 * (size_t(y) * width + x) + c;
        const double se = std::sqrt(r.film.variance[i]);
        ASSERT_TRUE(std::isfinite(r.film.mean[i]));
        if (std::abs(r.film.mean[i] - expected[c]) > 4.5 * se + 1e-6) ++outliers;
        if (c == 0) {
          sum += r.film.mean[i];
          expected_sum += expected[c];
          variance += r.film.variance[i];
        }
      }
    }
  EXPECT_LE(outliers, 1u);  // 384 values at 4.5 standard errors: 0.003 expected by chance
  EXPECT_NEAR(sum, expected_sum, 4 * std::sqrt(variance));
  // The colours gathered for 8 and 16 lanes at once (kernels/surface.cl vertex_blend_lanes) are one lane's.
  RenderOptions one_lane = opt;
  one_lane.lanes = 1;
  const std::vector<float> reference = render(test_device(), device, one_lane).film.mean;
  for (uint32_t lanes : {8u, 16u}) {
    RenderOptions wide = opt;
    wide.lanes = lanes;
    const std::vector<float> pixels = render(test_device(), device, wide).film.mean;
    ASSERT_EQ(pixels.size(), reference.size());
    EXPECT_EQ(std::memcmp(pixels.data(), reference.data(), pixels.size() * sizeof(float)), 0) << lanes << " lanes";
  }
}
