// Scene files: every error names the file and the place; transforms and flags do what they say.
#include <cmath>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "scene/scene_error.h"
#include "test_support.h"

namespace {

std::string scenes() { return PATHCL_TEST_SCENES; }

// The message of the SceneError that loading `path` throws, or "" if it loads.
std::string load_error(const std::string& path) {
  try {
    load_scene(path);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

std::string scene_with_shape(const std::string& shape) {
  return R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
    "materials": {"m": {"type": "diffuse"}}, "shapes": [)" + shape + "]}";
}

}  // namespace

TEST(SceneLoad, ErrorsNameFileAndPlace) {
  EXPECT_NE(load_error(scenes() + "/bad-malformed.json").find("bad-malformed.json: malformed JSON"), std::string::npos);
  EXPECT_NE(load_error(scenes() + "/bad-malformed.json").find("line 5"), std::string::npos);
  EXPECT_NE(load_error(scenes() + "/bad-unknown-key.json").find("shapes[0]: unknown key \"colour\""), std::string::npos);
  EXPECT_NE(load_error(scenes() + "/bad-unknown-material.json").find("shapes[0].material: unknown material \"glas\""),
            std::string::npos);
  EXPECT_NE(load_error(scenes() + "/bad-missing-obj.json").find("does-not-exist.obj: cannot open"), std::string::npos);
  EXPECT_NE(load_error(scenes() + "/bad-face-index.json").find("bad-face-index.obj:7: face index 9 out of range"),
            std::string::npos);
  EXPECT_NE(load_error(scenes() + "/bad-nan-vertex.json").find("nan-vertex.obj:2:"), std::string::npos);
  EXPECT_NE(load_error(scenes() + "/bad-negative-spp.json").find("render.spp: expected an integer in [1,"),
            std::string::npos);
  EXPECT_NE(load_error(scenes() + "/no-such-scene.json").find("cannot open the scene file"), std::string::npos);
}

TEST(SceneLoad, WrongTypesAndValuesAreRejected) {
  struct Case {
    std::string shape, expected;
  } cases[] = {
      {R"({"type": "sphere", "radius": "1", "material": "m"})", "shapes[0].radius: expected a number"},
      {R"({"type": "sphere", "radius": -1, "material": "m"})", "shapes[0].radius: expected a number > 0"},
      {R"({"type": "sphere", "radius": 1, "material": "m", "center": [0, 1]})", "shapes[0].center: expected an array of 3"},
      {R"({"type": "cone", "material": "m"})", "shapes[0].type: unknown shape type \"cone\""},
      {R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,3]], "material": "m"})",
       "shapes[0].indices[0][2]: vertex index 3 out of range"},
      {R"({"type": "sphere", "radius": 1, "material": "m", "emission": [1, -1, 0]})",
       "shapes[0].emission: expected non-negative values"},
      {R"({"type": "sphere", "radius": 1, "material": "m", "transform": {"scale": [1, 2, 1]}})",
       "shapes[0].transform: a sphere allows only translation, rotation and uniform scale"},
      {R"({"type": "sphere", "radius": 1, "material": "m", "transform": {"skew": 1}})",
       "shapes[0].transform: unknown key \"skew\""},
  };
  for (const Case& c : cases) {
    std::string path = write_temp_file("case.json", scene_with_shape(c.shape));
    std::string error = load_error(path);
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.shape << "\n  gave: " << error;
    EXPECT_EQ(error.rfind(path, 0), 0u) << "the message starts with the file: " << error;
  }
}

TEST(SceneLoad, CameraLookingAlongTheDefaultUpIsAClearError) {
  std::string path = write_temp_file("up.json", R"({"camera": {"position": [0,5,0], "look_at": [0,0,0], "width": 8,
    "height": 8}, "materials": {}, "shapes": []})");
  EXPECT_NE(load_error(path).find("camera: up is parallel to the view direction"), std::string::npos) << load_error(path);
}

