// Closed furnaces with known answers. Inside a closed enclosure whose walls all emit Le and reflect
// diffusely with albedo rho, the radiance after at most D scattering events is exactly
// Le (1 - rho^(D+1)) / (1 - rho), whatever the shape. Inside a sphere even each sample is exact while
// Russian roulette is off (D <= 3): next-event and BSDF sampling have equal densities, so MIS weights
// are 1/2 and every estimate is constant.
#include <cmath>
#include <sstream>

#include <gtest/gtest.h>

#include "test_support.h"

namespace {

constexpr double kLe = 0.5, kRho = 0.5;

double furnace_value(uint32_t max_depth) { return kLe * (1 - std::pow(kRho, max_depth + 1)) / (1 - kRho); }

std::string furnace_scene(const std::string& shape_json, int size) {
  std::ostringstream s;
  s << R"({"camera": {"position": [0.1, -0.2, 0.3], "look_at": [0.5, 0.4, -1], "fov_y_degrees": 100, "width": )" << size
    << R"(, "height": )" << size << R"(},
  "materials": {"grey": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}},
  "shapes": [)" << shape_json << R"(, "material": "grey", "emission": [0.5, 0.5, 0.5]}]})";
  return s.str();
}

const std::string kSphere = R"({"type": "sphere", "center": [0, 0, 0], "radius": 2, "flip_normals": true)";

// lanes: paths per work item (kernels/lanes.cl); 0 the device's own (16 or 8 on PoCL).
RenderResult render_scene(const DeviceScene& scene, uint32_t spp, uint32_t max_depth, uint32_t seed = 1,
                          uint32_t lanes = 0) {
  RenderOptions opt;
  opt.spp = spp;
  opt.max_depth = max_depth;
  opt.seed = seed;
  opt.lanes = lanes;
  return render(test_device(), scene, opt);
}

void expect_clean(const RenderResult& r) {
  EXPECT_EQ(r.nan_samples, 0u);
  EXPECT_EQ(r.inf_samples, 0u);
  EXPECT_EQ(r.negative_samples, 0u);
}

}  // namespace

TEST(Furnace, AnalyticSphereIsExactPerPixelWithoutRussianRoulette) {
  DeviceScene scene = load_device_scene(write_temp_file("furnace-sphere.json", furnace_scene(kSphere, 24)));
  for (uint32_t depth : {0u, 1u, 2u, 3u}) {
    RenderResult r = render_scene(scene, 4, depth);
    expect_clean(r);
    double expected = furnace_value(depth);
    double worst = 0;
    for (float v : r.film.mean) worst = std::max(worst, std::abs(v - expected) / expected);
    EXPECT_LT(worst, 2e-5) << "max_depth " << depth << ": expected " << expected;
  }
}

// At every lane width: one path per work item (the GPUs' kernel) and 8 or 16 over SIMD lanes.
TEST(Furnace, AnalyticSphereMeanWithRussianRouletteWithinFourStandardErrors) {
  DeviceScene scene = load_device_scene(write_temp_file("furnace-sphere-rr.json", furnace_scene(kSphere, 32)));
  for (uint32_t lanes : {1u, 8u, 16u}) {
    for (uint32_t depth : {6u, 12u}) {
      SCOPED_TRACE(std::to_string(lanes) + " lanes");
      RenderResult r = render_scene(scene, 16, depth, 11, lanes);
      expect_clean(r);
      std::vector<double> pixels;
      for (size_t i = 0; i < r.film.mean.size(); i += 3) pixels.push_back(r.film.mean[i]);
      MeanStd m = mean_and_error(pixels);
      double expected = furnace_value(depth);
      EXPECT_GT(m.std_error, 0);  // Russian roulette adds noise; zero would mean it never ran
      EXPECT_NEAR(m.mean, expected, 4 * m.std_error) << "max_depth " << depth;
      EXPECT_LT(m.std_error, 0.01 * expected);
    }
  }
}

TEST(Furnace, ClosedTriangleMeshNoPixelLeaksAndMeanIsExact) {
  std::string scene_json = furnace_scene(icosphere_json(2, 3, /*inward=*/true), 96);
  DeviceScene scene = load_device_scene(write_temp_file("furnace-mesh.json", scene_json));
  ASSERT_EQ(scene.triangle_count, 1280u);
  // Depth 0: every camera ray must hit the closed mesh and see exactly Le; a ray slipping through a
  // shared edge would leave a black pixel.
  RenderResult direct = render_scene(scene, 4, 0);
  expect_clean(direct);
  size_t wrong = 0;
  for (float v : direct.film.mean) wrong += std::abs(v - kLe) > 1e-6;
  EXPECT_EQ(wrong, 0u);

  for (uint32_t depth : {1u, 3u}) {
    RenderResult r = render_scene(scene, 8, depth, 5);
    expect_clean(r);
    std::vector<double> pixels;
    for (size_t i = 0; i < r.film.mean.size(); i += 3) pixels.push_back(r.film.mean[i]);
    MeanStd m = mean_and_error(pixels);
    EXPECT_NEAR(m.mean, furnace_value(depth), 4 * m.std_error + 1e-6) << "max_depth " << depth;
    for (double p : pixels) ASSERT_GE(p, kLe * 0.999);  // emission is always seen: no leak, no black pixel
  }
}

