// Scene files: every error names the file and the place; transforms and flags do what they say.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "runtime/image_io.h"
#include "scene/scene_error.h"
#include "scene/texture_load.h"
#include "test_support.h"

namespace {

std::string scenes() { return PATHCL_TEST_SCENES; }

std::string load_error(const std::string& path) { return scene_load_error(path); }

std::string scene_with_shape(const std::string& shape) {
  return R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
    "materials": {"m": {"type": "diffuse"}}, "shapes": [)" + shape + "]}";
}

}  // namespace

TEST(SceneLoad, ErrorsNameFileAndPlace) {
  // nlohmann's description of the syntax error, in our form (not "[json.exception.parse_error.101] ...").
  EXPECT_EQ(load_error(scenes() + "/bad-malformed.json"),
            scenes() + "/bad-malformed.json:5:1: malformed JSON: syntax error while parsing value - unexpected '}'; "
                       "expected '[', '{', or a literal");
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

// A directory or a missing file where a file is expected is named as such, with the path, whichever
// reader would have read it (it used to be "basic_filebuf::underflow error reading the file: Is a
// directory", exit 1, for a scene, and "no faces" for a mesh).
TEST(SceneLoad, DirectoriesAndMissingFilesAreNamedAsSuch) {
  const std::string dir = temp_dir() + "/inputs";
  for (const char* d : {"scene-dir.json", "meshes/dir.obj", "tex/dir.png", "lib-dir.mtl", "sky-dir.exr"})
    std::filesystem::create_directories(dir + "/" + d);
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  write_temp_file("inputs/meshes/lib.obj", "mtllib ../lib-dir.mtl\n" + tri + "usemtl m\nf 1 2 3\n");
  auto scene = [&](const std::string& name, const std::string& materials, const std::string& shape,
                   const std::string& lights = "") {
    return write_temp_file("inputs/" + name, R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
      "materials": {)" + materials + R"(}, "shapes": [)" + shape + "], \"lights\": [" + lights + "]}");
  };
  const std::string diffuse = R"("m": {"type": "diffuse"})", sphere = R"({"type": "sphere", "radius": 1, "material": "m"})";
  struct Case {
    std::string scene, expected;
  } cases[] = {
      {dir + "/scene-dir.json", dir + "/scene-dir.json: is a directory, expected a JSON scene file"},
      {dir + "/missing.json", dir + "/missing.json: cannot open the scene file: no such file"},
      {scene("mesh-dir.json", diffuse, R"({"type": "mesh", "file": "meshes/dir.obj", "material": "m"})"),
       dir + "/meshes/dir.obj: is a directory, expected an OBJ, PLY, STL or OFF mesh file"},
      {scene("mesh-missing.json", diffuse, R"({"type": "mesh", "file": "meshes/missing.obj", "material": "m"})"),
       dir + "/meshes/missing.obj: cannot open the mesh file: no such file"},
      {scene("mtl-dir.json", diffuse, R"({"type": "mesh", "file": "meshes/lib.obj", "material": "from_mtl"})"),
       dir + "/meshes/../lib-dir.mtl: is a directory, expected an MTL material file"},
      {scene("texture-dir.json", R"("m": {"type": "diffuse", "reflectance": {"texture": "tex/dir.png"}})", sphere),
       dir + "/texture-dir.json: materials.m.reflectance.texture: " + dir +
           "/tex/dir.png: is a directory, expected an image file (PNG, JPEG, BMP, TGA, Radiance HDR or OpenEXR)"},
      {scene("texture-missing.json", R"("m": {"type": "diffuse", "reflectance": {"texture": "tex/none.png"}})", sphere),
       dir + "/texture-missing.json: materials.m.reflectance.texture: " + dir +
           "/tex/none.png: cannot open the image file: no such file"},
      {scene("sky-dir.json", diffuse, sphere, R"({"type": "environment", "file": "sky-dir.exr"})"),
       dir + "/sky-dir.json: lights[0].file: " + dir + "/sky-dir.exr: is a directory, expected an image file"},
  };
  for (const Case& c : cases) {
    std::string error;
    try {
      load_scene(c.scene);
      error = "(loaded)";
    } catch (const std::exception& e) {
      error = e.what();
    }
    EXPECT_NE(error.find(c.expected), std::string::npos) << "expected \"" << c.expected << "\"\n  gave: " << error;
  }
}

// Mesh files of formats pathcl does not read are named for what they are, by extension or by content,
// instead of what tinyobjloader made of them ("igea.ply: no faces", "Duck.glb: Failed parse 'l' line");
// PLY, STL and OFF files go to their readers by extension, and named .obj are told to be renamed.
TEST(SceneLoad, MeshFilesOfOtherFormatsAreNamed) {
  const std::string bin("\x00\x01\x02\x03\x4d\x4d\x10\x00", 8);
  const std::string lfs =
      "version https://git-lfs.github.com/spec/v1\noid sha256:4d7a214614ab2935c943f9e0ff69d22eadbb8f32b1258daaa5e2ca24d17e2393\nsize 12345\n";
  const std::string obj = " (expected an OBJ, PLY, STL or OFF mesh file)";
  const std::string gltf_shape = "a glTF file is placed by a shape of its own ({\"type\": \"gltf\", \"file\": ...}), not as a mesh";
  struct Case {
    std::string file, content, expected;
  } cases[] = {
      {"igea.ply", "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n",
       "no faces (0 vertices: a point cloud? pathcl renders surfaces)"},
      // glTF files are a shape of their own (tests/gltf_test.cpp).
      {"Duck.glb", std::string("glTF\x02\x00\x00\x00", 8), gltf_shape},
      {"Duck.gltf", "{\"asset\": {\"version\": \"2.0\"}}", gltf_shape},
      {"part.STL", "solid part\nendsolid part\n", "no faces"},
      {"box.off", "OFF\n0 0 0\n", "no faces"},
      {"rig.fbx", "; FBX 7.4.0 project file\n", "FBX meshes are not supported" + obj},
      {"scene.dae", "<?xml version=\"1.0\"?>\n<COLLADA/>\n", "COLLADA meshes are not supported" + obj},
      {"old.3ds", bin, "3DS meshes are not supported" + obj},
      {"model.blend", "BLENDER-v300", "Blender meshes are not supported" + obj},
      {"model.obj.gz", "\x1f\x8b\x08", "Compressed meshes are not supported (expected an OBJ, PLY, STL or OFF mesh file; decompress it first)"},
      // Named .obj, told by content.
      {"ply-inside.obj", "ply\r\nformat binary_little_endian 1.0\r\n",
       "a PLY file named as OBJ (the reader is chosen by the extension: name it .ply)"},
      {"stl-inside.obj", "solid part\nendsolid part\n", "an STL file named as OBJ (the reader is chosen by the extension: name it .stl)"},
      {"gltf-inside.obj", "\n  {\"asset\": {}}",
       "looks like JSON (a glTF mesh or a scene file?), expected an OBJ, PLY, STL or OFF mesh file"},
      {"binary.obj", "v 0 0 0\n" + bin,
       "not a text OBJ file (it has binary content), expected an OBJ, PLY, STL or OFF mesh file"},
      {"lfs.obj", lfs, "looks like a Git LFS pointer, not a mesh (run git lfs pull)"},
      {"lfs.ply", lfs, "looks like a Git LFS pointer, not a mesh (run git lfs pull)"},
      {"lfs.stl", lfs, "looks like a Git LFS pointer, not a mesh (run git lfs pull)"},
      {"lfs.off", lfs, "looks like a Git LFS pointer, not a mesh (run git lfs pull)"},
  };
  for (const Case& c : cases) {
    std::string mesh = write_temp_file("formats/" + c.file, c.content);
    std::string error = load_error(write_temp_file("formats.json", scene_with_shape(
        R"({"type": "mesh", "file": "formats/)" + c.file + R"(", "material": "m"})")));
    EXPECT_EQ(error, mesh + ": " + c.expected) << c.file;
  }
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
      {R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,2]], "material": "m", "subdivide": 0})",
       "shapes[0].subdivide: expected a whole number of parts per edge, 1 to 64, got 0"},
      {R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,2]], "material": "m", "subdivide": 2.5})",
       "shapes[0].subdivide: expected a whole number of parts per edge, 1 to 64, got 2.5"},
      {R"({"type": "sphere", "radius": 1, "material": "m", "subdivide": 2})", "shapes[0]: unknown key \"subdivide\""},
  };
  for (const Case& c : cases) {
    std::string path = write_temp_file("case.json", scene_with_shape(c.shape));
    std::string error = load_error(path);
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.shape << "\n  gave: " << error;
    EXPECT_EQ(error.rfind(path, 0), 0u) << "the message starts with the file: " << error;
  }
}

// "subdivide": n splits each triangle into n^2 of the same plane: a closed cube stays closed (every edge in
// exactly two triangles, opposite ways), its area and winding unchanged, the points of shared edges shared.
TEST(SceneLoad, SubdivideKeepsTheSurfaceWatertight) {
  const std::string cube = std::string(PATHCL_SOURCE_DIR) + "/scenes/meshes/cube.obj";
  auto load = [&](int parts) {
    std::string shape = R"({"type": "mesh", "file": ")" + cube + R"(", "material": "m")" +
                        (parts > 0 ? ", \"subdivide\": " + std::to_string(parts) : std::string()) + "}";
    return load_scene(write_temp_file("subdivide.json", scene_with_shape(shape))).shapes.at(0).mesh;
  };
  const TriangleMesh plain = load(0), fine = load(3);
  ASSERT_EQ(fine.triangles.size(), 9 * plain.triangles.size());
  auto area_and_normal = [](const TriangleMesh& m, size_t t) {
    const auto& [a, b, c] = m.triangles[t];
    return glm::cross(m.positions[b] - m.positions[a], m.positions[c] - m.positions[a]) * 0.5;
  };
  double plain_area = 0, fine_area = 0;
  for (size_t t = 0; t < plain.triangles.size(); ++t) {
    plain_area += glm::length(area_and_normal(plain, t));
    // The 9 parts of triangle t face as it does.
    for (size_t k = 9 * t; k < 9 * t + 9; ++k) {
      EXPECT_GT(glm::dot(area_and_normal(fine, k), area_and_normal(plain, t)), 0.0) << "part " << k;
      fine_area += glm::length(area_and_normal(fine, k));
    }
  }
  EXPECT_NEAR(fine_area, plain_area, 1e-12 * plain_area);
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const auto& t : fine.triangles)
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << edge.first << "-" << edge.second;
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << "edge " << edge.first << "-" << edge.second << " is open";
  }
  // Each point once: the 8 corners, 2 on each of the 18 edges (12 and 6 diagonals), 1 inside each triangle.
  EXPECT_EQ(fine.positions.size(), 8u + 18 * 2 + 12 * 1);
}

TEST(SceneLoad, CameraLookingAlongTheDefaultUpIsAClearError) {
  std::string path = write_temp_file("up.json", R"({"camera": {"position": [0,5,0], "look_at": [0,0,0], "width": 8,
    "height": 8}, "materials": {}, "shapes": []})");
  EXPECT_NE(load_error(path).find("camera: up is parallel to the view direction"), std::string::npos) << load_error(path);
}

