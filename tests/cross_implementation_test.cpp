// The same bits on two independent OpenCL implementations: small renders of every feature (each material,
// light type, shape, texture, sampler, camera, pixel filter, smooth normals, the environment maps) on
// PoCL and on Oclgrind (an interpreter with its own builtins, registered for this test's processes only
// through OCL_ICD_VENDORS, see tests/CMakeLists.txt) must be bitwise equal, and Oclgrind, which checks
// every memory access, must report no invalid access and no data race on them. Then the two devices
// render one image together: the start-up probe puts them in one arithmetic class.
#include <array>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>

#include <gtest/gtest.h>

#include "runtime/image_io.h"
#include "test_support.h"

namespace fs = std::filesystem;

namespace {

const std::string kScenes = std::string(PATHCL_SOURCE_DIR) + "/scenes";

struct Case {
  std::string name, scene, options;
  uint32_t bvh_width = 0;  // PATHCL_BVH_WIDTH for both devices; 0: each device's own layout
};

// A scene file in the test's directory, with the repository's meshes at absolute paths.
std::string scene_file(const std::string& name, const std::string& json) { return write_temp_file(name + ".json", json); }

// A quad with a PNG texture on it, a textured sphere, a smooth-shaded mesh, an emitting sphere, an
// environment map, a tent filter.
std::string textured_scene() {
  std::vector<unsigned char> checker(8 * 8 * 3), sky(16 * 8 * 3);
  for (int i = 0; i < 64; ++i)
    for (int c = 0; c < 3; ++c) checker[3 * i + c] = ((i % 8 + i / 8) % 2) ? 230 : uint8_t(40 + 60 * c);
  for (int i = 0; i < 128; ++i)
    for (int c = 0; c < 3; ++c) sky[3 * i + c] = uint8_t((i / 16 < 3 ? 250 : 60) - 20 * c + (i % 16 == 5 ? 5 : 0));
  write_temp_png("checker.png", 8, 8, checker);
  write_temp_png("sky.png", 16, 8, sky);
  return scene_file("textured", R"({
    "camera": {"position": [0, 1, 3.5], "look_at": [0, 0.8, 0], "width": 16, "height": 12,
               "filter": {"type": "tent", "radius": 1.5}},
    "materials": {
      "checker": {"type": "diffuse", "reflectance": {"texture": "checker.png", "wrap": "mirror"}},
      "globe":   {"type": "plastic", "diffuse": {"texture": "checker.png"}, "roughness": 0.3},
      "white":   {"type": "oren_nayar", "reflectance": [0.7, 0.7, 0.7], "sigma_degrees": 20},
      "lamp":    {"type": "diffuse", "reflectance": [0, 0, 0]}},
    "shapes": [
      {"type": "triangles", "positions": [[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]],
       "uvs": [[0, 0], [3, 0], [3, 3], [0, 3]], "indices": [[0, 2, 1], [0, 3, 2]], "material": "checker"},
      {"type": "sphere", "center": [-0.6, 0.5, 0], "radius": 0.45, "material": "globe",
       "transform": {"rotate": {"axis": [1, 1, 0], "degrees": 30}}},
      )" + icosphere_json(0.4f, 2, false) + R"(, "material": "white", "smooth": true, "transform": {"translate": [0.6, 0.5, 0]}},
      {"type": "sphere", "center": [0, 1.8, 0.5], "radius": 0.15, "material": "lamp", "emission": [20, 18, 15]}],
    "lights": [{"type": "environment", "file": "sky.png", "scale": 0.8}],
    "render": {"spp": 2, "max_depth": 5, "seed": 3}})");
}

