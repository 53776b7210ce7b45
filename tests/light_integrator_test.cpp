// The light-tracing integrator (`light`, kernels/light_integrator.cl): exact values where it can see
// them, agreement with the path integrator on the pixels it reaches, darkness where it cannot see, a
// caustic that path tracing misses entirely, and the splat film's determinism (work-group size, unit
// split, resume, 64-bit atomics against 32-bit word pairs, lane width). Tolerances are in standard errors, from
// independent seeds.
#include <cmath>

#include <gtest/gtest.h>

#include "light_transport_support.h"

using namespace light_transport_test;

// The Szirmay-Kalos sphere (scripts/make-cap-sphere): every wall pixel is f Le rho (1 - rho^n) / (1 - rho)
// after n reflections. Light tracing sees it all (the camera sees only the wall).
TEST(LightIntegrator, CapSphereWithinFourStandardErrors) {
  std::vector<double> exact;
  DeviceScene scene = cap_sphere(&exact);
  for (uint32_t depth : {1u, 4u}) {
    Options o;
    o.spp = 64;
    o.max_depth = depth;
    MeanStd m = seeded_mean(scene, o, 6);
    // The icosphere's tessellation bias is about 0.1 % (docs/accuracy.md): added to the tolerance.
    EXPECT_NEAR(m.mean, exact[depth], 4 * m.std_error + 2e-3 * exact[depth]) << "max_depth " << depth << ", error " << m.std_error;
    EXPECT_LT(m.std_error, 0.02 * exact[depth]) << "too noisy for the test to mean anything";
  }
}

// The closed furnace (tests/furnace_test.cpp): a sphere whose wall emits Le and reflects rho. Light
// tracing sees all but the emission seen directly: Le rho (1 - rho^D) / (1 - rho) after D events.
TEST(LightIntegrator, FurnaceMeanWithinFourStandardErrors) {
  DeviceScene scene = furnace_scene();
  const uint32_t depth = 6;
  Options o;
  o.spp = 32;
  o.max_depth = depth;
  MeanStd m = seeded_mean(scene, o, 4);
  double exact = 0.5 * 0.5 * (1 - std::pow(0.5, depth)) / 0.5;
  EXPECT_NEAR(m.mean, exact, 4 * m.std_error) << "error " << m.std_error;
  EXPECT_LT(m.std_error, 0.01 * exact);
}

// A diffuse sphere of radius R = 5 and reflectance rho lit by a point light of intensity I at its centre,
// enclosed in a glass ball of radius 0.5: every ray leaves the ball radially (normal incidence; reflected
// rays cross the centre and leave on the other side) and no flux is absorbed but by the wall, so by
// symmetry the wall has uniform direct irradiance E0 = I / R^2 and all the light the wall reflects comes
// back to the wall: radiance L = rho E0 / (pi (1 - rho)) (up to the depth limit, which at rho = 0.5 and
// 20 events is far below the noise). Path tracing sees nothing: the glass blocks every shadow ray.
TEST(LightIntegrator, PointLightInGlassBallLightsTheEnclosureExactly) {
  const double rho = 0.5, intensity = 10, radius = 5;
  std::string json = R"({"camera": {"position": [0, 0, 2], "look_at": [0, 0, 5], "fov_y_degrees": 30, "width": 16, "height": 16},
    "materials": {"wall": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}, "glass": {"type": "dielectric", "ior": 1.5}},
    "shapes": [{"type": "sphere", "radius": 5, "flip_normals": true, "material": "wall"},
               {"type": "sphere", "radius": 0.5, "material": "glass"}],
    "lights": [{"type": "point", "position": [0, 0, 0], "intensity": [10, 10, 10]}]})";
  DeviceScene scene = scene_from("glass-ball.json", json);
  const double exact = rho * intensity / (radius * radius) / (M_PI * (1 - rho));
  Options o;
  o.spp = 96;
  o.max_depth = 20;  // the light beyond 20 events is below rho^18 = 4e-6 of it
  MeanStd m = seeded_mean(scene, o, 6);
  EXPECT_NEAR(m.mean, exact, 4 * m.std_error) << "error " << m.std_error;
  EXPECT_LT(m.std_error, 0.02 * exact);
  o.integrator = "path";
  o.spp = 4;
  Film path = render_with(scene, o).film;
  for (float v : path.mean) ASSERT_EQ(v, 0.0f) << "path tracing cannot reach a point light through glass";
}