TEST(SceneLoad, LeftHandedCameraMirrorsTheImageOnly) {
  // pbrt's camera frame: the image's x axis is cross(up, forward), where pathcl's is cross(forward, up).
  auto header = [](const std::string& handedness) {
    return load_device_scene(write_temp_file("hand.json", R"({"camera": {"position": [1,2,3], "look_at": [0,0.5,0],
        "up": [0.1,1,0], "fov_y_degrees": 50, "width": 16, "height": 8)" + handedness + R"(}, "materials": {},
        "shapes": [], "lights": [{"type": "point", "position": [0,1,0], "intensity": [1,1,1]}]})")).header;
  };
  const SceneHeader right = header(""), also_right = header(R"(, "handedness": "right")"),
                    left = header(R"(, "handedness": "left")");
  EXPECT_EQ(std::memcmp(&right, &also_right, sizeof right), 0);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ((&left.cam_right.x)[k], -(&right.cam_right.x)[k]);
    EXPECT_EQ((&left.cam_up.x)[k], (&right.cam_up.x)[k]);
    EXPECT_EQ((&left.cam_forward.x)[k], (&right.cam_forward.x)[k]);
  }
  EXPECT_GT(std::abs(right.cam_right.x) + std::abs(right.cam_right.z), 0.1f);
  EXPECT_NE(load_error(write_temp_file("hand.json", R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8,
      "height": 8, "handedness": "up"}, "materials": {}, "shapes": []})")).find(
                "camera.handedness: expected \"right\" or \"left\", got \"up\""),
            std::string::npos);
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
  ASSERT_EQ(d.light_bvh.size(), 1u);
  EXPECT_EQ(d.light_bvh[0].light, 0u);
}

TEST(SceneLoad, LightBvhBoundsItsLightsIntensityAndDirections) {
  std::string scene = R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
    "materials": {"m": {"type": "diffuse"}}, "shapes": [
      {"type": "sphere", "radius": 1, "material": "m", "emission": [1, 1, 1]},
      {"type": "sphere", "radius": 2, "center": [5, 0, 0], "material": "m", "emission": [1, 1, 1], "two_sided": true},
      {"type": "triangles", "positions": [[0,3,0],[1,3,0],[0,3,1]], "indices": [[0,2,1]], "material": "m", "emission": [2, 2, 2]}]})";
  DeviceScene d = load_device_scene(write_temp_file("power.json", scene));
  ASSERT_EQ(d.lights.size(), 3u);
  ASSERT_EQ(d.header.tree_light_count, 3u);
  ASSERT_EQ(d.light_bvh.size(), 5u);
  // Peak intensities: L pi r^2 for spheres, L x area along a triangle's normal; the root holds their sum.
  double expected[] = {M_PI, 4 * M_PI, 2 * 0.5};
  for (uint32_t i = 0; i < 3; ++i) {
    const LightBvhNode& leaf = d.light_bvh[d.lights[i].tree_leaf];
    EXPECT_EQ(leaf.light, i);
    EXPECT_EQ(leaf.second, PC_INVALID);
    EXPECT_NEAR(leaf.lo.w, expected[i], 1e-5 * expected[i]);
  }
  const LightBvhNode& root = d.light_bvh[0];
  EXPECT_NEAR(root.lo.w, M_PI + 4 * M_PI + 1, 1e-5);
  EXPECT_FLOAT_EQ(root.hi.w, -1.0f);  // the spheres emit in every direction
  // The triangle's leaf: a cone of one normal (+y, from the winding 0 2 1), emitting within 90 degrees of it.
  const LightBvhNode& tri = d.light_bvh[d.lights[2].tree_leaf];
  EXPECT_FLOAT_EQ(tri.axis.y, 1.0f);
  EXPECT_FLOAT_EQ(tri.hi.w, 1.0f);
  EXPECT_NEAR(tri.axis.w, 0.0f, 1e-7);
  // Every node's box holds its children's.
  for (size_t i = 0; i < d.light_bvh.size(); ++i) {
    const LightBvhNode& n = d.light_bvh[i];
    if (n.second == PC_INVALID) continue;
    for (const LightBvhNode* c : {&d.light_bvh[i + 1], &d.light_bvh[n.second]}) {
      EXPECT_LE(n.lo.x, c->lo.x); EXPECT_LE(n.lo.y, c->lo.y); EXPECT_LE(n.lo.z, c->lo.z);
      EXPECT_GE(n.hi.x, c->hi.x); EXPECT_GE(n.hi.y, c->hi.y); EXPECT_GE(n.hi.z, c->hi.z);
    }
  }
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

// ---- Numeric fields ------------------------------------------------------------------------------------

namespace {

// A scene whose camera has these keys (besides position and look_at) and a point light.
std::string scene_with_camera(const std::string& keys, const std::string& rest = "") {
  return R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], )" + keys + R"(},
    "materials": {"m": {"type": "diffuse"}}, "shapes": [],
    "lights": [{"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1]}])" + rest + "}";
}

const char* const kCamera = R"("width": 8, "height": 8)";

// `text` with its "@" replaced by `value`.
std::string with_value(std::string text, const std::string& value) {
  return text.replace(text.find('@'), 1, value);
}

}  // namespace