// What the Mitsuba and pbrt importers map onto: a checkerboard floor, a thin glass pane, a metal mirror
// (eta and k) and pbrt's equal-area environment map, rotated, looked up bilinearly across its folded edges.
std::string imported_features_scene() {
  std::vector<unsigned char> sky(16 * 16 * 3);
  for (int i = 0; i < 256; ++i)
    for (int c = 0; c < 3; ++c) sky[3 * i + c] = uint8_t((i / 16 < 5 ? 240 : 50) - 15 * c + (i % 16 == 0 ? 10 : 0));
  write_temp_png("sky-square.png", 16, 16, sky);
  return scene_file("imported-features", R"({
    "camera": {"position": [0, 1, 3.5], "look_at": [0, 0.6, 0], "width": 12, "height": 9},
    "materials": {
      "floor": {"type": "diffuse", "reflectance": {"checkerboard": {"color0": [0.8, 0.7, 0.6], "color1": [0.1, 0.2, 0.3],
                                                                     "tiles": [3, 5], "offset": [0.25, 0.5]}}},
      "pane":  {"type": "thin_dielectric", "ior": 1.5, "transmittance": [0.9, 0.95, 1]},
      "gold":  {"type": "mirror", "eta": [0.18, 0.42, 1.37], "k": [3.42, 2.35, 1.77]}},
    "shapes": [
      {"type": "triangles", "positions": [[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]],
       "uvs": [[0, 0], [1, 0], [1, 1], [0, 1]], "indices": [[0, 2, 1], [0, 3, 2]], "material": "floor"},
      {"type": "triangles", "positions": [[-1, 0, 0.5], [0, 0, 0.5], [0, 1.2, 0.5], [-1, 1.2, 0.5]],
       "indices": [[0, 1, 2], [0, 2, 3]], "material": "pane"},
      {"type": "sphere", "center": [0.6, 0.5, 0], "radius": 0.45, "material": "gold"}],
    "lights": [{"type": "environment", "file": "sky-square.png", "mapping": "equal_area", "scale": 0.8,
                "transform": {"rotate": {"axis": [1, 0.3, 0], "degrees": -80}}}],
    "render": {"spp": 2, "max_depth": 5, "seed": 3}})");
}

// A copy of a bundled scene (or with `from`, another scene file whose meshes are the bundled ones) at
// another resolution.
std::string resized(const std::string& bundled, int width, int height, int spp, const std::string& from = "") {
  std::string text = read_text_file(from.empty() ? kScenes + "/" + bundled + ".json" : from);
  for (size_t at = 0; (at = text.find("\"../../scenes/meshes/", at)) != std::string::npos;) text.erase(at + 1, 13);
  auto replace = [&](const std::string& key, int value) {
    size_t at = text.find("\"" + key + "\":");
    size_t end = text.find_first_of(",}", at);
    text = text.substr(0, at) + "\"" + key + "\": " + std::to_string(value) + text.substr(end);
  };
  replace("width", width);
  replace("height", height);
  replace("spp", spp);
  for (size_t at = 0; (at = text.find("\"meshes/", at)) != std::string::npos;) text.insert(at + 1, kScenes + "/");
  // Named by its size too: cases of one scene at several sizes each keep their own file.
  return scene_file(bundled + "-" + std::to_string(width) + "x" + std::to_string(height) + "-" + std::to_string(spp), text);
}

// A copy of scene file `file` rendered with this render.integrator object (an integrator's own options,
// which the command line does not take).
std::string with_integrator(const std::string& file, const std::string& name, const std::string& integrator) {
  std::string text = read_text_file(file);
  const size_t at = text.find("\"render\": {");
  text.insert(at + 11, "\"integrator\": " + integrator + ", ");
  return scene_file(name, text);
}

const std::string kEveryAov = "albedo,normal,depth,position,uv,material_id";

// Each case is a test of its own (CTest runs them in two shards at once: tests/CMakeLists.txt).
constexpr size_t kCases = 24;