// What light tracing cannot see: an emitter seen directly, and anything seen through a mirror. A camera
// looking only at a lamp (black, emitting) gets black, and so does one looking at a mirror that shows a
// lit diffuse wall, while the path integrator sees both.
TEST(LightIntegrator, DirectlySeenLightsAndMirrorImagesAreOutOfReach) {
  std::string lamp = R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y_degrees": 10, "width": 8, "height": 8},
    "materials": {"black": {"type": "diffuse", "reflectance": [0, 0, 0]}, "white": {"type": "diffuse", "reflectance": [0.8, 0.8, 0.8]}},
    "shapes": [{"type": "sphere", "radius": 1, "material": "black", "emission": [1, 1, 1]},
               {"type": "sphere", "radius": 10, "flip_normals": true, "material": "white"}]})";
  std::string mirror = R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov_y_degrees": 10, "width": 8, "height": 8},
    "materials": {"m": {"type": "mirror", "reflectance": [1, 1, 1]}, "white": {"type": "diffuse", "reflectance": [0.8, 0.8, 0.8]}},
    "shapes": [{"type": "sphere", "radius": 1, "material": "m"},
               {"type": "sphere", "radius": 10, "flip_normals": true, "material": "white"}],
    "lights": [{"type": "point", "position": [0, 5, 0], "intensity": [50, 50, 50]}]})";
  for (const auto& [name, json] : {std::pair<const char*, std::string>{"lamp.json", lamp}, {"mirror.json", mirror}}) {
    DeviceScene scene = scene_from(name, json);
    Options o;
    o.spp = 8;
    Film light = render_with(scene, o).film;
    for (float v : light.mean) ASSERT_EQ(v, 0.0f) << name;
    o.integrator = "path";
    EXPECT_GT(image_mean(render_with(scene, o).film), 0.01) << name;
  }
}

// The Cornell box at 32 x 32: light tracing and path tracing estimate the same pixels, except where the
// lamp is seen directly (path tracing at max_depth 0 shows those; they are left out).
TEST(LightIntegrator, AgreesWithPathTracingPerPixelOnTheCornellBox) {
  DeviceScene scene = load_device_scene(std::string(PATHCL_SOURCE_DIR) + "/scenes/cornell-box.json");
  scene.header.width = 32;
  scene.header.height = 32;
  Options o;
  o.max_depth = 3;
  o.integrator = "path";
  o.spp = 64;  // enough to find the pixels the lamp covers only in part
  o.max_depth = 0;
  Film direct = render_with(scene, o).film;
  o.max_depth = 3;
  o.spp = 256;
  Film path = render_with(scene, o).film;
  o.integrator = "light";
  o.spp = 256;
  Film light = render_with(scene, o).film;
  PixelComparison c = expect_same_pixels(path, light, [&](size_t p) {
    return direct.mean[3 * p] > 0 || direct.mean[3 * p + 1] > 0 || direct.mean[3 * p + 2] > 0;
  });
  EXPECT_GT(c.compared, path.mean.size() * 8 / 10);
}

// The image is a pure function of scene, settings and seed: the same bits for any work-group size, any
// split into units, a resumed render, and with 32-bit word pairs instead of 64-bit atomics.
TEST(LightIntegrator, SplatFilmIsBitwiseDeterministic) {
  DeviceScene scene = load_device_scene(std::string(PATHCL_SOURCE_DIR) + "/scenes/cornell-box.json");
  scene.header.width = 24;
  scene.header.height = 20;
  Options o;
  o.spp = 8;
  o.max_depth = 4;
  expect_bitwise_deterministic(scene, o);
}

// A work item traces 8 or 16 light paths at once, a lane each (kernels/light_path.cl): every width gives the
// one-lane splats bit for bit (light_transport_support.h).
TEST(LightIntegrator, EveryLaneWidthGivesTheOneLaneSplats) { expect_one_lane_bits_at_every_width("light"); }
