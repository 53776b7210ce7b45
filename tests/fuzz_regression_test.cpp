// Inputs that the fuzzers (fuzz/, scripts/fuzz) found to crash or to trip a sanitizer, kept in
// tests/scenes/fuzz-regressions/: each must load or be rejected with SceneError, never anything else.
// Scenes (JSON, and the importers' Mitsuba XML and pbrt files) go through load_scene and build_device_scene; meshes through load_obj and clean_mesh with every
// combination of orient and smooth normals (the fuzzer's leading option byte is stripped from them).
// fuzz_render's findings (*.scene, in its input format: fuzz/render_input.h) are also rendered, tiny as
// the fuzzer renders them, on the test device ($PATHCL_TEST_DEVICE). fuzz_gltf's (*.gltf, *.glb) go through
// load_gltf, fuzz_texture's (image files by extension) through load_texture_image and decode_texture_image;
// the fuzzers' option byte is stripped from all of them.
#include <algorithm>
#include <cmath>
#include <cstring>
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
#include "scene/gltf_load.h"
#include "scene/mesh_clean.h"
#include "scene/scene_description.h"
#include "scene/scene_error.h"
#include "scene/texture_load.h"
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

// "" if load() returns, the SceneError message if it throws one; fails the test on any other exception.
template <class Load>
std::string load_outcome(const std::string& path, Load load) {
  try {
    load();
  } catch (const SceneError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << path << ": unexpected exception: " << e.what();
    return "unexpected";
  }
  return "";
}

// The outcome of loading and flattening a scene file.
std::string scene_outcome(const std::string& path) {
  return load_outcome(path, [&] {
    DeviceScene scene = build_device_scene(load_scene(path));
    EXPECT_LE(scene.bvh.depth, kBvhMaxDepth) << path;
  });
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

// The outcome of loading a glTF file.
std::string gltf_outcome(const std::string& path) {
  return load_outcome(path, [&] {
    std::vector<std::string> warnings;
    load_gltf(path, warnings);
  });
}

// The outcome of an image file, read from the file or (as an image embedded in glTF) decoded from its bytes.
std::string texture_outcome(const std::string& path, bool in_memory) {
  return load_outcome(path, [&] {
    if (in_memory)
      decode_texture_image(path, read_text_file(path));
    else
      load_texture_image(path);
  });
}

}  // namespace

TEST(FuzzRegression, GltfFilesLoadOrFailWithSceneError) {
  std::vector<std::string> files = files_ending(".gltf"), glb = files_ending(".glb");
  files.insert(files.end(), glb.begin(), glb.end());
  ASSERT_FALSE(files.empty());
  for (const std::string& path : files) gltf_outcome(path);
}

TEST(FuzzRegression, ImagesLoadOrFailWithSceneError) {
  size_t images = 0;
  for (const char* extension : {".png", ".jpg", ".bmp", ".tga", ".hdr", ".exr"})
    for (const std::string& path : files_ending(extension)) {
      ++images;
      texture_outcome(path, false);
      texture_outcome(path, true);
    }
  ASSERT_GT(images, 0u);
}

// glTF offsets are unsigned 64-bit numbers: an offset near 2^64 plus a length wrapped around to a small sum
// that passed the range check, and the accessor read before its buffer (fuzz_gltf).
TEST(FuzzRegression, GltfOffsetsThatWrapAreRejected) {
  const std::string dir = regressions();
  EXPECT_NE(gltf_outcome(dir + "/gltf-accessor-offset-wraps.gltf").find("4 elements from byte 18446744073709551600 reach beyond the end of bufferViews[0] (48 bytes)"),
            std::string::npos);
  EXPECT_NE(gltf_outcome(dir + "/gltf-view-offset-wraps.gltf").find("bufferViews[0]: 48 bytes from byte 18446744073709551600 reach beyond the end of buffers[0] (140 bytes)"),
            std::string::npos);
}

// tinygltf passed an image's buffer view to the image callback unchecked: a GLB image view past the end of
// its BIN chunk was read out of bounds (fuzz_gltf, ASan).
TEST(FuzzRegression, GltfImageViewPastItsBufferIsRejected) {
  const std::string message = gltf_outcome(regressions() + "/gltf-image-view-past-buffer.glb");
  EXPECT_NE(message.find("gltf-image-view-past-buffer.glb: images[0]: bufferViews["), std::string::npos) << message;
  EXPECT_NE(message.find("reach beyond the end of buffers[0]"), std::string::npos) << message;
}