TEST(SceneLoad, TransformsMoveGeometryAndMirrorsKeepTheFrontSide) {
  std::string tri = R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,2]], "material": "m")";
  SceneDescription moved = load_scene(write_temp_file(
      "moved.json", scene_with_shape(tri + R"(, "transform": {"translate": [1, 2, 3], "scale": 2}})")));
  const TriangleMesh& m = moved.shapes[0].mesh;
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.positions[m.triangles[0][1]], glm::vec3(3, 2, 3));  // (1,0,0) scaled by 2, then moved

  SceneDescription mirrored = load_scene(write_temp_file(
      "mirrored.json", scene_with_shape(tri + R"(, "transform": {"scale": [1, 1, -1]}})")));
  const TriangleMesh& mm = mirrored.shapes[0].mesh;
  glm::vec3 a = mm.positions[mm.triangles[0][0]], b = mm.positions[mm.triangles[0][1]], c = mm.positions[mm.triangles[0][2]];
  // The front faces +z; mirrored in z it must face -z, as the transformed normal M^-T n does. The
  // points do not move, so only the swapped winding can say so.
  EXPECT_LT(glm::cross(b - a, c - a).z, 0.0f);

  SceneDescription sphere = load_scene(write_temp_file(
      "sphere.json", scene_with_shape(R"({"type": "sphere", "radius": 1, "material": "m", "center": [1, 0, 0],
        "transform": {"translate": [0, 1, 0], "rotate": {"axis": [0, 0, 1], "degrees": 90}, "scale": 3}})")));
  EXPECT_NEAR(sphere.shapes[0].radius, 3.0f, 1e-5f);
  EXPECT_NEAR(sphere.shapes[0].center.x, 0.0f, 1e-5f);
  EXPECT_NEAR(sphere.shapes[0].center.y, 4.0f, 1e-5f);
}

TEST(SceneLoad, ZeroAreaEmittersNeverReachLightSampling) {
  std::string scene = scene_with_shape(
      R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0],[2,0,0]], "indices": [[0,1,2],[0,1,3]],
          "material": "m", "emission": [1, 1, 1]})");
  DeviceScene d = load_device_scene(write_temp_file("zero-area.json", scene));
  EXPECT_EQ(d.triangle_count, 1u);  // the collinear triangle is removed by clean-up
  ASSERT_EQ(d.lights.size(), 1u);
  EXPECT_FLOAT_EQ(d.lights[0].area, 0.5f);
  EXPECT_FLOAT_EQ(d.lights[0].select_pdf, 1.0f);
}

TEST(SceneLoad, LightsAreChosenInProportionToPower) {
  std::string scene = R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
    "materials": {"m": {"type": "diffuse"}}, "shapes": [
      {"type": "sphere", "radius": 1, "material": "m", "emission": [1, 1, 1]},
      {"type": "sphere", "radius": 2, "center": [5, 0, 0], "material": "m", "emission": [1, 1, 1], "two_sided": true}]})";
  DeviceScene d = load_device_scene(write_temp_file("power.json", scene));
  ASSERT_EQ(d.lights.size(), 2u);
  // Power ~ area x sides: 4 pi vs 16 pi x 2.
  EXPECT_NEAR(d.lights[0].select_pdf, 1.0 / 9.0, 1e-6);
  EXPECT_NEAR(d.lights[1].select_pdf, 8.0 / 9.0, 1e-6);
  EXPECT_FLOAT_EQ(d.light_cdf.back(), 1.0f);
}

namespace {

// A scene with the given materials block body, lights array body and camera extras.
std::string scene_with(const std::string& materials, const std::string& lights = "", const std::string& camera = "") {
  return R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8)" + camera + R"(},
    "materials": {)" + materials + R"(}, "shapes": [{"type": "sphere", "radius": 1, "material": "m"}])" +
         (lights.empty() ? "" : R"(, "lights": [)" + lights + "]") + "}";
}

std::string error_of(const std::string& json) { return load_error(write_temp_file("case.json", json)); }

}  // namespace

