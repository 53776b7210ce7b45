// Inputs that the fuzzers (fuzz/, scripts/fuzz) found to crash or to trip a sanitizer, kept in
// tests/scenes/fuzz-regressions/: each must load or be rejected with SceneError, never anything else.
// Scenes go through load_scene and build_device_scene; meshes through load_obj and clean_mesh with every
// combination of orient and smooth normals (the fuzzer's leading option byte is stripped from them).
// fuzz_render's findings (*.scene, in its input format: fuzz/render_input.h) are also rendered, tiny as
// the fuzzer renders them, on the test device ($PATHCL_TEST_DEVICE).
#include <algorithm>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fuzz/render_input.h"
#include "runtime/errors.h"
#include "runtime/renderer.h"
#include "scene/bvh_build.h"
#include "scene/device_scene_build.h"
#include "scene/mesh_clean.h"
#include "scene/scene_description.h"
#include "scene/scene_error.h"
#include "test_support.h"

namespace {

std::string regressions() { return std::string(PATHCL_TEST_SCENES) + "/fuzz-regressions"; }

std::vector<std::string> files_ending(const std::string& extension) {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(regressions()))
    if (entry.path().extension() == extension) files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

// "" if the scene loads and flattens, the SceneError message if it is rejected; fails the test on any
// other exception.
std::string scene_outcome(const std::string& path) {
  try {
    DeviceScene scene = build_device_scene(load_scene(path));
    EXPECT_LE(scene.bvh.depth, kBvhMaxDepth) << path;
  } catch (const SceneError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << path << ": unexpected exception: " << e.what();
    return "unexpected";
  }
  return "";
}

// A fuzz_render input, unpacked, loaded and rendered tiny as fuzz_render does: "rendered" if the film is
// clean, else what went wrong: "SceneError: message" or "UsageError: message" for the exit-2 class, "out
// of memory: message" for a reported lack of memory (the outcomes a scene may have), anything else.
std::string render_outcome(const std::string& path) {
  const std::string scene_path =
      fuzz::write_render_input(fuzz::split_render_input(read_text_file(path)), temp_dir() + "/render");
  try {
    SceneDescription scene = load_scene(scene_path);
    const RenderOptions options = fuzz::tiny_render(scene);
    const DeviceScene device_scene = build_device_scene(scene);
    const RenderResult result = render(test_device(), device_scene, options);
    const std::string problem = fuzz::render_problem(result, device_scene, options);
    return problem.empty() ? "rendered" : problem;
  } catch (const SceneError& e) {
    return std::string("SceneError: ") + e.what();
  } catch (const UsageError& e) {
    return std::string("UsageError: ") + e.what();
  } catch (const RuntimeFailure& e) {
    return (fuzz::reported_out_of_memory(e.what()) ? "out of memory: " : "RuntimeFailure: ") + std::string(e.what());
  } catch (const std::exception& e) {
    return std::string("unexpected exception: ") + e.what();
  }
}

}  // namespace

TEST(FuzzRegression, ScenesLoadOrFailWithSceneError) {
  const std::vector<std::string> scenes = files_ending(".json");
  ASSERT_FALSE(scenes.empty());
  for (const std::string& path : scenes) {
    SCOPED_TRACE(path);
    scene_outcome(path);
  }
}

TEST(FuzzRegression, MeshesLoadAndCleanOrFailWithSceneError) {
  const std::vector<std::string> meshes = files_ending(".obj");
  ASSERT_FALSE(meshes.empty());
  for (const std::string& path : meshes)
    for (int bits = 0; bits < 4; ++bits) {
      SCOPED_TRACE(path + " orient=" + std::to_string(bits & 1) + " smooth=" + std::to_string(bits >> 1));
      CleanOptions options;
      options.orient = (bits & 1) != 0;
      options.smooth_normals = (bits & 2) != 0;
      try {
        const PolygonSoup soup = load_obj(path);
        CleanReport report;
        const TriangleMesh mesh = clean_mesh(soup, options, report);
        for (const auto& t : mesh.triangles)
          for (uint32_t v : t) ASSERT_LT(v, mesh.positions.size());
        // Every triangle names its source polygon and corners, at the same positions.
        ASSERT_EQ(mesh.source_polygon.size(), mesh.triangles.size());
        ASSERT_EQ(mesh.source_corners.size(), mesh.triangles.size());
        ASSERT_EQ(mesh.uvs.size(), soup.uvs.empty() ? 0 : mesh.triangles.size());
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
          const auto& polygon = soup.polygons.at(mesh.source_polygon[t]);
          for (int j = 0; j < 3; ++j)
            ASSERT_EQ(soup.positions[polygon.at(mesh.source_corners[t][j])], mesh.positions[mesh.triangles[t][j]]);
        }
      } catch (const SceneError&) {
        // Rejected: fine.
      } catch (const std::exception& e) {
        ADD_FAILURE() << "unexpected exception: " << e.what();
      }
    }
}

