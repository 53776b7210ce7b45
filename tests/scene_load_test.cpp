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
  EXPECT_EQ(m.positions[m.triangles[0][1]], glm::dvec3(3, 2, 3));  // (1,0,0) scaled by 2, then moved

  SceneDescription mirrored = load_scene(write_temp_file(
      "mirrored.json", scene_with_shape(tri + R"(, "transform": {"scale": [1, 1, -1]}})")));
  const TriangleMesh& mm = mirrored.shapes[0].mesh;
  glm::dvec3 a = mm.positions[mm.triangles[0][0]], b = mm.positions[mm.triangles[0][1]], c = mm.positions[mm.triangles[0][2]];
  // The front faces +z; mirrored in z it must face -z, as the transformed normal M^-T n does. The
  // points do not move, so only the swapped winding can say so.
  EXPECT_LT(glm::cross(b - a, c - a).z, 0.0);

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

TEST(SceneLoad, DeviceSceneIsCameraRelativeWithPositionsSubtractedInDouble) {
  // At 1e6 float spacing is 0.0625: in float, 1e6 + 0.33 - (1e6 + 0.1) would be 0.1875, not 0.23.
  std::string path = write_temp_file("far.json", R"({"camera": {"position": [1000000.1, 2000000.2, 5], "look_at": [1000000.1, 2000000.2, 0],
    "width": 8, "height": 8}, "materials": {"m": {"type": "diffuse"}}, "shapes": [
      {"type": "triangles", "positions": [[0.33, 0.2, 0], [1.33, 0.2, 0], [0.33, 1.2, 0]], "indices": [[0, 1, 2]],
       "material": "m", "transform": {"translate": [1000000, 2000000, 0]}},
      {"type": "sphere", "center": [1000000.35, 2000000.2, -1], "radius": 0.5, "material": "m"}]})");
  SceneDescription description = load_scene(path);
  DeviceScene d = build_device_scene(description);
  EXPECT_EQ(d.origin, description.camera.position);
  EXPECT_EQ(d.header.cam_position.x, 0.0f);
  EXPECT_EQ(d.header.cam_position.y, 0.0f);
  EXPECT_EQ(d.header.cam_position.z, 0.0f);
  Primitive tri = scene_primitive(d, 0), sphere = scene_primitive(d, 1);
  EXPECT_NEAR(tri.a.x, 0.23, 1e-6);
  EXPECT_NEAR(tri.a.y, 0.0, 1e-6);
  EXPECT_NEAR(tri.a.z, -5.0, 1e-6);
  EXPECT_NEAR(sphere.a.x, 0.25, 1e-6);
  // Flattened around the world origin (ray files), the camera keeps its world position.
  DeviceScene w = build_device_scene(description, DeviceOrigin::world);
  EXPECT_EQ(w.origin, glm::dvec3(0));
  EXPECT_EQ(w.header.cam_position.x, float(1000000.1));
}

TEST(SceneLoad, GeometryBeyondFloatReachIsRefusedWithThePlace) {
  struct Case {
    std::string shape, expected;
  } cases[] = {
      // 4 pi r^2 overflows float for these radii.
      {R"({"type": "sphere", "radius": 1e30, "material": "m"})",
       "shapes[0].radius: a sphere radius of 1e+30 is beyond the largest of 1.5e+18"},
      {R"({"type": "sphere", "radius": 3e38, "material": "m", "emission": [1, 1, 1]})",
       "shapes[0].radius: a sphere radius of 3e+38 is beyond the largest of 1.5e+18"},
      {R"({"type": "sphere", "radius": 1e10, "material": "m", "transform": {"scale": 1e9}})",
       "shapes[0].transform: a sphere radius of 1e+19 is beyond the largest of 1.5e+18"},
      // Within float range, but too far from the camera for squared distances.
      {R"({"type": "sphere", "radius": 1, "center": [0, 2e18, 0], "material": "m"})",
       "shapes[0]: geometry reaches 2e+18 from the camera"},
      {R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1e38,0]], "indices": [[0,1,2]], "material": "m"})",
       "shapes[0]: geometry reaches 1e+38 from the camera"},
  };
  for (const Case& c : cases) {
    std::string path = write_temp_file("case.json", scene_with_shape(c.shape));
    std::string error;
    try {
      build_device_scene(load_scene(path));
    } catch (const SceneError& e) {
      error = e.what();
    }
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.shape << "\n  gave: " << error;
    EXPECT_EQ(error.rfind(path, 0), 0u) << "the message starts with the file: " << error;
  }
  // The same from an OBJ file: the message names the shape and its file.
  write_temp_file("meshes/huge.obj", "v 0 0 0\nv 1e38 0 0\nv 0 1 0\nf 1 2 3\n");
  std::string path = write_temp_file("huge-obj.json", scene_with_shape(R"({"type": "mesh", "file": "meshes/huge.obj", "material": "m"})"));
  try {
    build_device_scene(load_scene(path));
    ADD_FAILURE() << "expected a SceneError";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("shapes[0] (meshes/huge.obj): geometry reaches 1e+38 from the camera"),
              std::string::npos) << e.what();
  }
}