// Every numeric field of the format against each class of bad number that applies to it: zero, negative,
// too large, so small that it is 0 as a float, beyond float range (and beyond double range: 1e400), a
// fraction or an exponent where an integer is meant (8.0 and 1e3 are refused like 3.5: docs/scene-format.md), a string. The message names
// the file, the field's JSON path and what was expected.
TEST(SceneLoad, EveryNumericFieldRefusesEachClassOfBadNumber) {
  const std::string integer = "expected an integer in ";
  const std::string no_fraction = " without a fraction or exponent, got ";
  struct Field {
    std::string json, path;  // the scene with "@" for the value, and the value's JSON path
    std::vector<std::pair<std::string, std::string>> bad;  // value, what the message says after the path
  } fields[] = {
      {scene_with_camera(R"("width": @, "height": 8)"), "camera.width",
       {{"0", integer + "[1, 16384], got 0"}, {"-1", integer + "[1, 16384], got -1"},
        {"16385", integer + "[1, 16384], got 16385"}, {"8.0", integer + "[1, 16384]" + no_fraction + "8.0"},
        {"3.5", no_fraction + "3.5"}, {"1e3", no_fraction + "1000.0"},
        {"18446744073709551616", no_fraction + "1.8446744073709552e+19"}, {"\"8\"", integer + "[1, 16384]"}}},
      {std::string(R"({"camera": {"position": [@, 0, 5], "look_at": [0,0,0], "width": 8, "height": 8},
         "materials": {}, "shapes": []})"), "camera.position[0]",
       {{"1e39", "expected a finite number within float range, got 1e+39"}, {"\"0\"", "expected a number"}}},
      {std::string(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, @], "width": 8, "height": 8},
         "materials": {}, "shapes": []})"), "camera",
       {{"5", "position and look_at coincide"}}},
      {std::string(R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, @, 0], "width": 8, "height": 8},
         "materials": {}, "shapes": []})"), "camera.up",
       {{"0", "up is parallel to the view direction"}}},
      {scene_with_camera(R"("width": 8, "height": @)"), "camera.height",
       {{"0", integer + "[1, 16384], got 0"}, {"-8", "got -8"}, {"1e9", no_fraction + "1000000000.0"},
        {"99999", "got 99999"}}},
      {scene_with_camera(kCamera, R"(, "render": {"spp": @})"), "render.spp",
       {{"0", integer + "[1, 16777216], got 0"}, {"-4", "got -4"}, {"16777217", "got 16777217"},
        {"3.5", no_fraction + "3.5"}, {"1.0", no_fraction + "1.0"}, {"true", integer + "[1, 16777216]"}}},
      {scene_with_camera(kCamera, R"(, "render": {"max_depth": @})"), "render.max_depth",
       {{"-1", integer + "[0, 1024], got -1"}, {"1025", "got 1025"}, {"2.5", no_fraction + "2.5"}}},
      {scene_with_camera(kCamera, R"(, "render": {"seed": @})"), "render.seed",
       {{"-1", integer + "[0, 4294967295], got -1"}, {"4294967296", "got 4294967296"},
        {"1.5", no_fraction + "1.5"}}},
      {scene_with_camera(std::string(kCamera) + R"(, "fov_y_degrees": @)"), "camera.fov_y_degrees",
       {{"0", "expected a number > 0, got 0"}, {"-40", "expected a number > 0, got -40"},
        {"1e-300", "expected a number > 0 (at least 1.2e-38), got 1e-300"},
        {"180", "expected a field of view below 180 degrees"}, {"1e39", "expected a finite number within float range"},
        {"\"40\"", "expected a number"}}},
      {scene_with_camera(std::string(kCamera) + R"(, "type": "thin_lens", "focus_distance": 1, "aperture_radius": @)"),
       "camera.aperture_radius",
       {{"-0.1", "expected a number >= 0, got -0.1"}, {"1e20", "expected at most 1.5e18, got 1e+20"}}},
      {scene_with_camera(std::string(kCamera) + R"(, "type": "thin_lens", "aperture_radius": 0.1, "focus_distance": @)"),
       "camera.focus_distance",
       {{"0", "expected a number > 0"}, {"-2", "expected a number > 0"},
        {"1e-300", "expected a number > 0 (at least 1.2e-38)"}, {"3e38", "expected at most 1.5e18"}}},
      {scene_with_camera(std::string(kCamera) + R"(, "filter": {"type": "tent", "radius": @})"), "camera.filter.radius",
       {{"0", "expected a number > 0"}, {"-1", "expected a number > 0"}, {"1e-300", "(at least 1.2e-38)"},
        {"16385", "expected at most 16384 pixels, got 16385"}, {"1e30", "expected at most 16384 pixels"}}},
      {scene_with_camera(std::string(kCamera) + R"(, "filter": {"type": "gaussian", "sigma": @})"),
       "camera.filter.sigma",
       {{"0", "expected a number > 0"}, {"1e-300", "(at least 1.2e-38)"},
        {"5462", "expected at most 5461 pixels, got 5462"}}},
      {scene_with_camera(std::string(kCamera) + R"(, "filter": {"type": "gaussian", "radius": @})"),
       "camera.filter.radius", {{"0", "expected a number > 0"}, {"20000", "expected at most 16384 pixels"}}},
      {scene_with_shape(R"({"type": "sphere", "radius": @, "material": "m"})"), "shapes[0].radius",
       {{"0", "expected a number > 0, got 0"}, {"-1", "expected a number > 0"},
        {"1e39", "expected a finite number within float range"},
        {"1e30", "a sphere radius of 1e+30 is beyond the largest of 1.5e+18"}}},
      {scene_with_shape(R"({"type": "sphere", "radius": 1, "center": [0, @, 0], "material": "m"})"),
       "shapes[0].center[1]", {{"1e39", "expected a finite number within float range, got 1e+39"}}},
      {scene_with(R"("m": {"type": "dielectric", "ior": @})"), "materials.m.ior",
       {{"0", "expected an index of refraction in (0, 10], got 0"}, {"-1.5", "got -1.5"},
        {"1e-300", "expected an index of refraction in (0, 10], got 1e-300"}, {"11", "got 11"}}},
      {scene_with(R"("m": {"type": "plastic", "ior": @})"), "materials.m.ior",
       {{"0", "expected an index of refraction in (0, 10]"}}},
      {scene_with(R"("m": {"type": "phong", "exponent": @})"), "materials.m.exponent",
       {{"0", "expected an exponent in (0, 100000], got 0"}, {"-1", "got -1"}, {"1e-300", "got 1e-300"},
        {"1e6", "got 1000000.0"}}},
      {scene_with(R"("m": {"type": "oren_nayar", "sigma_degrees": @})"), "materials.m.sigma_degrees",
       {{"-1", "expected an angle in [0, 90] degrees"}, {"91", "expected an angle in [0, 90] degrees"}}},
      {scene_with(R"("m": {"type": "rough_conductor", "specular": [1, 1, 1], "roughness": @})"),
       "materials.m.roughness",
       {{"0", "expected a roughness in [0.01, 1]"}, {"-0.5", "expected a roughness in [0.01, 1]"},
        {"1.5", "expected a roughness in [0.01, 1]"}}},
      {scene_with(R"("m": {"type": "plastic", "roughness": @})"), "materials.m.roughness",
       {{"-1", "expected 0 (smooth) or a roughness in [0.01, 1]"}, {"0.001", "expected 0 (smooth)"},
        {"2", "expected 0 (smooth)"}}},
      {scene_with(R"("m": {"type": "diffuse", "reflectance": [0.5, @, 0.5]})"), "materials.m.reflectance",
       {{"-0.1", "expected non-negative values"}, {"1.1", "expected values in [0, 1]"}}},
      {scene_with(R"("m": {"type": "rough_conductor", "roughness": 0.5, "eta": [1, @, 1], "k": [1, 1, 1]})"),
       "materials.m.eta", {{"0", "expected values > 0"}, {"-1", "expected values > 0"}}},
      {scene_with(R"("m": {"type": "rough_conductor", "roughness": 0.5, "eta": [1, 1, 1], "k": [1, @, 1]})"),
       "materials.m.k", {{"-1", "expected non-negative values"}}},
      {scene_with_shape(R"({"type": "sphere", "radius": 1, "material": "m", "emission": [1, @, 1]})"),
       "shapes[0].emission", {{"-1", "expected non-negative values"}, {"1e13", "expected values of at most 1e12"}}},
      {scene_with_shape(R"({"type": "sphere", "radius": 1, "material": "m", "emission": [1, @, 1]})"),
       "shapes[0].emission[1]", {{"1e39", "expected a finite number within float range"}}},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "point", "position": [0, 2, 0], "intensity": [@, 1, 1]})"),
       "lights[0].intensity", {{"-1", "expected non-negative values"}, {"2e12", "expected values of at most 1e12"}}},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "point", "position": [@, 0, 0], "intensity": [1, 1, 1]})"),
       "lights[0].position",
       {{"2e18", "the light is 2e+18 from the camera, beyond the largest distance of 1.5e+18"},
        {"-3e38", "the light is 3e+38 from the camera"}}},
      {scene_with(R"("m": {"type": "diffuse"})",
                  R"({"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "intensity": [1, 1, 1], "outer_angle_degrees": @})"),
       "lights[0].outer_angle_degrees",
       {{"0", "expected an angle in (0, 180] degrees, got 0"}, {"-10", "got -10"},
        {"1e-300", "expected an angle in (0, 180] degrees, got 1e-300"}, {"181", "got 181"}}},
      {scene_with(R"("m": {"type": "diffuse"})",
                  R"({"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "intensity": [1, 1, 1], "outer_angle_degrees": 30, "inner_angle_degrees": @})"),
       "lights[0].inner_angle_degrees",
       {{"-1", "expected an angle in [0, outer_angle_degrees], got -1"}, {"31", "got 31"}}},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "directional", "direction": [0, @, 0], "irradiance": [1, 1, 1]})"),
       "lights[0].direction", {{"0", "expected a non-zero direction"}}},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "directional", "direction": [0, -1, 0], "irradiance": [1, @, 1]})"),
       "lights[0].irradiance", {{"-1", "expected non-negative values"}, {"1e30", "expected values of at most 1e12"}}},
      {scene_with(R"("m": {"type": "diffuse"})", R"({"type": "environment", "file": "sky.exr", "scale": @})"),
       "lights[0].scale",
       {{"-1", "expected a number in [0, 1e12], got -1"}, {"1e13", "expected a number in [0, 1e12]"},
        {"1e39", "expected a finite number"}}},
      {scene_with_shape(R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,@]], "material": "m"})"),
       "shapes[0].indices[0][2]",
       {{"-1", "vertex index -1 out of range (3 positions)"}, {"3", "vertex index 3 out of range (3 positions)"},
        {"18446744073709551615", "vertex index 18446744073709551615 out of range"},
        {"2.0", "expected an integer vertex index, got 2.0"}, {"\"2\"", "expected an integer vertex index"}}},
      {scene_with_shape(R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,@,0]], "indices": [[0,1,2]], "material": "m"})"),
       "shapes[0].positions[2][1]", {{"1e39", "expected a finite number within float range"}}},
      {scene_with_shape(R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0]], "uvs": [[0,0],[1,0],[0,@]], "indices": [[0,1,2]], "material": "m"})"),
       "shapes[0].uvs[2][1]", {{"1e39", "expected a finite number within float range"}}},
      {scene_with_shape(R"({"type": "sphere", "radius": 1, "material": "m", "transform": {"scale": [1, @, 1]}})"),
       "shapes[0].transform.scale", {{"0", "expected non-zero scale factors"}}},
      {scene_with_shape(R"({"type": "sphere", "radius": 1, "material": "m", "transform": {"translate": [1, @, 1]}})"),
       "shapes[0].transform.translate[1]", {{"1e39", "expected a finite number within float range"}}},
      {scene_with_shape(R"({"type": "sphere", "radius": 1, "material": "m", "transform": {"rotate": {"axis": [0, 1, 0], "degrees": @}}})"),
       "shapes[0].transform.rotate.degrees", {{"1e39", "expected a finite number within float range"}}},
      {scene_with_shape(R"({"type": "sphere", "radius": 1, "material": "m", "transform": {"rotate": {"axis": [0, @, 0], "degrees": 1}}})"),
       "shapes[0].transform.rotate.axis", {{"0", "expected a non-zero axis"}}},
      {scene_with_shape(R"({"type": "sphere", "radius": 1, "material": "m", "transform": {"matrix": [[1,0,0,0],[0,@,0,0],[0,0,1,0],[0,0,0,1]]}})"),
       "shapes[0].transform.matrix", {{"0", "the matrix is singular"}}},
  };
  for (const Field& f : fields)
    for (const auto& [value, expected] : f.bad) {
      std::string path = write_temp_file("numeric.json", with_value(f.json, value));
      std::string error = load_error(path);
      EXPECT_NE(error.find(path + ": " + f.path + ": "), std::string::npos) << f.path << " = " << value << "\n  gave: " << error;
      EXPECT_NE(error.find(expected), std::string::npos)
          << f.path << " = " << value << ": expected \"" << expected << "\"\n  gave: " << error;
    }
  // Beyond double range, every field: a JSON text error, with the line and the value's JSON path.
  for (const Field& f : fields) {
    std::string path = write_temp_file("numeric.json", with_value(f.json, "1e400"));
    std::string error = load_error(path);
    EXPECT_EQ(error.rfind(path + ":", 0), 0u) << error;
    EXPECT_NE(error.find(": " + f.path), std::string::npos) << error;
    EXPECT_NE(error.find(": malformed JSON: the number 1e400 is beyond the range of a double"), std::string::npos) << error;
  }
}

// The edges of each range load (a sphere's radius, like all geometry, need only be > 0: degenerate
// geometry is handled), and directions are normalised in double: in float [3e38, 3e38, 0] has an
// infinite length and [1e-30, 0, 0] a zero one.
TEST(SceneLoad, NumericFieldsAcceptTheEdgesOfTheirRanges) {
  SceneDescription s = load_scene(write_temp_file("edges.json", scene_with_camera(
      R"("width": 1, "height": 16384, "fov_y_degrees": 1e-30, "filter": {"type": "gaussian", "sigma": 5461, "radius": 16384})",
      R"(, "render": {"spp": 16777216, "max_depth": 0, "seed": 4294967295})")));
  EXPECT_EQ(s.camera.width, 1u);
  EXPECT_EQ(s.camera.height, 16384u);
  EXPECT_EQ(s.render.spp, 16777216u);
  EXPECT_EQ(s.render.max_depth, 0u);
  EXPECT_EQ(s.render.seed, 4294967295u);
  EXPECT_EQ(load_scene(write_temp_file("tiny-sphere.json", scene_with_shape(
                R"({"type": "sphere", "radius": 1e-300, "material": "m"})"))).shapes[0].radius, 1e-300);
  SceneDescription d = load_scene(write_temp_file("directions.json", scene_with(R"("m": {"type": "diffuse"})",
      R"({"type": "directional", "direction": [3e38, 3e38, 0], "irradiance": [1, 1, 1]},
         {"type": "directional", "direction": [1e-30, 0, 0], "irradiance": [1, 1, 1]},
         {"type": "point", "position": [1.4e18, 0, 0], "intensity": [1, 1, 1]})")));
  ASSERT_EQ(d.lights.size(), 3u);
  EXPECT_NEAR(d.lights[0].direction.x, std::sqrt(0.5f), 1e-6f);
  EXPECT_NEAR(d.lights[0].direction.y, std::sqrt(0.5f), 1e-6f);
  EXPECT_EQ(d.lights[1].direction, glm::vec3(1, 0, 0));
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

// Point and spot lights join the light BVH with their intensity; lights at infinity stay beside it, in
// proportion to their irradiance, whatever the scene's size.
TEST(SceneLoad, LightsAtInfinityAreChosenBesideTheTreeByIrradiance) {
  DeviceScene d = load_device_scene(write_temp_file("powers.json", scene_with(R"("m": {"type": "diffuse"})",
      R"({"type": "directional", "direction": [0, -1, 0], "irradiance": [3, 3, 3]},
         {"type": "point", "position": [0, 2, 0], "intensity": [1, 1, 1]},
         {"type": "environment", "radiance": [0.5, 0.5, 0.5]},
         {"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "intensity": [2, 2, 2], "outer_angle_degrees": 60, "inner_angle_degrees": 60})")));
  ASSERT_EQ(d.lights.size(), 4u);
  ASSERT_EQ(d.header.tree_light_count, 2u);
  EXPECT_EQ(d.lights[0].type, PC_LIGHT_POINT);
  EXPECT_EQ(d.lights[1].type, PC_LIGHT_SPOT);
  EXPECT_NEAR(d.light_bvh[0].lo.w, 3.0, 1e-6);  // 1 + 2
  EXPECT_EQ(d.lights[2].type, PC_LIGHT_DIRECTIONAL);
  EXPECT_EQ(d.lights[3].type, PC_LIGHT_ENVIRONMENT);
  EXPECT_EQ(d.header.env_light, 3u);
  // Irradiance on a surface facing the light: 3 for the directional light, pi x 0.5 for the environment.
  double sun = 3, sky = M_PI * 0.5;
  EXPECT_NEAR(d.header.infinite_irradiance, sun + sky, 1e-5);
  EXPECT_NEAR(d.lights[2].infinite_share, sun / (sun + sky), 1e-6);
  EXPECT_NEAR(d.lights[3].infinite_share, sky / (sun + sky), 1e-6);
  ASSERT_EQ(d.light_cdf.size(), 3u);
  EXPECT_FLOAT_EQ(d.light_cdf.back(), 1.0f);
}

// A scene without any light renders black: it is loaded, with a warning. Lights are emitting shapes
// (spheres, triangles left after clean-up, MTL materials with Ke) and entries of "lights" that emit.
TEST(SceneLoad, ASceneWithoutLightIsWarnedAbout) {
  write_temp_png("nolight/black.png", 1, 1, {0, 0, 0});
  write_temp_png("nolight/sky.png", 1, 1, {0, 0, 10});
  write_temp_file("nolight/lamp.mtl", "newmtl lamp\nKe 1 1 1\n");
  write_temp_file("nolight/lamp.obj", "mtllib lamp.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl lamp\nf 1 2 3\n");
  const std::string diffuse = R"("m": {"type": "diffuse"})";
  const std::string point = R"({"type": "point", "position": [0, 2, 0], "intensity": [@]})";
  struct Case {
    std::string json;
    bool warned;
  } cases[] = {
      {scene_with(diffuse), true},
      {scene_with(diffuse, with_value(point, "0, 0, 0")), true},
      {scene_with(diffuse, R"({"type": "environment", "radiance": [0, 0, 0]})"), true},
      {scene_with(diffuse, R"({"type": "environment", "file": "nolight/black.png", "scale": 5})"), true},
      {scene_with(diffuse, R"({"type": "environment", "file": "nolight/sky.png", "scale": 0})"), true},
      {scene_with(diffuse, R"({"type": "directional", "direction": [0, -1, 0], "irradiance": [0, 0, 0]})"), true},
      {scene_with_shape(R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[2,0,0]], "indices": [[0,1,2]],
                            "material": "m", "emission": [1, 1, 1]})"), true},  // collinear: removed by clean-up
      {scene_with_shape(R"({"type": "sphere", "radius": 1, "material": "m", "emission": [0, 0, 0.1]})"), false},
      {scene_with_shape(R"({"type": "mesh", "file": "nolight/lamp.obj", "material": "from_mtl"})"), false},
      {scene_with(diffuse, with_value(point, "0, 1e-30, 0")), false},
      {scene_with(diffuse, R"({"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0], "intensity": [1, 1, 1], "outer_angle_degrees": 30})"), false},
      {scene_with(diffuse, R"({"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]})"), false},
      {scene_with(diffuse, R"({"type": "environment", "radiance": [0.1, 0, 0]})"), false},
      {scene_with(diffuse, R"({"type": "environment", "file": "nolight/sky.png"})"), false},
  };
  for (const Case& c : cases) {
    std::string path = write_temp_file("nolight.json", c.json);
    std::string warning = path + ": the scene has no light (no shape or MTL material emits, and no entry of \"lights\" "
                                 "emits): it renders black";
    std::vector<std::string> warnings = load_scene(path).warnings;
    EXPECT_EQ(std::count(warnings.begin(), warnings.end(), warning), c.warned ? 1 : 0) << c.json;
  }
}

// ---- Textures, texture coordinates and materials from MTL files -----------------------------------------

namespace {

std::string textured_scene(const std::string& materials, const std::string& shape) {
  return R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
    "materials": )" + materials + R"(, "shapes": [)" + shape + "]}";
}