std::array<Case, kCases> make_cases() {
  // Oclgrind interprets unoptimised code (kernel_program.cpp): a few hundred paths take a second or two.
  std::string cornell = resized("cornell-box", 8, 8, 4);
  return {{{"cornell box, sobol", cornell, ""},
          {"cornell box, independent", cornell, "--sampler independent"},
          {"cornell box, stratified", cornell, "--sampler stratified"},
          {"cornell box, halton", cornell, "--sampler halton"},
          // The light integrator's splat film: integer atomics from every work item into any pixel.
          {"cornell box, light tracing", cornell, "--integrator light"},
          {"every light type, light tracing, thin lens, gaussian filter", resized("materials", 16, 12, 2), "--integrator light"},
          // BDPT: light subpaths in a device buffer, connections, splats and the camera sums.
          {"cornell box, bdpt", cornell, "--integrator bdpt"},
          {"every material and light type, bdpt, thin lens, gaussian filter", resized("materials", 8, 6, 1), "--integrator bdpt --max-depth 4"},
          // Photon merging: light vertices at slots, the grid's integer counts, scan and scatter, each merge
          // in fixed point; sppm's visible points and next-event estimation.
          // (Small: Oclgrind interprets a merging camera path in about 0.2 s.)
          {"cornell box, vcm", resized("cornell-box", 6, 4, 2), "--integrator vcm"},
          {"every material and light type, sppm, thin lens, gaussian filter", resized("materials", 6, 4, 1), "--integrator sppm --max-depth 4"},
          // The gathering integrators: every pixel's connections to the iteration's virtual point lights
          // (clamped), and radiosity's per-primitive power sums in fixed point, shown by a final gather.
          {"cornell box, instant radiosity, clamped", with_integrator(resized("cornell-box", 6, 4, 2), "ir",
                                                                      R"({"type": "instant_radiosity", "light_paths": 4, "clamp": 1})"), ""},
          {"every material and light type, radiosity, thin lens, gaussian filter",
           with_integrator(resized("materials", 6, 4, 1), "radiosity", R"({"type": "radiosity", "light_paths": 16})"),
           "--max-depth 4"},
          // Metropolis: the bootstrap's float prefix sum, each chain's lazily mutated numbers carried in the film.
          {"every material and light type, mlt", with_integrator(resized("materials", 6, 4, 3), "mlt", R"({"type": "mlt", "bootstrap": 32})"),
           "--max-depth 4"},
          {"every material and light, thin lens, gaussian filter", resized("materials", 16, 12, 2), ""},
          // With every AOV (kernels/aov.cl): mirror and glass chains followed for albedo and normal.
          {"glass and metal, every AOV", resized("glass-metal", 16, 12, 2), "--aov " + kEveryAov},
          // 8 and 16 lanes on Oclgrind too (the other cases: PoCL at its default width, Oclgrind at one lane).
          {"every material and light, 8 lanes", resized("materials", 16, 12, 1), "--lanes 8"},
          {"cornell box, 16 lanes", cornell, "--lanes 16"},
          // Packets (the 16- and 8-wide layouts) on Oclgrind too: where PoCL's clang targets AVX-512,
          // packet_leaf looks vertex coordinates up with a permutation instruction, elsewhere it selects them
          // with masks.
          {"cornell box, 16 lanes, packets", cornell, "--lanes 16", 16},
          {"every material and light, 8 lanes, packets", resized("materials", 16, 12, 1), "--lanes 8", 8},
          // Single rays through the 8- and 16-wide layouts: where fma is an instruction (PoCL) the node test
          // takes the fused slab planes, elsewhere (Oclgrind) the unfused ones; they visit other nodes, never
          // other hits.
          {"cornell box, single rays, 8-wide layout", cornell, "--lanes 1", 8},
          {"cornell box, single rays, 16-wide layout", cornell, "--lanes 1", 16},
          {"textures, smooth normals, emitting sphere, environment map, every AOV", textured_scene(), "--aov " + kEveryAov},
          {"checkerboard, thin glass, metal mirror, rotated equal-area environment map", imported_features_scene(), ""},
          {"instances: moved, scaled, mirrored, smooth, cut-out",
           resized("instances", 12, 9, 2, std::string(PATHCL_TEST_SCENES) + "/instances.json"), ""}}};
}

// Written on first use, in the test process's temporary directory.
const std::array<Case, kCases>& cases() {
  static const std::array<Case, kCases> all = make_cases();
  return all;
}

struct Render {
  int status = -1;
  std::string err;
  Image image;
};

Render render_on(const std::string& device, const Case& c, const std::string& out) {
  Render r;
  r.status = run_pathcl("render " + c.scene + " " + c.options + " --device " + device + " --variance --quiet -o " + out,
                        &r.err);
  if (r.status == 0) r.image = read_exr(out);
  return r;
}