TEST(SceneLoad, LightDistributionStaysFiniteForExtremeEmitters) {
  // The largest sphere allowed, a small one, one whose float area is 0, and a triangle emitting 1e-45
  // in blue only (its luminance is 0 in float): powers span ~80 orders of magnitude.
  std::string scene = R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
    "materials": {"m": {"type": "diffuse"}}, "shapes": [
      {"type": "sphere", "radius": 1.5e18, "flip_normals": true, "material": "m", "emission": [1, 1, 1]},
      {"type": "sphere", "radius": 1e-3, "material": "m", "emission": [1, 1, 1]},
      {"type": "sphere", "radius": 1e-30, "center": [1, 0, 0], "material": "m", "emission": [1, 1, 1]},
      {"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,2]], "material": "m",
       "emission": [0, 0, 1e-45]}]})";
  DeviceScene d = load_device_scene(write_temp_file("extreme-lights.json", scene));
  EXPECT_EQ(d.skipped_zero_area_emitters, 1u);  // the 1e-30 sphere
  ASSERT_EQ(d.lights.size(), 3u);
  for (const Light& l : d.lights) {
    EXPECT_TRUE(l.area > 0 && std::isfinite(l.area)) << l.area;
    EXPECT_TRUE(l.select_pdf >= 0 && l.select_pdf <= 1) << l.select_pdf;
  }
  EXPECT_EQ(d.lights[0].select_pdf, 1.0f);  // the others' share is below float's smallest numbers
  ASSERT_EQ(d.light_cdf.size(), 4u);
  for (size_t i = 1; i < d.light_cdf.size(); ++i) EXPECT_GE(d.light_cdf[i], d.light_cdf[i - 1]);
  EXPECT_EQ(d.light_cdf.back(), 1.0f);
}

TEST(SceneLoad, SmoothNormalsAreIndexedByPrimitiveAfterSpheres) {
  // Normals are stored 3 per scene-order primitive: a sphere before a smooth mesh takes its 3 slots.
  std::string scene = scene_with_shape(R"({"type": "sphere", "radius": 0.5, "center": [0, 0, -3], "material": "m"},
    {"type": "mesh", "file": ")" + std::string(PATHCL_SOURCE_DIR) + R"(/scenes/meshes/cube.obj", "material": "m",
     "smooth": true})");
  DeviceScene d = load_device_scene(write_temp_file("sphere-then-smooth.json", scene));
  ASSERT_EQ(d.header.prim_count, 13u);
  ASSERT_EQ(d.normals.size(), 3u * 13);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(d.normals[k].x * d.normals[k].x + d.normals[k].y * d.normals[k].y, 0.0f);
  for (uint32_t i = 3; i < d.normals.size(); ++i) {
    const pc_float4& n = d.normals[i];
    EXPECT_NEAR(n.x * n.x + n.y * n.y + n.z * n.z, 1.0f, 1e-5f) << i;
  }
}

TEST(SceneLoad, ObjNormalsAreIgnoredEvenZeroLengthOnes) {
  // `vn` lines (here of zero length) are not read: shading normals come only from "smooth".
  write_temp_file("meshes/vn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nvn nan 0 0\nf 1//1 2//1 3//2\n");
  for (bool smooth : {false, true}) {
    std::string path = write_temp_file("vn.json", scene_with_shape(R"({"type": "mesh", "file": "meshes/vn.obj", "material": "m",
      "smooth": )" + std::string(smooth ? "true" : "false") + "}"));
    SceneDescription s = load_scene(path);
    ASSERT_EQ(s.shapes[0].mesh.triangles.size(), 1u);
    EXPECT_EQ(s.shapes[0].mesh.normals.size(), smooth ? 3u : 0u);
    for (const glm::vec3& n : s.shapes[0].mesh.normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-6f);
  }
}