TEST(SceneLoad, BadMaterialLightAndCameraParametersAreRejected) {
  struct Case {
    std::string json, expected;
  } cases[] = {
      {scene_with(R"("m": {"type": "rough_conductor", "roughness": -0.1, "specular": [1, 1, 1]})"),
       "materials.m.roughness: expected a roughness in [0.01, 1]"},
      {scene_with(R"("m": {"type": "rough_conductor", "roughness": 0.3})"),
       "materials.m: a rough_conductor needs specular, or eta and k"},
      {scene_with(R"("m": {"type": "rough_conductor", "roughness": 0.3, "eta": [0, 1, 1], "k": [1, 1, 1]})"),
       "materials.m.eta: expected values > 0"},
      {scene_with(R"("m": {"type": "dielectric", "ior": 0})"), "materials.m.ior: expected an index of refraction in (0, 10]"},
      {scene_with(R"("m": {"type": "dielectric", "ior": -1.5})"), "materials.m.ior: expected an index of refraction"},
      {scene_with(R"("m": {"type": "dielectric"})"), "materials.m: missing key \"ior\""},
      {scene_with(R"("m": {"type": "plastic", "roughness": 0.001})"), "materials.m.roughness: expected 0 (smooth)"},
      {scene_with(R"("m": {"type": "phong", "diffuse": [0.6, 0.6, 0.6], "specular": [0.5, 0.1, 0.1], "exponent": 10})"),
       "materials.m: diffuse + specular exceeds 1"},
      {scene_with(R"("m": {"type": "phong", "exponent": 0})"), "materials.m.exponent: expected an exponent in (0, 100000]"},
      {scene_with(R"("m": {"type": "oren_nayar", "sigma_degrees": 95})"), "materials.m.sigma_degrees: expected an angle in [0, 90]"},
      {scene_with(R"("m": {"type": "mirror", "reflectance": [1.2, 1, 1]})"), "materials.m.reflectance: expected values in [0, 1]"},
      {scene_with(R"("m": {"type": "glas"})"), "materials.m.type: unknown material type \"glas\""},
      {scene_with(R"("m": {"type": "diffuse", "roughness": 1})"), "materials.m: unknown key \"roughness\""},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "area"})"), "lights[0].type: unknown light type \"area\""},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "point", "position": [0, 1, 0]})"),
       "lights[0]: missing key \"intensity\""},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "point", "position": [0, 1, 0], "intensity": [-1, 1, 1]})"),
       "lights[0].intensity: expected non-negative values"},
      {scene_with(R"("m": {"type": "diffuse"})",
                  R"({"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0], "intensity": [1, 1, 1], "outer_angle_degrees": 20, "inner_angle_degrees": 30})"),
       "lights[0].inner_angle_degrees: expected an angle in [0, outer_angle_degrees]"},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "directional", "direction": [0, 0, 0], "irradiance": [1, 1, 1]})"),
       "lights[0].direction: expected a non-zero direction"},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "environment"})"),
       "lights[0]: an environment light needs either radiance or file"},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "environment", "file": "missing-sky.exr"})"),
       "lights[0].file: "},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "environment", "radiance": [1, 1, 1]}, {"type": "environment", "radiance": [1, 1, 1]})"),
       "lights[1]: a scene has at most one environment light"},
      {scene_with(R"("m": {"type": "diffuse"})", "", R"(, "type": "thin_lens", "aperture_radius": 0.1)"),
       "camera: a thin_lens camera needs aperture_radius and focus_distance"},
      {scene_with(R"("m": {"type": "diffuse"})", "", R"(, "type": "thin_lens", "aperture_radius": -0.1, "focus_distance": 2)"),
       "camera.aperture_radius: expected a number >= 0"},
      {scene_with(R"("m": {"type": "diffuse"})", "", R"(, "aperture_radius": 0.1)"),
       "camera: aperture_radius and focus_distance need \"type\": \"thin_lens\""},
      {scene_with(R"("m": {"type": "diffuse"})", "", R"(, "filter": {"type": "mitchell"})"),
       "camera.filter.type: unknown filter \"mitchell\""},
      {scene_with(R"("m": {"type": "diffuse"})", "", R"(, "filter": {"type": "gaussian", "sigma": 0})"),
       "camera.filter.sigma: expected a number > 0"},
  };
  for (const Case& c : cases) {
    std::string error = error_of(c.json);
    EXPECT_NE(error.find(c.expected), std::string::npos) << "expected \"" << c.expected << "\", got \"" << error << "\"";
  }
  // The missing environment map is named with its path.
  EXPECT_NE(error_of(cases[19].json).find("missing-sky.exr: cannot open the image file"), std::string::npos);
}