const char* const kTexturedTriangle =
    R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,2]], "material": "t")";

}  // namespace

TEST(SceneLoadTextures, BadTexturesAreClearErrors) {
  write_temp_png("tex/grey.png", 2, 1, {128, 128, 128, 255, 255, 255});
  struct Case {
    std::string materials, shape, expected;
  } cases[] = {
      {R"({"t": {"type": "diffuse", "reflectance": {"texture": "tex/none.png"}}})", "",
       "materials.t.reflectance.texture: " + temp_dir() + "/tex/none.png: cannot open the image file"},
      {R"({"t": {"type": "diffuse", "reflectance": {"texture": "tex/grey.png", "wrap": "tile"}}})", "",
       "materials.t.reflectance.wrap: unknown wrap mode \"tile\" (expected repeat, clamp or mirror)"},
      {R"({"t": {"type": "mirror", "reflectance": {"texture": "tex/grey.png", "scale": 2}}})", "",
       "materials.t.reflectance: unknown key \"scale\""},
      {R"({"t": {"type": "dielectric", "ior": 1.5, "transmittance": {"wrap": "clamp"}}})", "",
       "materials.t.transmittance: missing key \"texture\""},
      {R"({"t": {"type": "diffuse", "reflectance": "tex/grey.png"}})", "",
       "materials.t.reflectance: expected an array of 3 numbers or {\"texture\": FILE}"},
      {R"({"t": {"type": "phong", "diffuse": {"texture": "tex/grey.png"}, "specular": [0.1, 0.1, 0.1], "exponent": 10}})",
       "", "materials.t: the diffuse texture's largest value + specular exceeds 1"},
      {R"({"from_mtl": {"type": "diffuse"}})", "", "materials.from_mtl: the name \"from_mtl\" is reserved"},
      {R"({"t": {"type": "diffuse", "reflectance": {"texture": "tex/grey.png"}}})", std::string(kTexturedTriangle) + "}",
       "shapes[0]: material \"t\" has a texture, but the shape has no \"uvs\""},
      {R"({"t": {"type": "diffuse"}})", std::string(kTexturedTriangle) + R"(, "uvs": [[0, 0], [1, 0]]})",
       "shapes[0].uvs: expected one [u, v] per position (3), got 2"},
      {R"({"t": {"type": "diffuse"}})", std::string(kTexturedTriangle) + R"(, "uvs": [[0, 0], [1, 0], [0]]})",
       "shapes[0].uvs[2]: expected an array of 2 numbers"},
      {R"({"t": {"type": "diffuse"}})", R"({"type": "sphere", "radius": 1, "material": "from_mtl"})",
       "shapes[0].material: \"from_mtl\" needs a mesh shape"},
  };
  for (const Case& c : cases) {
    std::string path = write_temp_file("textures.json", textured_scene(c.materials, c.shape));
    std::string error = load_error(path);
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.materials << c.shape << "\n  gave: " << error;
    EXPECT_EQ(error.rfind(path, 0), 0u) << "the message starts with the file: " << error;
  }
}

TEST(SceneLoadTextures, InlineUvsBelongToPositionsAndTexturesAreShared) {
  write_temp_png("tex/grey.png", 2, 1, {128, 128, 128, 255, 255, 255});
  std::string scene = textured_scene(
      R"({"t": {"type": "diffuse", "reflectance": {"texture": "tex/grey.png"}},
          "u": {"type": "plastic", "diffuse": {"texture": "tex/grey.png", "wrap": "repeat"}},
          "v": {"type": "oren_nayar", "sigma_degrees": 10, "reflectance": {"texture": "tex/grey.png", "wrap": "mirror"}}})",
      R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[1,1,0],[0,1,0]], "indices": [[0,1,2],[2,3,0]],
          "uvs": [[0.1, 0.2], [0.3, 0.4], [0.5, 0.6], [0.7, 0.8]], "material": "t"})");
  DeviceScene d = load_device_scene(write_temp_file("inline-uvs.json", scene));
  ASSERT_TRUE(d.features & kFeatureTextures);
  ASSERT_EQ(d.textures.size(), 2u);  // one image, two wrap modes
  EXPECT_EQ(d.materials[0].color_texture, d.materials[1].color_texture);
  EXPECT_EQ(d.textures[d.materials[2].color_texture].wrap, PC_WRAP_MIRROR);
  ASSERT_EQ(d.uvs.size(), 4u);
  auto expect_uv = [](const pc_float4& got, float a, float b, float c, float e) {
    EXPECT_FLOAT_EQ(got.x, a);
    EXPECT_FLOAT_EQ(got.y, b);
    EXPECT_FLOAT_EQ(got.z, c);
    EXPECT_FLOAT_EQ(got.w, e);
  };
  expect_uv(d.uvs[0], 0.1f, 0.2f, 0.3f, 0.4f);  // triangle 0: corners 0, 1 ...
  expect_uv(d.uvs[1], 0.5f, 0.6f, 0, 0);        // ... and 2
  expect_uv(d.uvs[2], 0.5f, 0.6f, 0.7f, 0.8f);  // triangle 1: corners 2, 3 ...
  expect_uv(d.uvs[3], 0.1f, 0.2f, 0, 0);        // ... and 0
}

TEST(SceneLoadTextures, ObjTexcoordErrorsNameTheLine) {
  struct Case {
    std::string obj, expected;
  } cases[] = {
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/9 3/1\n", "vt.obj:5: texture coordinate index 9 out of range (1 texture"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2 3/1\n", "vt.obj:5: a face needs texture coordinates at all of its corners or at none"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt nan 0\nf 1/1 2/1 3/1\n", "vt.obj:4: expected 1 to 3 finite texture coordinates"},
  };
  for (const Case& c : cases) {
    write_temp_file("vt.obj", c.obj);
    std::string path = write_temp_file(
        "vt.json", scene_with_shape(R"({"type": "mesh", "file": "vt.obj", "material": "m"})"));
    std::string error = load_error(path);
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.obj << "\n  gave: " << error;
  }
}

namespace {

const char* const kMtl = R"(# a test library
newmtl matte
Kd 0.8 0.6 0.4
Ka 0.1 0.1 0.1
illum 2

newmtl shiny
Kd 0.7
Ks 0.5 0.5 0.5
Ns 50

newmtl glass
Kd 1 1 1
Ni 1.33
d 0.5
Tf 0.9 0.95 1
illum 7

newmtl lamp
Kd 0 0 0
Ke 4 3 2

newmtl wood
Kd 0.5 1 1
map_Kd -clamp on textures/wood.png

newmtl varnish
Kd 0.9 0.9 0.9
Ks 0.2 0.2 0.2
Ns 10
map_Kd textures/wood.png

newmtl unused
Kd 0.1 0.1 0.1
)";

// Seven faces: triangles 0-5 in a row on the plane z = 0, then a quad at z = 1; materials by usemtl.
const char* const kObj = R"(mtllib lib/materials.mtl
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 2 0 0
v 2 1 0
v 3 0 0
v 3 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vt 1 0
vt 0 1
vt 1 1
usemtl matte
f 1 2 3
usemtl lamp
f 2 4 3
usemtl shiny
f 2 5 4
usemtl glass
f 5 6 4
usemtl wood
f 5/1 7/2 6/3
usemtl matte
f 7 8 6
usemtl varnish
f 9/1 10/2 11/4 12/3
)";

// Writes the OBJ, its MTL library and the texture; returns the scene path.
std::string write_mtl_scene(const std::string& obj, const std::string& mtl, const std::string& shape_extra = "") {
  write_temp_file("mtl/lib/materials.mtl", mtl);
  write_temp_png("mtl/lib/textures/wood.png", 2, 1, {255, 128, 64, 64, 64, 64});
  write_temp_file("mtl/model.obj", obj);
  return write_temp_file("mtl-scene.json", textured_scene(R"({"m": {"type": "diffuse"}})",
                                                           R"({"type": "mesh", "file": "mtl/model.obj", "material": "from_mtl")" +
                                                               shape_extra + "}"));
}

}  // namespace

