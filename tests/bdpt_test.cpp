// Bidirectional path tracing (`bdpt`, kernels/bdpt.cl): exact values on analytic scenes, each of its
// strategies alone an unbiased estimator of the paths it makes, agreement with the path integrator per
// pixel, a point light inside glass that path tracing cannot see at all, and the splat film's
// determinism. Tolerances are in standard errors, from independent seeds or the films' variances.
#include <cmath>

#include <gtest/gtest.h>

#include "light_transport_support.h"

using namespace light_transport_test;

namespace {

// A checker-textured floor and back wall, a textured plastic ball and a small emitting sphere above.
std::string textured_scene() {
  std::vector<unsigned char> checker(8 * 8 * 3);
  for (int i = 0; i < 64; ++i)
    for (int c = 0; c < 3; ++c) checker[3 * i + c] = ((i % 8 + i / 8) % 2) ? 220 : uint8_t(30 + 70 * c);
  write_temp_png("bdpt-checker.png", 8, 8, checker);
  return write_temp_file("bdpt-textured.json", R"({
    "camera": {"position": [0, 1, 3.5], "look_at": [0, 0.7, 0], "width": 24, "height": 24},
    "materials": {
      "checker": {"type": "diffuse", "reflectance": {"texture": "bdpt-checker.png"}},
      "ball": {"type": "plastic", "diffuse": {"texture": "bdpt-checker.png"}, "roughness": 0.3},
      "lamp": {"type": "diffuse", "reflectance": [0, 0, 0]}},
    "shapes": [
      {"type": "triangles", "positions": [[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]],
       "uvs": [[0, 0], [3, 0], [3, 3], [0, 3]], "indices": [[0, 2, 1], [0, 3, 2]], "material": "checker"},
      {"type": "triangles", "positions": [[-2, 0, -2], [2, 0, -2], [2, 3, -2], [-2, 3, -2]],
       "uvs": [[0, 0], [2, 0], [2, 2], [0, 2]], "indices": [[0, 1, 2], [0, 2, 3]], "material": "checker"},
      {"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "material": "ball"},
      {"type": "sphere", "center": [0.6, 1.9, 0.6], "radius": 0.15, "material": "lamp", "emission": [30, 27, 22]}]})");
}

Options bdpt(uint32_t spp, uint32_t max_depth) {
  Options o;
  o.integrator = "bdpt";
  o.spp = spp;
  o.max_depth = max_depth;
  return o;
}

}  // namespace

// Every wall pixel of the cap sphere is f Le rho (1 - rho^n) / (1 - rho) after n reflections.
TEST(Bdpt, CapSphereWithinFourStandardErrors) {
  std::vector<double> exact;
  DeviceScene scene = cap_sphere(&exact);
  for (uint32_t depth : {1u, 4u}) {
    MeanStd m = seeded_mean(scene, bdpt(32, depth), 6);
    // The icosphere's tessellation bias is about 0.1 % (docs/accuracy.md): added to the tolerance.
    EXPECT_NEAR(m.mean, exact[depth], 4 * m.std_error + 2e-3 * exact[depth]) << "max_depth " << depth << ", error " << m.std_error;
    EXPECT_LT(m.std_error, 0.02 * exact[depth]) << "too noisy for the test to mean anything";
  }
}

// Each strategy (s light vertices, t camera vertices) alone and unweighted estimates the paths of
// k = s + t - 2 scattering events, which on the cap sphere add exact[k] - exact[k - 1]: all k + 2
// strategies of k = 1, 2, 3 (t = 0 is not taken; the camera sees no emitter, so k = 0 is black).
TEST(Bdpt, EachStrategyAloneIsUnbiasedOnTheCapSphere) {
  std::vector<double> exact;
  DeviceScene scene = cap_sphere(&exact);
  const uint32_t max_depth = 3;
  for (uint32_t k = 1; k <= max_depth; ++k)
    for (uint32_t s = 0; s <= k + 1; ++s) {
      uint32_t t = k + 2 - s;
      Options o = bdpt(32, max_depth);
      o.strategy_s = int(s);
      o.strategy_t = int(t);
      MeanStd m = seeded_mean(scene, o, 4);
      double expected = exact[k] - exact[k - 1];
      EXPECT_NEAR(m.mean, expected, 4 * m.std_error + 2e-3 * exact[k])
          << "strategy s " << s << ", t " << t << ": error " << m.std_error;
      EXPECT_LT(m.std_error, 0.05 * expected) << "strategy s " << s << ", t " << t << " too noisy to mean anything";
    }
}