size_t identical_pixels(const Image& a, const Image& b) {
  size_t same = 0;
  for (size_t p = 0; p + 2 < a.rgb.size() && p + 2 < b.rgb.size(); p += 3)
    same += std::memcmp(&a.rgb[p], &b.rgb[p], 3 * sizeof(float)) == 0 &&
            std::memcmp(&a.variance[p], &b.variance[p], 3 * sizeof(float)) == 0;
  return same;
}

}  // namespace

class EveryFeature : public ::testing::TestWithParam<size_t> {};

TEST_P(EveryFeature, RendersTheSameBitsOnPoclAndOclgrind) {
  const Case& c = cases()[GetParam()];
  ASSERT_FALSE(c.scene.empty()) << "fewer cases than kCases";
  SCOPED_TRACE(c.name);
  // Oclgrind's checks of every memory access, and of data races between work items.
  setenv("OCLGRIND_DATA_RACES", "1", 1);
  std::string tag = temp_dir() + "/cross/" + std::to_string(GetParam());
  fs::create_directories(temp_dir() + "/cross");
  std::optional<BvhWidthScope> width;
  if (c.bvh_width != 0) width.emplace(c.bvh_width);
  Render pocl = render_on("pthread", c, tag + "-pocl.exr");
  Render grind = render_on("oclgrind", c, tag + "-oclgrind.exr");
  unsetenv("OCLGRIND_DATA_RACES");
  ASSERT_EQ(pocl.status, 0) << pocl.err;
  ASSERT_EQ(grind.status, 0) << grind.err;
  // Oclgrind reports what it finds on stderr; pathcl itself says only its warnings with --quiet, the same on
  // both.
  EXPECT_EQ(grind.err, pocl.err) << "Oclgrind's diagnostics";
  size_t pixels = pocl.image.rgb.size() / 3, same = identical_pixels(pocl.image, grind.image);
  std::printf("%s: %zu of %zu pixels identical\n", c.name.c_str(), same, pixels);
  EXPECT_EQ(same, pixels);
  ASSERT_EQ(pocl.image.layers.size(), grind.image.layers.size());
  for (size_t i = 0; i < pocl.image.layers.size(); ++i) {
    const ImageLayer &a = pocl.image.layers[i], &b = grind.image.layers[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_TRUE(a.values.size() == b.values.size() &&
                std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(float)) == 0)
        << "AOV layer " << a.name << " differs";
  }
  if (c.options.find("--aov") != std::string::npos) { EXPECT_FALSE(pocl.image.layers.empty()); }
  double sum = 0;
  for (float v : pocl.image.rgb) sum += v;
  EXPECT_GT(sum / pocl.image.rgb.size(), 1e-3) << "a black image proves little";
}

INSTANTIATE_TEST_SUITE_P(CrossImplementation, EveryFeature, ::testing::Range<size_t>(0, kCases));

TEST(CrossImplementation, PoclAndOclgrindRenderOneImageTogether) {
  std::string dir = temp_dir() + "/together", err;
  fs::create_directories(dir);
  std::string scene = resized("cornell-box", 16, 8, 4);
  ASSERT_EQ(run_pathcl("render " + scene + " --device pthread --quiet -o " + dir + "/one.exr", &err), 0) << err;
  ASSERT_EQ(run_pathcl("render " + scene + " --device pthread,oclgrind --quiet -o " + dir + "/two.exr --stats " + dir +
                           "/two.json",
                       &err),
            0)
      << err;
  EXPECT_EQ(read_exr(dir + "/one.exr").rgb, read_exr(dir + "/two.exr").rgb);
  std::string stats = read_text_file(dir + "/two.json");
  // Both in arithmetic class 0: the probe found the same bits.
  size_t first = stats.find("\"class\": 0"), second = stats.find("\"class\": 0", first + 1);
  EXPECT_NE(second, std::string::npos) << stats;
  EXPECT_EQ(read_exr(dir + "/two.exr").attributes["determinism"], "bitwise");
  // Oclgrind calls itself a GPU: with a GPU in the set, the CPU device leaves a core to the host.
  EXPECT_NE(stats.find("\"sub_device\": true"), std::string::npos) << stats;
}