TEST(FuzzRegression, RenderFindingsRenderCleanlyOrExitWith2) {
  const std::vector<std::string> inputs = files_ending(".scene");
  ASSERT_FALSE(inputs.empty());
  for (const std::string& path : inputs) {
    const std::string outcome = render_outcome(path);
    EXPECT_TRUE(outcome == "rendered" || outcome.rfind("SceneError: ", 0) == 0 || outcome.rfind("UsageError: ", 0) == 0 ||
                outcome.rfind("out of memory: ", 0) == 0)
        << path << ": " << outcome;
  }
}

// The render findings that must render (their fix was in the kernels, not a new rejection).
TEST(FuzzRegression, RenderFindingsRender) {
  const std::string dir = regressions();
  // GGX at the smallest roughness (alpha 1e-4): 1 + (alpha^2 - 1) cos^2 rounded to 0 for normals within
  // 1e-4 rad of the surface normal, D became infinite and the sample weight infinity / infinity = NaN.
  EXPECT_EQ(render_outcome(dir + "/render-rough-conductor-smooth-nan.scene"), "rendered");
  // A light sampled from 1e18 away (inside a sphere of radius 1e18) has a solid-angle pdf of about 1e36:
  // the power heuristic's squares overflowed and its weight was infinity / infinity = NaN.
  EXPECT_EQ(render_outcome(dir + "/render-mis-pdf-overflow.scene"), "rendered");
  // A conductor channel with "specular": 0 (eta 1, k 0): the Fresnel term, a difference of two equal
  // numbers there, came out slightly negative, and so did the radiance.
  EXPECT_EQ(render_outcome(dir + "/render-conductor-fresnel-negative.scene"), "rendered");
}

// The render findings whose fix is in the loader: rejected, with the place and what was expected.
TEST(FuzzRegression, RenderFindingsRejectedWithAMessage) {
  const std::string dir = regressions();
  // nlohmann parses every non-negative integer as unsigned, and only the upper bound was checked for it:
  // a 16 x 0 film reached clCreateBuffer (CL_INVALID_BUFFER_SIZE), and spp 0 rendered an empty film.
  EXPECT_NE(render_outcome(dir + "/render-camera-height-zero.scene").find("camera.height: expected an integer in [1, 16384]"),
            std::string::npos);
  EXPECT_NE(render_outcome(dir + "/render-spp-zero.scene").find("render.spp: expected an integer in [1, 16777216]"),
            std::string::npos);
  // An emission of 3.4e38: light sampling made infinite samples, and a radiance above 1.8e19 seen directly
  // overflows the film's sum of squares.
  EXPECT_NE(render_outcome(dir + "/render-emission-overflow.scene").find("shapes[0].emission: expected values of at most 1e12"),
            std::string::npos);
}

// The messages of the inputs whose fix was to reject them.
TEST(FuzzRegression, RejectedWithAMessage) {
  const std::string dir = regressions();
  // nlohmann reports a number too large for a double as out_of_range, not parse_error.
  EXPECT_NE(scene_outcome(dir + "/json-number-overflow.json").find("malformed JSON"), std::string::npos);
  // A finite double beyond float range used to become an infinite vertex.
  EXPECT_NE(scene_outcome(dir + "/json-float-overflow-no-transform.json")
                .find("shapes[0].positions[4][0]: expected a finite number within float range"),
            std::string::npos);
  EXPECT_NE(scene_outcome(dir + "/json-sphere-translate-overflow.json")
                .find("shapes[0].transform: the transform takes the sphere to infinity"),
            std::string::npos);
  // Tiny but valid extents load (they used to convert NaN to int in the BVH builder).
  EXPECT_EQ(scene_outcome(dir + "/json-bvh-tiny-extent.json"), "");
}