// The closed furnace (tests/furnace_test.cpp): a sphere whose wall emits Le and reflects rho gives
// Le (1 - rho^(D+1)) / (1 - rho) everywhere, here with Russian roulette and every strategy at once. Light
// subpaths live in device memory (max_depth slots per path of a unit): at max_depth 100 too.
TEST(Bdpt, FurnaceMeanWithinFourStandardErrors) {
  DeviceScene scene = furnace_scene();
  for (uint32_t depth : {6u, 100u}) {
    MeanStd m = seeded_mean(scene, bdpt(16, depth), 4);
    double exact = 0.5 * (1 - std::pow(0.5, depth + 1)) / 0.5;
    EXPECT_NEAR(m.mean, exact, 4 * m.std_error) << "max_depth " << depth << ": error " << m.std_error;
    EXPECT_LT(m.std_error, 0.01 * exact);
  }
}

// A point light inside a glass ball inside a diffuse sphere (tests/light_integrator_test.cpp derives
// L = rho I / (R^2 pi (1 - rho))): BDPT gets it from its light subpaths; path tracing gets exactly 0.
TEST(Bdpt, PointLightInGlassBallLightsTheEnclosureExactly) {
  const double rho = 0.5, intensity = 10, radius = 5;
  DeviceScene scene = scene_from("bdpt-glass-ball.json", R"({"camera": {"position": [0, 0, 2], "look_at": [0, 0, 5], "fov_y_degrees": 30, "width": 16, "height": 16},
    "materials": {"wall": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}, "glass": {"type": "dielectric", "ior": 1.5}},
    "shapes": [{"type": "sphere", "radius": 5, "flip_normals": true, "material": "wall"},
               {"type": "sphere", "radius": 0.5, "material": "glass"}],
    "lights": [{"type": "point", "position": [0, 0, 0], "intensity": [10, 10, 10]}]})");
  const double exact = rho * intensity / (radius * radius) / (M_PI * (1 - rho));
  MeanStd m = seeded_mean(scene, bdpt(96, 20), 6);  // beyond 20 events: below rho^18 = 4e-6 of it
  EXPECT_NEAR(m.mean, exact, 4 * m.std_error) << "error " << m.std_error;
  EXPECT_LT(m.std_error, 0.02 * exact);
}

// BDPT and path tracing estimate the same pixels, those that see the lamp or glass included: the
// Cornell box, glass-metal (glass, metals, a mirror) and a textured scene (image textures, a textured
// plastic, an emitting sphere, an environment map, a tent filter), per channel |z| <= 4.
TEST(Bdpt, AgreesWithPathTracingPerPixel) {
  struct Case {
    const char* name;
    std::string file;
    uint32_t size, path_spp, bdpt_spp;
  };
  const std::string scenes = std::string(PATHCL_SOURCE_DIR) + "/scenes/";
  for (const Case& c : {Case{"cornell-box", scenes + "cornell-box.json", 24, 256, 128},
                        Case{"glass-metal", scenes + "glass-metal.json", 24, 256, 128},
                        Case{"textured", textured_scene(), 24, 256, 128}}) {
    SCOPED_TRACE(c.name);
    DeviceScene scene = load_device_scene(c.file);
    scene.header.width = c.size;
    scene.header.height = c.size;
    Options o = bdpt(c.bdpt_spp, 5);
    Film b = render_with(scene, o).film;
    o.integrator = "path";
    o.spp = c.path_spp;
    Film p = render_with(scene, o).film;
    expect_same_pixels(p, b);
  }
}

// The image is a pure function of scene, settings and seed: the same bits for any work-group size, any
// split into units, a resumed render, and with 32-bit word pairs instead of 64-bit atomics.
TEST(Bdpt, SplatFilmIsBitwiseDeterministic) {
  DeviceScene scene = load_device_scene(std::string(PATHCL_SOURCE_DIR) + "/scenes/cornell-box.json");
  scene.header.width = 24;
  scene.header.height = 20;
  Options o = bdpt(8, 5);
  expect_bitwise_deterministic(scene, o);
}

// bdpt takes any max_depth the path integrator takes (FurnaceMeanWithinFourStandardErrors renders 100):
// beyond path's bound both refuse alike.
// A work item renders 8 or 16 BDPT samples at once, a lane each (kernels/bdpt.cl): every width gives the
// one-lane film bit for bit (light_transport_support.h).
TEST(Bdpt, EveryLaneWidthGivesTheOneLaneFilm) { expect_one_lane_bits_at_every_width("bdpt"); }

TEST(Bdpt, RefusesMaxDepthBeyondPathsBound) {
  DeviceScene scene = furnace_scene();
  RenderOptions opt;
  opt.spp = 1;
  opt.max_depth = technique_named("path", "test").max_depth_limit + 1;
  for (const char* integrator : {"path", "bdpt"}) {
    opt.integrator = integrator;
    EXPECT_THROW(render(test_device(), scene, opt), UsageError) << integrator;
  }
}