TEST(Furnace, CornellBoxHasNoInvalidSamples) {
  DeviceScene scene = load_device_scene(std::string(PATHCL_TEST_SCENES) + "/../../scenes/cornell-box.json");
  scene.header.width = 64;  // a small film of the same view
  scene.header.height = 64;
  RenderResult r = render_scene(scene, 8, 8);
  expect_clean(r);
  double sum = 0;
  for (float v : r.film.mean) sum += v;
  EXPECT_GT(sum / r.film.mean.size(), 0.05);  // lit, not black
  EXPECT_GT(r.rays, uint64_t(64 * 64 * 8 * 2));
}

TEST(Furnace, HazardCountersCountForcedHazardsAndKeepThemOffTheFilm) {
  DeviceScene scene = load_device_scene(write_temp_file("furnace-hazard.json", furnace_scene(kSphere, 8)));
  RenderOptions opt;
  opt.spp = 30;
  opt.max_depth = 2;
  opt.debug_inject_hazards = true;
  RenderResult r = render(test_device(), scene, opt);
  // The kernel's classification, replayed: NaN first, then infinity, then negative.
  uint64_t nan = 0, inf = 0, negative = 0;
  for (uint32_t s = 0; s < opt.spp; ++s) {
    if (s % 7 == 3) ++nan;
    else if (s % 11 == 5) ++inf;
    else if (s % 13 == 6) ++negative;
  }
  uint64_t pixels = 8 * 8;
  EXPECT_EQ(r.nan_samples, nan * pixels);
  EXPECT_EQ(r.inf_samples, inf * pixels);
  EXPECT_EQ(r.negative_samples, negative * pixels);
  for (float v : r.film.mean) ASSERT_TRUE(std::isfinite(v) && v >= 0);
  // Dropped samples count as zero: the mean is the exact value scaled by the kept fraction.
  double kept = double(opt.spp - nan - inf - negative) / opt.spp;
  EXPECT_NEAR(r.film.mean[0], furnace_value(2) * kept, 1e-4);
}

TEST(Furnace, ClosedObjWithEmissionPerFaceFromMtl) {
  // An octahedron whose faces alternate between two MTL materials, both Kd = rho and Ke = Le, facing
  // inwards: the faces become lights one by one (there is no shape emission) and the furnace holds.
  write_temp_file("furnace-mtl/walls.mtl", "newmtl a\nKd 0.5\nKe 0.5 0.5 0.5\nnewmtl b\nKd 0.5 0.5 0.5\nKe 0.5\n");
  write_temp_file("furnace-mtl/octahedron.obj",
                  "mtllib walls.mtl\nv 2 0 0\nv -2 0 0\nv 0 2 0\nv 0 -2 0\nv 0 0 2\nv 0 0 -2\n"
                  "usemtl a\nf 5 3 1\nusemtl b\nf 5 2 3\nusemtl a\nf 5 4 2\nusemtl b\nf 5 1 4\n"
                  "usemtl a\nf 6 1 3\nusemtl b\nf 6 3 2\nusemtl a\nf 6 2 4\nusemtl b\nf 6 4 1\n");
  std::string scene_json = R"({"camera": {"position": [0.1, -0.2, 0.3], "look_at": [0.5, 0.4, -1], "fov_y_degrees": 100,
    "width": 32, "height": 32}, "materials": {},
    "shapes": [{"type": "mesh", "file": "furnace-mtl/octahedron.obj", "material": "from_mtl"}]})";
  DeviceScene scene = load_device_scene(write_temp_file("furnace-mtl.json", scene_json));
  ASSERT_EQ(scene.lights.size(), 8u);
  ASSERT_EQ(scene.materials.size(), 2u);
  RenderResult direct = render_scene(scene, 4, 0);
  expect_clean(direct);
  for (float v : direct.film.mean) ASSERT_NEAR(v, kLe, 1e-6);  // every face emits towards the camera
  RenderResult r = render_scene(scene, 16, 2, 9);
  expect_clean(r);
  std::vector<double> pixels;
  for (size_t i = 0; i < r.film.mean.size(); i += 3) pixels.push_back(r.film.mean[i]);
  MeanStd m = mean_and_error(pixels);
  EXPECT_NEAR(m.mean, furnace_value(2), 4 * m.std_error + 1e-6);
}