// The kernel is specialised to what the scene uses, and only to that: a change of per-render settings
// (samples, depth, seed, camera) leaves the build options, and so the cached binary, unchanged.
TEST(SceneLoad, KernelFeaturesFollowTheSceneNotTheSettings) {
  DeviceScene diffuse = load_device_scene(std::string(PATHCL_TEST_SCENES) + "/../../scenes/cornell-box.json");
  EXPECT_EQ(kernel_options(diffuse.features), "-cl-std=CL1.2 -DPC_HAS_TRIANGLES -DPC_HAS_AREA_LIGHTS -DPC_HAS_DIFFUSE");
  DeviceScene all = load_device_scene(std::string(PATHCL_TEST_SCENES) + "/../../scenes/materials.json");
  for (uint32_t f : {kFeatureTriangles, kFeatureSpheres, kFeatureAreaLights, kFeatureDiffuse, kFeatureOrenNayar,
                     kFeaturePhong, kFeatureMirror, kFeatureDielectric, kFeatureRoughConductor, kFeaturePlastic,
                     kFeaturePointLights, kFeatureDirectionalLights, kFeatureEnvironment})
    EXPECT_TRUE(all.features & f) << "feature bit " << f;
  EXPECT_FALSE(all.features & kFeatureEnvironmentMap);

  std::string base = scene_with(R"("m": {"type": "mirror"})", R"({"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1]})");
  std::string other_settings = base;
  other_settings.replace(other_settings.find("\"width\": 8"), 10, "\"width\": 9");
  other_settings.replace(other_settings.find("[0,0,5]"), 7, "[1,2,6]");
  DeviceScene a = load_device_scene(write_temp_file("a.json", base));
  DeviceScene b = load_device_scene(write_temp_file("b.json", other_settings + ""));
  EXPECT_EQ(kernel_options(a.features), kernel_options(b.features));
  EXPECT_EQ(a.features, kFeatureSpheres | kFeatureMirror | kFeaturePointLights);
  // A light that emits nothing is dropped and turns on no code.
  DeviceScene dark = load_device_scene(write_temp_file(
      "dark.json", scene_with(R"("m": {"type": "diffuse"})", R"({"type": "directional", "direction": [0, -1, 0], "irradiance": [0, 0, 0]})")));
  EXPECT_TRUE(dark.lights.empty());
  EXPECT_FALSE(dark.features & kFeatureDirectionalLights);
}

// Lights are chosen in proportion to power, over every type at once.
TEST(SceneLoad, LightSelectionIsProportionalToPowerAcrossTypes) {
  DeviceScene d = load_device_scene(write_temp_file("powers.json", scene_with(R"("m": {"type": "diffuse"})",
      R"({"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1]},
         {"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "intensity": [2, 2, 2], "outer_angle_degrees": 60, "inner_angle_degrees": 60})")));
  ASSERT_EQ(d.lights.size(), 2u);
  double point = 4 * M_PI, spot = 2 * M_PI * 2 * (1 - std::cos(M_PI / 3));
  EXPECT_NEAR(d.lights[0].select_pdf, point / (point + spot), 1e-6);
  EXPECT_NEAR(d.lights[1].select_pdf, spot / (point + spot), 1e-6);
  EXPECT_FLOAT_EQ(d.light_cdf.back(), 1.0f);
}