TEST(SceneLoadMtl, MaterialsEmissionAndTexturesPerFace) {
  SceneDescription scene = load_scene(write_mtl_scene(kObj, kMtl));
  // "m" from the scene file, then the MTL materials in the order the faces first use them; "unused" is not
  // there.
  ASSERT_EQ(scene.materials.size(), 7u);
  const char* names[] = {"m", "matte", "lamp", "shiny", "glass", "wood", "varnish"};
  for (size_t i = 0; i < 7; ++i) EXPECT_EQ(scene.materials[i].name, names[i]);

  const MaterialDesc &matte = scene.materials[1], &lamp = scene.materials[2], &shiny = scene.materials[3],
                     &glass = scene.materials[4], &wood = scene.materials[5], &varnish = scene.materials[6];
  EXPECT_EQ(matte.type_id, PC_MAT_DIFFUSE);
  EXPECT_EQ(matte.color, glm::vec3(0.8f, 0.6f, 0.4f));
  EXPECT_EQ(lamp.type_id, PC_MAT_DIFFUSE);
  EXPECT_EQ(lamp.color, glm::vec3(0));
  // Kd + Ks = 1.2: both scaled by 1 / 1.2.
  EXPECT_EQ(shiny.type_id, PC_MAT_PHONG);
  EXPECT_NEAR(shiny.color.x, 0.7f / 1.2f, 1e-6f);
  EXPECT_NEAR(shiny.specular.x, 0.5f / 1.2f, 1e-6f);
  EXPECT_FLOAT_EQ(shiny.exponent, 50.0f);
  EXPECT_EQ(glass.type_id, PC_MAT_DIELECTRIC);
  EXPECT_FLOAT_EQ(glass.ior, 1.33f);
  EXPECT_EQ(glass.color, glm::vec3(0.9f, 0.95f, 1.0f));
  // map_Kd: the texture (relative to the MTL file) times Kd.
  EXPECT_EQ(wood.type_id, PC_MAT_DIFFUSE);
  EXPECT_EQ(wood.color, glm::vec3(0.5f, 1, 1));
  ASSERT_NE(wood.color_texture, PC_INVALID);
  const TextureImage& texture = scene.textures[wood.color_texture];
  EXPECT_EQ(texture.file, temp_dir() + "/mtl/lib/textures/wood.png");
  EXPECT_EQ(texture.wrap, PC_WRAP_CLAMP);
  // Phong with a texture: the largest diffuse value is Kd times the largest texel, 0.9 in red (byte 255);
  // 0.9 + 0.2 = 1.1, so both are scaled by 1 / 1.1. The texture is loaded again for the other wrap mode.
  EXPECT_EQ(varnish.type_id, PC_MAT_PHONG);
  EXPECT_NEAR(varnish.color.x, 0.9f / 1.1f, 1e-6f);
  EXPECT_NEAR(varnish.specular.x, 0.2f / 1.1f, 1e-6f);
  EXPECT_EQ(scene.textures[varnish.color_texture].wrap, PC_WRAP_REPEAT);

  // Warnings: the ignored Ka and illum-less statements, and the two scaled phong materials.
  std::string warnings;
  for (const std::string& w : scene.warnings) warnings += w + "\n";
  EXPECT_NE(warnings.find("materials.mtl: ignored statements (not used by pathcl): Ka"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find("materials.mtl:7: material \"shiny\": Kd + Ks reaches 1.2"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find("material \"varnish\": Kd + Ks reaches 1.1"), std::string::npos) << warnings;

  // Per face: the material and the emission; the quad became two triangles.
  const ShapeDesc& shape = scene.shapes[0];
  EXPECT_EQ(shape.triangle_materials, (std::vector<uint32_t>{1, 2, 3, 4, 5, 1, 6, 6}));
  ASSERT_EQ(shape.triangle_emission.size(), 8u);
  for (size_t t = 0; t < 8; ++t)
    EXPECT_EQ(shape.triangle_emission[t], t == 1 ? glm::vec3(4, 3, 2) : glm::vec3(0)) << t;

  DeviceScene d = build_device_scene(scene);
  ASSERT_EQ(d.triangle_count, 8u);
  for (uint32_t t = 0; t < 8; ++t) EXPECT_EQ(d.shading[t].material, shape.triangle_materials[t]) << t;
  // One light: the lamp face, area 0.5, emission Ke.
  ASSERT_EQ(d.lights.size(), 1u);
  EXPECT_EQ(d.lights[0].prim, 1u);
  EXPECT_EQ(d.shading[1].light, 0u);
  EXPECT_FLOAT_EQ(d.lights[0].area, 0.5f);
  EXPECT_FLOAT_EQ(d.lights[0].emission.x, 4.0f);
  EXPECT_FLOAT_EQ(d.lights[0].emission.z, 2.0f);
  EXPECT_TRUE(d.features & kFeatureAreaLights);
  EXPECT_TRUE(d.features & kFeaturePhong);
  EXPECT_TRUE(d.features & kFeatureDielectric);
  EXPECT_TRUE(d.features & kFeatureTextures);
  // The wood face's uvs from its vt.
  ASSERT_EQ(d.uvs.size(), 16u);
  EXPECT_EQ(d.uvs[8].x, 0.0f);  // corner 0: vt 1 = (0, 0)
  EXPECT_EQ(d.uvs[8].z, 1.0f);  // corner 1: vt 2 = (1, 0)
  EXPECT_EQ(d.uvs[9].y, 1.0f);  // corner 2: vt 3 = (0, 1)
}

TEST(SceneLoadMtl, ErrorsNameTheObjOrMtlLine) {
  std::string obj_path = temp_dir() + "/mtl/model.obj", mtl_path = temp_dir() + "/mtl/lib/materials.mtl";
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  struct Case {
    std::string obj, mtl, shape_extra, expected;
  } cases[] = {
      {"mtllib lib/nothere.mtl\n" + tri + "usemtl matte\nf 1 2 3\n", kMtl, "",
       obj_path + ":1: cannot open the material file " + temp_dir() + "/mtl/lib/nothere.mtl"},
      {"mtllib lib/materials.mtl\n" + tri + "usemtl marble\nf 1 2 3\n", kMtl, "",
       obj_path + ":5: unknown material \"marble\" (not in its mtllib files)"},
      {tri + "usemtl matte\nf 1 2 3\n", kMtl, "", obj_path + ":4: unknown material \"matte\" (the file has no mtllib)"},
      {"mtllib lib/materials.mtl\n" + tri + "f 1 2 3\n", kMtl, "", obj_path + ":5: face without a material"},
      {"mtllib lib/materials.mtl\n" + tri + "usemtl m\nf 1 2 3\n", "newmtl m\nKd 0.5 0.5\n", "",
       mtl_path + ":2: Kd: expected 1 or 3 numbers"},
      {"mtllib lib/materials.mtl\n" + tri + "usemtl m\nf 1 2 3\n", "newmtl m\n\nKs 1.5 0 0\n", "",
       mtl_path + ":3: Ks: expected values in [0, 1]"},
      {"mtllib lib/materials.mtl\n" + tri + "usemtl m\nf 1 2 3\n", "Kd 1 1 1\n", "",
       mtl_path + ":1: Kd before any newmtl"},
      {"mtllib lib/materials.mtl\n" + tri + "usemtl m\nf 1 2 3\n", "newmtl m\nnewmtl m\n", "",
       mtl_path + ":2: material \"m\" defined twice"},
      {"mtllib lib/materials.mtl\n" + tri + "usemtl m\nf 1 2 3\n", "newmtl m\nmap_Kd -s 2 2 1 wood.png\n", "",
       mtl_path + ":2: map_Kd option -s is not supported"},
      {"mtllib lib/materials.mtl\n" + tri + "usemtl m\nf 1 2 3\n", "newmtl m\nmap_Kd textures/none.png\n", "",
       mtl_path + ":2: map_Kd: " + temp_dir() + "/mtl/lib/textures/none.png: cannot open the image file"},
      {"mtllib lib/materials.mtl\n" + tri + "usemtl wood\nf 1 2 3\n", kMtl, "",
       "shapes[0]: " + obj_path + ":6: face without texture coordinates (vt), but its material \"wood\" has a texture"},
      {"mtllib lib/materials.mtl\n" + tri + "usemtl matte\nf 1 2 3\n", kMtl, R"(, "emission": [1, 1, 1])",
       "shapes[0].emission: with \"from_mtl\" the emission comes from the MTL files (Ke)"},
  };
  for (const Case& c : cases) {
    std::string path = write_mtl_scene(c.obj, c.mtl, c.shape_extra);
    std::string error = load_error(path);
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.obj << c.mtl << "\n  gave: " << error;
  }
}

// ---- The JSON text ---------------------------------------------------------------------------------------

// A key given twice in one object is refused with its JSON path and both lines (nlohmann keeps the last
// silently); keys are compared as decoded, so "\u0061" is "a"; the same key in different objects is fine.
TEST(SceneLoad, DuplicateKeysAreRefusedWithBothLines) {
  struct Case {
    std::string json, expected;  // expected after "PATH:"
  } cases[] = {
      {R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
 "materials": {"m": {"type": "diffuse"}},
 "shapes": [{"type": "sphere", "radius": 1, "material": "m",
   "radius": 2}]})",
       "4: shapes[0].radius: duplicate key \"radius\" (first at line 3)"},
      {R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
 "materials": {"m": {"type": "diffuse"}, "glass": {"type": "dielectric", "ior": 1.5},
   "m": {"type": "mirror"}}, "shapes": []})",
       "3: materials.m: duplicate key \"m\" (first at line 2)"},
      {"{\"camera\": {\"position\": [0,0,5], \"look_at\": [0,0,0], \"width\": 8, \"height\": 8},\n"
       "\"materials\": {\"a \\\"q\\\" \\\\\": {\"type\": \"diffuse\"}, \"\\u0061 \\\"q\\\" \\\\\": {\"type\": \"diffuse\"}},\n"
       "\"shapes\": []}",
       "2: materials.a \"q\" \\: duplicate key \"a \"q\" \\\" (first at line 2)"},
      {"{\"camera\": {\"position\": [0,0,5], \"look_at\": [0,0,0], \"width\": 8, \"height\": 8},\n\"materials\": {},\n"
       "\"shapes\": [],\n\n\"camera\": {}}",
       "5: camera: duplicate key \"camera\" (first at line 1)"},
  };
  for (const Case& c : cases) {
    std::string path = write_temp_file("duplicate.json", c.json);
    EXPECT_EQ(load_error(path), path + ":" + c.expected);
  }
  // The same keys in different objects, and keys that differ only after an escape, load.
  EXPECT_EQ(error_of(R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
    "materials": {"m": {"type": "diffuse"}, "m\"": {"type": "diffuse"}, "m\\": {"type": "diffuse"}},
    "shapes": [{"type": "sphere", "radius": 1, "material": "m"}, {"type": "sphere", "radius": 2, "material": "m"}]})"),
            "");
}