// tinygltf's GetNumberAsInt converted a light index of 1e30 to int (undefined behaviour; found by reading
// the loader for fuzz_gltf, which confirmed it with UBSan).
TEST(FuzzRegression, GltfLightIndexThatIsNoIntegerIsRejected) {
  const std::string message = gltf_outcome(regressions() + "/gltf-light-index-huge.gltf");
  EXPECT_NE(message.find("nodes[2]: KHR_lights_punctual: expected an integer light index"), std::string::npos) << message;
}

// stb_image 2.27 built a JPEG Huffman table of more than 256 codes out of bounds (fuzz_texture, UBSan).
TEST(FuzzRegression, JpegHuffmanTableOfTooManyCodesIsRejected) {
  const std::string path = regressions() + "/texture-jpeg-huffman-overflow.jpg";
  for (bool in_memory : {false, true}) {
    const std::string message = texture_outcome(path, in_memory);
    EXPECT_NE(message.find("texture-jpeg-huffman-overflow.jpg: corrupt JPEG image: a Huffman table of "), std::string::npos)
        << message;
  }
}

// stb_image decoded a 19-byte RLE TGA file saying 32771 x 2304 texels, reading zeros past its end: 3 s and
// 600 MB (fuzz_texture, a slow unit). A file too short for its texels is truncated.
TEST(FuzzRegression, TruncatedTgaIsRejected) {
  const std::string path = regressions() + "/texture-tga-truncated-huge.tga";
  for (bool in_memory : {false, true})
    EXPECT_NE(texture_outcome(path, in_memory).find("texture-tga-truncated-huge.tga: truncated TGA image: its 75504384 "
                                                     "texels take at least 1179756 bytes, the file has 19"),
              std::string::npos)
        << texture_outcome(path, in_memory);
  // The same with a header cut short (17 bytes, stb_image reads the missing ones as zeros).
  const std::string short_header = regressions() + "/texture-tga-short-header.tga";
  for (bool in_memory : {false, true})
    EXPECT_NE(texture_outcome(short_header, in_memory).find("truncated TGA image: its 248472576 texels take at least 993890304 bytes, the file has 17"),
              std::string::npos)
        << texture_outcome(short_header, in_memory);
}

// stb_image 2.27 looped forever on a Radiance HDR RLE packet of length 0 (fuzz_texture, a timeout).
TEST(FuzzRegression, HdrRlePacketOfLengthZeroIsRejected) {
  const std::string path = regressions() + "/texture-hdr-rle-zero-packet.hdr";
  for (bool in_memory : {false, true})
    EXPECT_NE(texture_outcome(path, in_memory).find("texture-hdr-rle-zero-packet.hdr: corrupt or truncated Radiance HDR "
                                                     "image: scanline 0 has an RLE packet of length 0"),
              std::string::npos)
        << texture_outcome(path, in_memory);
}

// texel_nearest with clamping converted a NaN coordinate to an integer (fuzz_texture, UBSan): texel 0, as
// the other wrap modes give.
TEST(FuzzRegression, TexelNearestOfNanIsTexelZero) {
  TextureImage image;
  image.width = 2;
  image.height = 1;
  image.format = PC_TEXELS_FLOAT;
  image.words.resize(6);
  const float texels[6] = {1, 2, 3, 4, 5, 6};
  std::memcpy(image.words.data(), texels, sizeof texels);
  for (uint32_t wrap : {PC_WRAP_CLAMP, PC_WRAP_REPEAT, PC_WRAP_MIRROR}) {
    image.wrap = wrap;
    EXPECT_EQ(texel_nearest(image, glm::vec2(NAN, NAN)), glm::vec3(1, 2, 3)) << wrap;
  }
}

TEST(FuzzRegression, ScenesLoadOrFailWithSceneError) {
  // JSON scenes, and fuzz_mitsuba's and fuzz_pbrt's Mitsuba XML and pbrt files (load_scene tells them apart).
  std::vector<std::string> scenes = files_ending(".json");
  ASSERT_FALSE(scenes.empty());
  for (const char* imported : {".xml", ".pbrt"})
    for (const std::string& path : files_ending(imported)) scenes.push_back(path);
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