// What the whole file can be instead of a scene: empty, UTF-16, valid JSON but not an object, nested
// deeper than any scene, a number beyond double range (nlohmann says "number overflow" without a
// position: the line and the JSON path come from our scan). A UTF-8 byte order mark is accepted.
TEST(SceneLoad, FilesThatAreNoSceneObjectAreNamed) {
  const std::string scene = R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8},
    "materials": {}, "shapes": []})";
  std::string deep = R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "width": 8, "height": 8}, "materials": {"m": )" +
                     std::string(100000, '[') + std::string(100000, ']') + "}, \"shapes\": []}";
  struct Case {
    std::string json, expected;  // expected after "PATH"
  } cases[] = {
      {"", ": the file is empty, expected a JSON scene (or a Mitsuba XML or pbrt scene)"},
      {" \n\t\r\n", ": the file is empty, expected a JSON scene (or a Mitsuba XML or pbrt scene)"},
      {std::string("\xff\xfe{\0", 4), ": the file is UTF-16, expected UTF-8 JSON"},
      {"[1, 2, 3]", ": (top level): expected an object with camera, materials and shapes, got an array"},
      {"\"scene\"", ": (top level): expected an object with camera, materials and shapes, got a string"},
      {"null", ": (top level): expected an object with camera, materials and shapes, got a null"},
      {deep, ":1: materials.m[0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0]"
             "[0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0]: "
             "nested deeper than 64 levels"},
      {"{\"camera\": {\"position\": [0,0,5], \"look_at\": [0,0,0], \"width\": 8, \"height\": 8},\n\"materials\": {},\n"
       "\"shapes\": [{\"type\": \"sphere\", \"radius\": 1e400, \"material\": \"m\"}]}",
       ":3: shapes[0].radius: malformed JSON: the number 1e400 is beyond the range of a double"},
      {"{\"camera\": {\"position\": [0,0,5], \"look_at\": [0,0,0], \"width\": 8, \"height\": 8},\n\"materials\": {},\n"
       "\"shapes\": [], \"render\": {\"spp\": -1e999}}",
       ":3: render.spp: malformed JSON: the number -1e999 is beyond the range of a double"},
      {"{\"camera\": {\"position\": [0,0,5], \"look_at\": [0, 1e400, 0]", 
       ":1: camera.look_at[1]: malformed JSON: the number 1e400 is beyond the range of a double"},
      {"\xef\xbb\xbf" + scene, ""},
  };
  for (const Case& c : cases) {
    std::string path = write_temp_file("whole.json", c.json);
    EXPECT_EQ(load_error(path), c.expected.empty() ? "" : path + c.expected) << c.json.substr(0, 80);
  }
}

// ---- OBJ statements: every error ours and on its line -------------------------------------------------

namespace {

// Loads `obj` (written as objs/NAME) as the only shape of a scene, with `material`; returns the error.
std::string obj_error(const std::string& name, const std::string& obj, const std::string& material = "m") {
  write_temp_file("objs/" + name, obj);
  return load_error(write_temp_file("objs.json", scene_with_shape(
      R"({"type": "mesh", "file": "objs/)" + name + R"(", "material": ")" + material + "\"}")));
}

std::string joined(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  return text;
}

}  // namespace

// Statements tinyobjloader fails on ("Failed parse 'f' line(e.g. zero value for face index. line 16.)")
// or reads wrong (a face of more than 255 corners) are refused as FILE:LINE: what.
TEST(SceneLoadObj, BadStatementsAreRefusedOnTheirLine) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  const std::string corner = " (expected v, v/vt, v//vn or v/vt/vn: non-zero integers, 1 for the first vertex)";
  std::string big;
  for (int i = 1; i <= 300; ++i) big += " " + std::to_string(i % 3 + 1);
  struct Case {
    std::string obj, expected;  // expected after "PATH:"
  } cases[] = {
      {tri + "f 1 2 0\n", "4: bad vertex reference \"0\" in \"f\"" + corner},
      {tri + "f 1 2 x\n", "4: bad vertex reference \"x\" in \"f\"" + corner},
      {tri + "f 1/0 2 3\n", "4: bad vertex reference \"1/0\" in \"f\"" + corner},
      {tri + "f 1// 2 3\n", "4: bad vertex reference \"1//\" in \"f\"" + corner},
      {tri + "f 1/1/1/1 2 3\n", "4: bad vertex reference \"1/1/1/1\" in \"f\"" + corner},
      {tri + "f 1 2 3 # a comment\n", "4: bad vertex reference \"#\" in \"f\"" + corner},
      {tri + "f 1 2 99999999999\n", "4: bad vertex reference \"99999999999\" in \"f\"" + corner},
      {tri + "l 1 0\n", "4: bad vertex reference \"0\" in \"l\"" + corner},
      {tri + "f" + big + "\n", "4: a face with 300 vertices, more than the 255 the OBJ reader supports (split it)"},
      // tinyobjloader's own extension: what it fails on is passed on with its line only.
      {tri + "vw 0 -1 0.5\n", "4: cannot read this statement"},
      // Lines end at \r too, as tinyobjloader reads them.
      {"v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 9\r", "4: face index 9 out of range (3 vertices)"},
      // A face of 2 corners is dropped (with a warning): the faces after it keep their own lines.
      {tri + "f 1 2\nf 3\nf 1 2 9\n", "6: face index 9 out of range (3 vertices)"},
  };
  int n = 0;
  for (const Case& c : cases) {
    std::string name = "bad" + std::to_string(n++) + ".obj";
    EXPECT_EQ(obj_error(name, c.obj), temp_dir() + "/objs/" + name + ":" + c.expected) << c.obj;
  }
}

// Faces of 1 or 2 corners are dropped with a warning naming the first one's line; the faces after them
// keep their own materials (tinyobjloader's dropping them used to shift usemtl onto the wrong faces).
// mtllib names may have escaped spaces, and Windows paths in mtllib and map_Kd are found with a warning.
TEST(SceneLoadObj, ShortFacesWarnEscapedSpacesAndBackslashPathsLoad) {
  write_temp_file("objs/my material.mtl", "newmtl a\nKd 1 0 0\n");
  write_temp_file("objs/lib/b.mtl", "newmtl b\nKd 0 1 0\nnewmtl wood\nmap_Kd textures\\wood.png\n");
  write_temp_png("objs/lib/textures/wood.png", 1, 1, {200, 100, 50});
  const std::string obj = temp_dir() + "/objs/short.obj";
  write_temp_file("objs/short.obj", joined({"mtllib my\\ material.mtl lib\\b.mtl", "v 0 0 0", "v 1 0 0", "v 0 1 0",
                                            "v 1 1 0", "vt 0 0", "usemtl a", "f 2 4", "f 3", "usemtl b", "f 1 2 3",
                                            "usemtl wood", "f 2/1 4/1 3/1", "f 1 2"}));
  SceneDescription s = load_scene(write_temp_file("short.json", scene_with_shape(
      R"({"type": "mesh", "file": "objs/short.obj", "material": "from_mtl"})")));
  const ShapeDesc& shape = s.shapes[0];
  ASSERT_EQ(shape.triangle_materials.size(), 2u);
  EXPECT_EQ(s.materials[shape.triangle_materials[0]].name, "b");
  EXPECT_EQ(s.materials[shape.triangle_materials[1]].name, "wood");
  ASSERT_NE(s.materials[shape.triangle_materials[1]].color_texture, PC_INVALID);
  EXPECT_EQ(s.textures[s.materials[shape.triangle_materials[1]].color_texture].file,
            temp_dir() + "/objs/lib/textures/wood.png");
  std::string warnings = joined(s.warnings);
  EXPECT_NE(warnings.find(obj + ":8: face with 2 vertices ignored (a face needs at least 3), and 2 more such faces\n"),
            std::string::npos) << warnings;
  EXPECT_NE(warnings.find(obj + ":1: mtllib: \"lib\\b.mtl\" not found, read as \"lib/b.mtl\" (backslashes taken as "
                          "directory separators)\n"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find(temp_dir() + "/objs/lib/b.mtl:4: map_Kd: \"textures\\wood.png\" not found, read as "
                          "\"textures/wood.png\" (backslashes taken as directory separators)\n"), std::string::npos)
      << warnings;
}

// MTL warnings are about what is rendered: a library's materials that no face uses say nothing, and the
// ignored statements listed are those of the materials used.
TEST(SceneLoadMtl, WarningsOnlyForMaterialsFacesUse) {
  write_temp_png("mtl-used/tex/wood.png", 1, 1, {200, 100, 50});
  write_temp_file("mtl-used/lib.mtl", joined({"newmtl used", "Kd 0.5 0.5 0.5", "Ka 0.1 0.1 0.1",
                                              "newmtl unused", "Kd 0.9 0.9 0.9", "Ks 0.5 0.5 0.5", "map_Bump bump.png",
                                              "illum 2", "newmtl unused_glass", "d 0.5", "map_Kd tex\\wood.png", "Ni 1.5", "illum 4"}));
  write_temp_file("mtl-used/model.obj", "mtllib lib.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl used\nf 1 2 3\n");
  const std::string lamp = R"(, {"type": "sphere", "radius": 0.1, "center": [0, 0, 3], "material": "m", "emission": [1, 1, 1]})";
  SceneDescription s = load_scene(write_temp_file("mtl-used.json", scene_with_shape(
      R"({"type": "mesh", "file": "mtl-used/model.obj", "material": "from_mtl"})" + lamp)));
  EXPECT_EQ(s.warnings, (std::vector<std::string>{temp_dir() + "/mtl-used/lib.mtl: ignored statements (not used by pathcl): Ka"}));
  // With the other two used too, everything is said.
  write_temp_file("mtl-used/model.obj", "mtllib lib.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl used\nf 1 2 3\n"
                                        "usemtl unused\nf 2 4 3\nusemtl unused_glass\nf 1 2 4\n");
  s = load_scene(write_temp_file("mtl-used.json", scene_with_shape(
      R"({"type": "mesh", "file": "mtl-used/model.obj", "material": "from_mtl"})")));
  std::string warnings = joined(s.warnings);
  const std::string lib = temp_dir() + "/mtl-used/lib.mtl";
  EXPECT_NE(warnings.find(lib + ": ignored statements (not used by pathcl): Ka, map_Bump\n"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find(lib + ":11: map_Kd: \"tex\\wood.png\" not found, read as \"tex/wood.png\""), std::string::npos) << warnings;
  EXPECT_NE(warnings.find(lib + ":11: map_Kd ignored: material \"unused_glass\" is a dielectric"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find(lib + ":4: material \"unused\": Kd + Ks reaches 1.4"), std::string::npos) << warnings;
}

TEST(SceneLoad, FloatExrTexelsKeepFullPrecisionAndRange) {
  // A 32-bit float EXR (an HDR environment with a sun far above half's 65504, and values half rounds).
  Image img;
  img.width = 3;
  img.height = 2;
  img.rgb = {1.0e5f, 2.5e6f, 0.1234567f, 1.0f / 3, 0.7071068f, 3.0e-6f, 0, 1, 2, 4.2e4f, 1.000123f, 0.5f,
             1e-3f, 123.456f, 7.0f, 65519.0f, 0.0f, 99999.0f};
  std::string path = temp_dir() + "/float.exr";
  write_exr(path, img);
  TextureImage t = load_texture_image(path);
  ASSERT_EQ(t.width, 3u);
  ASSERT_EQ(t.height, 2u);
  ASSERT_EQ(t.format, PC_TEXELS_FLOAT);
  for (size_t i = 0; i < 6; ++i)
    EXPECT_EQ(texel_linear(t, i), glm::vec3(img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2])) << "texel " << i;
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
  }
  ASSERT_EQ(d.light_bvh.size(), 5u);
  for (const LightBvhNode& n : d.light_bvh) EXPECT_TRUE(n.lo.w >= 0 && std::isfinite(n.lo.w)) << n.lo.w;
  EXPECT_EQ(d.light_cdf.size(), 1u);  // no lights at infinity
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

TEST(SceneLoad, ObjNormalsAreShadingNormalsPerCorner) {
  // Per corner, after the transform (inverse transpose: the scale by 2 in x halves a normal's x); a
  // zero vn is a corner without a normal, a face without vn is flat unless "smooth" fills it in.
  write_temp_file("meshes/vn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 0\nvn 1 0 1\nvn 0 0 3\n"
                                   "f 1//3 2//2 3//1\nf 1 4 2\n");
  for (bool smooth : {false, true}) {
    std::string path = write_temp_file("vn.json", scene_with_shape(R"({"type": "mesh", "file": "meshes/vn.obj", "material": "m",
      "transform": {"scale": [2, 1, 1]}, "smooth": )" + std::string(smooth ? "true" : "false") + "}"));
    const SceneDescription scene = load_scene(path);
    const TriangleMesh& mesh = scene.shapes[0].mesh;
    ASSERT_EQ(mesh.triangles.size(), 2u);
    ASSERT_EQ(mesh.normals.size(), 2u);
    EXPECT_EQ(mesh.normals[0][0], glm::vec3(0, 0, 1));
    EXPECT_NEAR(glm::distance(mesh.normals[0][1], glm::normalize(glm::vec3(0.5f, 0, 1))), 0.0f, 1e-6f);
    EXPECT_EQ(mesh.normals[0][2], glm::vec3(0));
    // The second face meets the first at 90 degrees, a crease: its own normal.
    for (const glm::vec3& n : mesh.normals[1]) EXPECT_EQ(n, smooth ? glm::vec3(0, 1, 0) : glm::vec3(0));
  }
  struct Case {
    std::string obj, expected;
  } cases[] = {
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn nan 0 0\nf 1//1 2//1 3//1\n", ":4: expected 3 finite normal coordinates, got \"vn nan 0 0\""},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n", ":5: normal index 2 out of range (1 normals)"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2 3//1\n", ":5: a face needs normals at all of its corners or at none"},
  };
  for (const Case& c : cases) {
    std::string mesh = write_temp_file("meshes/bad-vn.obj", c.obj);
    std::string error = load_error(write_temp_file("bad-vn.json", scene_with_shape(
        R"({"type": "mesh", "file": "meshes/bad-vn.obj", "material": "m"})")));
    EXPECT_NE(error.find(mesh + c.expected), std::string::npos) << error;
  }
}

namespace {

// The bytes of a value in little- or big-endian order, for binary PLY and STL files written by the tests.
template <class T>
std::string bytes_of(T value, bool big_endian = false) {
  std::string b(sizeof(T), '\0');
  std::memcpy(b.data(), &value, sizeof(T));
  if (big_endian) std::reverse(b.begin(), b.end());
  return b;
}

// A unit square in z = 0 as one quad, with a normal tilted towards +x at vertex 1 and uvs = (x, y); and
// a triangle. The PLY header as its format asks for.
std::string square_ply_header(const std::string& format) {
  return "ply\nformat " + format + " 1.0\ncomment made by scene_load_test\nelement vertex 5\n"
         "property float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
         "property float nz\nproperty float u\nproperty float v\nproperty uchar red\nproperty uchar green\n"
         "property uchar blue\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
}
const float kSquare[5][8] = {{0, 0, 0, 0, 0, 1, 0, 0}, {1, 0, 0, 1, 0, 1, 1, 0}, {1, 1, 0, 0, 0, 1, 1, 1},
                             {0, 1, 0, 0, 0, 1, 0, 1}, {0, 0, 1, 0, 0, 1, 0, 0}};

std::string square_ply_binary(bool big_endian) {
  std::string ply = square_ply_header(big_endian ? "binary_big_endian" : "binary_little_endian");
  for (const auto& v : kSquare) {
    for (float f : v) ply += bytes_of(f, big_endian);
    ply += std::string("\x80\x80\x80", 3);
  }
  ply += bytes_of(uint8_t(4));
  for (int32_t i : {0, 1, 2, 3}) ply += bytes_of(i, big_endian);
  ply += bytes_of(uint8_t(3));
  for (int32_t i : {0, 4, 1}) ply += bytes_of(i, big_endian);
  return ply;
}

SceneDescription load_mesh(const std::string& file, const std::string& options = "") {
  return load_scene(write_temp_file("mesh-format.json", scene_with_shape(
      R"({"type": "mesh", "file": ")" + file + R"(", "material": "m")" + options + "}")));
}

void expect_square(const SceneDescription& scene, bool uvs) {
  const ShapeDesc& s = scene.shapes[0];
  EXPECT_EQ(s.clean.input_vertices, 5u);
  EXPECT_EQ(s.clean.input_polygons, 2u);
  ASSERT_EQ(s.mesh.triangles.size(), 3u);
  ASSERT_EQ(s.mesh.normals.size(), 3u);
  ASSERT_EQ(s.mesh.uvs.size(), uvs ? 3u : 0u);
  for (size_t t = 0; t < 3; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = s.mesh.triangles[t][k];
      const glm::vec3 expected = glm::normalize(glm::vec3(kSquare[v][3], kSquare[v][4], kSquare[v][5]));
      EXPECT_NEAR(glm::distance(s.mesh.normals[t][k], expected), 0.0f, 1e-6f) << t << " " << k;
      if (uvs) { EXPECT_EQ(s.mesh.uvs[t][k], glm::vec2(kSquare[v][6], kSquare[v][7])) << t << " " << k; }
    }
}

}  // namespace

TEST(SceneLoadMeshFormats, PlyInAsciiAndBothBinaryOrdersWithNormalsAndUvs) {
  std::string ascii = square_ply_header("ascii");
  for (const auto& v : kSquare) {
    for (float f : v) ascii += std::to_string(f) + " ";
    ascii += "128 128 128\n";
  }
  ascii += "4 0 1 2 3\n3 0 4 1\n";
  for (const auto& [name, text] : {std::pair{"ascii.ply", ascii}, std::pair{"little.PLY", square_ply_binary(false)},
                                   std::pair{"big.ply", square_ply_binary(true)}}) {
    SCOPED_TRACE(name);
    std::string path = write_temp_file(std::string("meshes/") + name, text);
    SceneDescription scene = load_mesh(path);
    expect_square(scene, true);
    // The 8-bit colours (128, sRGB-encoded) are read in every encoding, at every corner.
    ASSERT_EQ(scene.shapes[0].mesh.colors.size(), 3u);
    for (const auto& corners : scene.shapes[0].mesh.colors)
      for (const glm::vec3& c : corners) EXPECT_EQ(c, glm::vec3(srgb_to_linear(128 / 255.0)));
  }
}

TEST(SceneLoadMeshFormats, PlyCornerTexcoordsAsMeshLabWritesThem) {
  std::string ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
                    "element face 1\nproperty list uchar uint vertex_indices\nproperty list uchar float texcoord\n"
                    "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 6 0.1 0.2 0.3 0.4 0.5 0.6\n";
  SceneDescription scene = load_mesh(write_temp_file("meshes/texcoord.ply", ply));
  const TriangleMesh& m = scene.shapes[0].mesh;
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_TRUE(m.normals.empty());
  ASSERT_EQ(m.uvs.size(), 1u);
  EXPECT_EQ(m.uvs[0][2], glm::vec2(0.5f, 0.6f));
}

TEST(SceneLoadMeshFormats, StlAsciiAndBinary) {
  // A tetrahedron; STL repeats the vertices per facet, CGAL's reader merges them. STL's facet normals
  // are the faces' own: no shading normals.
  const glm::vec3 v[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::string ascii = "solid tetra\n", binary = std::string(80, ' ') + bytes_of(uint32_t(4));
  for (const auto& f : faces) {
    ascii += "facet normal 0 0 0\nouter loop\n";
    binary += std::string(12, '\0');
    for (int k : f) {
      ascii += "vertex " + std::to_string(v[k].x) + " " + std::to_string(v[k].y) + " " + std::to_string(v[k].z) + "\n";
      for (int c = 0; c < 3; ++c) binary += bytes_of(v[k][c]);
    }
    ascii += "endloop\nendfacet\n";
    binary += std::string(2, '\0');
  }
  ascii += "endsolid tetra\n";
  for (const auto& [name, text] : {std::pair{"ascii.stl", ascii}, std::pair{"binary.STL", binary}}) {
    SCOPED_TRACE(name);
    SceneDescription scene = load_mesh(write_temp_file(std::string("meshes/") + name, text), R"(, "orient": true)");
    const ShapeDesc& s = scene.shapes[0];
    EXPECT_EQ(s.clean.input_vertices, 4u);
    EXPECT_EQ(s.mesh.triangles.size(), 4u);
    EXPECT_TRUE(s.clean.closed);
    EXPECT_EQ(s.clean.faces_flipped, 0u);
    EXPECT_TRUE(s.mesh.normals.empty());
  }
}

TEST(SceneLoadMeshFormats, OffWithNormals) {
  std::string off = "NOFF\n# the square of the PLY tests\n5 2 0\n";
  for (const auto& v : kSquare)
    for (int i : {0, 1, 2, 3, 4, 5}) off += std::to_string(v[i]) + (i == 5 ? "\n" : " ");
  off += "4 0 1 2 3\n3 0 4 1\n";
  expect_square(load_mesh(write_temp_file("meshes/square.off", off)), false);
  // Texture coordinates and colours: refused (CGAL 5.5's ASCII scanner reads them out of bounds).
  for (const char* keyword : {"STNOFF", "COFF"})
    EXPECT_NE(scene_load_error(write_temp_file("off-st.json", scene_with_shape(
                  R"({"type": "mesh", "file": ")" + write_temp_file("meshes/st.off", std::string(keyword) + "\n3 1 0\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n") + R"(", "material": "m"})")))
                  .find(std::string(keyword) + ": texture coordinates and colours in ASCII OFF files are not supported"),
              std::string::npos) << keyword;
  // Plain OFF: no normals; with "smooth" they are generated.
  SceneDescription plain = load_mesh(write_temp_file("meshes/plain.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                                     R"(, "smooth": true)");
  ASSERT_EQ(plain.shapes[0].mesh.normals.size(), 1u);
  EXPECT_EQ(plain.shapes[0].mesh.normals[0][0], glm::vec3(0, 0, 1));
}

TEST(SceneLoadMeshFormats, BadFilesSayWhatIsWrong) {
  const std::string good = square_ply_binary(false);
  const std::string stl = std::string(80, ' ') + bytes_of(uint32_t(2)) + std::string(60, '\0');
  struct Case {
    std::string file, content, expected;
  } cases[] = {
      {"points.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                     "end_header\n0 0 0\n1 1 1\n",
       "no faces (2 vertices: a point cloud? pathcl renders surfaces)"},
      {"zero-faces.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                         "element face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
       "no faces (1 vertices: a point cloud? pathcl renders surfaces)"},
      {"truncated.ply", good.substr(0, good.size() - 7), "truncated or garbled PLY file: cannot read face 1 of 2"},
      {"short.ply", good.substr(0, good.find("end_header") + 11 + 40), "truncated or garbled PLY file: cannot read vertex 1 of 5"},
      {"garbled.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 zero\n0 1 0\n3 0 1 2\n",
       "truncated or garbled PLY file: cannot read vertex 1 of 3"},
      {"index.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
       "face 0: vertex index 7 out of range (3 vertices before the faces)"},
      {"not.ply", "PLY?\n", "not a PLY file (its header cannot be read)"},
      // fuzz_obj_clean: an element without properties and a count of -1 (2^64 - 1 empty items) hung the reader.
      {"empty-element.ply", "ply\nformat binary_little_endian 1.0\nelement e -1\nelement vertex 0\nproperty float x\n"
                            "property float y\nproperty float z\nend_header\n",
       "no faces (0 vertices: a point cloud? pathcl renders surfaces)"},
      // fuzz_obj_clean: doubles beyond float range overflowed to infinity in CGAL's clean-up (GMP: SIGFPE).
      {"huge.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1e300 0 0\n0 1 0\n3 0 1 2\n",
       "vertex 1: coordinate is not finite or beyond float range"},
      // fuzz_obj_clean: CGAL's reader adds a property to the last element without checking there is one.
      {"property-first.ply", "ply\nformat ascii 1 float x\nproperty float y\nelement face 1\nend_header\n",
       "line 3: a property before any element (a garbled PLY header)"},
      {"truncated.stl", stl,
       "truncated or garbled binary STL file: its header says 2 triangles, 184 bytes, but the file has 144"},
      {"tiny.stl", "abc", "truncated STL file (3 bytes, less than the 84 of a binary STL header)"},
      {"garbled.stl", "solid x\nfacet normal 0 0 0\nouter loop\nvertex 0 0 zero\n", "truncated or garbled ASCII STL file: no facet could be read"},
      {"counts.off", "OFF\n100000 1 0\n0 0 0\n", "truncated or garbled OFF file: its header's count of vertices is 100000, not a number up to what a file of 21 bytes holds"},
      // fuzz_obj_clean: CGAL converts the counts' sum times 2.1 to int unchecked.
      {"negative.off", "nOFF\n4\n-2147483\n6\n0 0 0 0 0\n", "truncated or garbled OFF file: its header's count of vertices is -2147483, not a number up to what a file of 28 bytes holds"},
      {"garbled.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n", "truncated or garbled OFF file (CGAL's reader cannot read it)"},
      // fuzz_obj_clean: CGAL sizes a face by its count before reading it.
      {"huge-face.off", "OFF\n3 1 0\n0 0 0\n# a comment\n1 0 0\n0 1 0\n99999999999 0 1 2\n",
       "face 0 has 99999999999 vertices, more than the 255 pathcl reads (or a garbled OFF file)"},
      // fuzz_obj_clean: the same in a binary file, the bits of a float 1.0 read as a face's vertex count
      // (CGAL asked for 8.5 GB).
      {"huge-face-binary.off", std::string("OFF BINARY\n\0\0\0\3\0\0\0\1\0\0\0\0", 23) + std::string(36, '\0') +
                                   std::string("\x3f\x80\0\0", 4) + std::string(12, '\0'),
       "face 0 has 1065353216 vertices, more than the 255 pathcl reads (or a garbled binary OFF file)"},
      // fuzz_obj_clean: a face count cut short by the end of the file, which CGAL took as a count.
      {"short-binary.off", std::string("OFF BINARY\n\0\0\0\3\0\0\0\1\0\0\0\0", 23) + std::string(36, '\0') + "pro",
       "truncated binary OFF file: face 0 of 1 is cut short"},
      // fuzz_obj_clean: CGAL doubles the count of edges as an int, unchecked.
      {"edges-binary.off", std::string("OFF BINARY\n\0\0\0\0\0\0\0\0nan\0", 23) + std::string(16, '\0'),
       "truncated or garbled OFF file: its header's count of edges is 1851878912, not a number up to what the 28 "
       "bytes after its binary header hold"},
      // fuzz_obj_clean: CGAL reads "OFF." as the keyword OFF (letters and digits, then one character).
      {"dot-binary.off", std::string("OFF.  BINARY\n\0\0\0\3\0\0\0\1\0\0\0\0", 25) + std::string(36, '\0') +
                             std::string("\x3f\x80\0\0", 4) + std::string(12, '\0'),
       "face 0 has 1065353216 vertices, more than the 255 pathcl reads (or a garbled binary OFF file)"},
      {"dot-ascii.off", "OFF. 3 1 -2147483\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
       "truncated or garbled OFF file: its header's count of edges is -2147483, not a number up to what a file of 44 bytes holds"},
      {"colours-binary.off", std::string("COFF BINARY\n\0\0\0\0\0\0\0\0\0\0\0\0", 24),
       "COFF BINARY: texture coordinates and colours in OFF files are not supported (CGAL's OFF reader misreads "
       "them); write the mesh as PLY or OBJ"},
  };
  for (const Case& c : cases) {
    std::string mesh = write_temp_file("bad-formats/" + c.file, c.content);
    std::string error = load_error(write_temp_file("bad-formats.json", scene_with_shape(
        R"({"type": "mesh", "file": "bad-formats/)" + c.file + R"(", "material": "m"})")));
    EXPECT_EQ(error, mesh + ": " + c.expected) << c.file;
  }
  std::string ply = write_temp_file("bad-formats/good.ply", good);
  EXPECT_NE(load_error(write_temp_file("from-mtl-ply.json", scene_with_shape(
                R"({"type": "mesh", "file": "bad-formats/good.ply", "material": "from_mtl"})")))
                .find("shapes[0].material: \"from_mtl\" needs an OBJ file with mtllib"),
            std::string::npos);
}

TEST(SceneLoadMeshFormats, SmoothAngleNeedsSmoothAndARange) {
  std::string tri = R"({"type": "triangles", "positions": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,2]], "material": "m")";
  EXPECT_NE(load_error(write_temp_file("angle.json", scene_with_shape(tri + R"(, "smooth_angle_degrees": 30})")))
                .find("shapes[0].smooth_angle_degrees: has no effect without \"smooth\": true"),
            std::string::npos);
  EXPECT_NE(load_error(write_temp_file("angle.json", scene_with_shape(tri + R"(, "smooth": true, "smooth_angle_degrees": 190})")))
                .find("shapes[0].smooth_angle_degrees: expected an angle in [0, 180] degrees, got 190"),
            std::string::npos);
  EXPECT_EQ(load_error(write_temp_file("angle.json", scene_with_shape(tri + R"(, "smooth": true, "smooth_angle_degrees": 0})"))), "");
}

// MTL transparency (scene/mtl_load.cpp): glass only from illum 4, 6 or 7 with Ni; d (or 1 - Tr) is an
// opacity with a transparency illum model, or without illum (with a warning), and ignored with the
// others (Blender writes d 0 with illum 1 on opaque materials); map_d is always an opacity map; an
// emitter's opacity is dropped.
TEST(SceneLoadMtl, TransparencyFollowsTheIllumModel) {
  write_temp_png("mtl-d/mask.png", 1, 1, {128, 128, 128});
  write_temp_file("mtl-d/lib.mtl",
                  joined({"newmtl blender_opaque", "Kd 0.5 0.5 0.5", "d 0", "illum 1",
                          "newmtl sheer", "Kd 0.5 0.5 0.5", "d 0.25", "illum 9",
                          "newmtl no_illum", "Kd 0.5 0.5 0.5", "Tr 0.75",
                          "newmtl leaves", "Kd 0.5 0.5 0.5", "map_d mask.png", "illum 2",
                          "newmtl glass", "Ni 1.4", "d 0.1", "illum 4",
                          "newmtl lamp", "Ke 1 1 1", "d 0.5", "illum 9"}));
  std::string faces = "mtllib lib.mtl\n";
  int first = 1;  // a triangle of its own per material (clean-up removes duplicate faces)
  for (const char* m : {"blender_opaque", "sheer", "no_illum", "leaves", "glass", "lamp"}) {
    faces += "v " + std::to_string(first) + " 0 0\nv " + std::to_string(first + 1) + " 0 0\nv " + std::to_string(first) +
             " 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n";
    faces += std::string("usemtl ") + m + "\nf " + std::to_string(first) + "/" + std::to_string(first) + " " +
             std::to_string(first + 1) + "/" + std::to_string(first + 1) + " " + std::to_string(first + 2) + "/" +
             std::to_string(first + 2) + "\n";
    first += 3;
  }
  write_temp_file("mtl-d/model.obj", faces);
  SceneDescription s = load_scene(write_temp_file("mtl-d.json", scene_with_shape(
      R"({"type": "mesh", "file": "mtl-d/model.obj", "material": "from_mtl"})")));
  auto material = [&](const std::string& name) {
    for (const MaterialDesc& m : s.materials)
      if (m.name == name) return m;
    ADD_FAILURE() << "no material " << name;
    return MaterialDesc{};
  };
  EXPECT_EQ(material("blender_opaque").opacity, 1.0f);
  EXPECT_EQ(material("blender_opaque").type_id, PC_MAT_DIFFUSE);
  EXPECT_EQ(material("sheer").opacity, 0.25f);
  EXPECT_EQ(material("no_illum").opacity, 0.25f);
  EXPECT_EQ(material("leaves").opacity, 1.0f);
  ASSERT_NE(material("leaves").opacity_texture, PC_INVALID);
  EXPECT_EQ(s.textures[material("leaves").opacity_texture].file, temp_dir() + "/mtl-d/mask.png");
  EXPECT_EQ(material("glass").type_id, PC_MAT_DIELECTRIC);
  EXPECT_EQ(material("glass").ior, 1.4f);
  EXPECT_EQ(material("glass").opacity, 1.0f);
  EXPECT_EQ(material("lamp").opacity, 1.0f);
  std::string warnings = joined(s.warnings);
  const std::string lib = temp_dir() + "/mtl-d/lib.mtl";
  EXPECT_NE(warnings.find(lib + ":1: material \"blender_opaque\": d 0.000000 ignored: illum 1 has no transparency"),
            std::string::npos) << warnings;
  EXPECT_NE(warnings.find(lib + ":9: material \"no_illum\": d 0.250000 without illum taken as an opacity"),
            std::string::npos) << warnings;
  EXPECT_NE(warnings.find(lib + ":16: material \"glass\" rendered as glass of ior 1.4"), std::string::npos) << warnings;
  EXPECT_NE(warnings.find(lib + ":20: material \"lamp\": its opacity (d, map_d) is ignored"), std::string::npos) << warnings;
  DeviceScene d = build_device_scene(s);
  EXPECT_TRUE(d.features & kFeatureCutouts);
  // The opacity map is an entry of its own over the same texels, read as a grey map.
  uint32_t leaves = 0;
  while (leaves < s.materials.size() && s.materials[leaves].name != "leaves") ++leaves;
  ASSERT_LT(leaves, s.materials.size());
  uint32_t map = d.materials[leaves].opacity_texture;
  ASSERT_LT(map, d.textures.size());
  EXPECT_EQ(d.textures[map].format, PC_TEXELS_OPACITY8_RED);
  EXPECT_EQ(d.textures[map].offset, d.textures[material("leaves").opacity_texture].offset);
}
