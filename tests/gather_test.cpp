// The gathering integrators (`instant_radiosity`, `radiosity`; kernels/gather.cl): exact on the cap sphere
// (uniform irradiance: instant radiosity is unbiased without a clamp, and a per-triangle radiosity is exact
// on any tessellation of it), instant radiosity's clamp loses energy as it tightens, radiosity's error on the
// Cornell box per wall (and its fall when the walls are finer), and bitwise determinism over every split.
// Tolerances are in standard errors.
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <map>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "light_transport_support.h"

using namespace light_transport_test;

namespace {

Options gathering(const char* integrator, uint32_t spp, uint32_t max_depth) {
  Options o;
  o.integrator = integrator;
  o.spp = spp;
  o.max_depth = max_depth;
  return o;
}

const std::string kScenes = std::string(PATHCL_SOURCE_DIR) + "/scenes/";

DeviceScene small_cornell(uint32_t width, uint32_t height) {
  DeviceScene scene = load_device_scene(kScenes + "cornell-box.json");
  scene.header.width = width;
  scene.header.height = height;
  return scene;
}

// Per shape (the shape-id AOV of film `ids`): the sums of each film's pixel means (R + G + B) over the
// pixels that see the shape.
std::map<uint32_t, std::pair<double, double>> per_shape_sums(const Film& ids, const Film& a, const Film& b) {
  std::map<uint32_t, std::pair<double, double>> sums;
  const std::vector<float>& id = ids.aovs.at(0).values;
  for (size_t p = 0; p < id.size(); ++p) {
    auto& s = sums[uint32_t(id[p])];
    for (int c = 0; c < 3; ++c) {
      s.first += a.mean[3 * p + c];
      s.second += b.mean[3 * p + c];
    }
  }
  return sums;
}

}  // namespace

// The Szirmay-Kalos cap sphere (scripts/make-cap-sphere): every wall pixel is f Le rho (1 - rho^n) / (1 - rho)
// after n reflections. Instant radiosity without a clamp is unbiased anywhere; radiosity's per-triangle
// irradiance is exact wherever the irradiance is uniform, with and without final gather.
TEST(Gather, CapSphereExact) {
  std::vector<double> exact;
  DeviceScene scene = cap_sphere(&exact);
  struct Case {
    const char* integrator;
    bool final_gather;
    uint32_t light_paths;
  };
  for (Case c : {Case{"instant_radiosity", true, 0}, Case{"radiosity", true, 4096}, Case{"radiosity", false, 4096}})
    for (uint32_t depth : {1u, 4u}) {
      Options o = gathering(c.integrator, 32, depth);
      o.final_gather = c.final_gather;
      o.light_paths = c.light_paths;
      MeanStd m = seeded_mean(scene, o, 4);
      // The icosphere's tessellation bias is about 0.1 % (docs/accuracy.md): added to the tolerance.
      EXPECT_NEAR(m.mean, exact[depth], 4 * m.std_error + 2e-3 * exact[depth])
          << c.integrator << (c.final_gather ? "" : " without final gather") << ", max_depth " << depth << ": error "
          << m.std_error;
      EXPECT_LT(m.std_error, 0.02 * exact[depth]) << c.integrator << " too noisy for the test to mean anything";
    }
}

// Instant radiosity without a clamp agrees with path tracing on the Cornell box (image means, 4 standard
// errors of both); a clamp of the geometry term only removes light, more the tighter it is (the corners' and
// edges' short connections).
TEST(Gather, InstantRadiosityClampLosesEnergyAsItTightens) {
  DeviceScene scene = small_cornell(32, 24);
  const MeanStd path = seeded_mean(scene, gathering("path", 64, 8), 4);
  Options o = gathering("instant_radiosity", 16, 8);
  const MeanStd unclamped = seeded_mean(scene, o, 4);
  EXPECT_NEAR(unclamped.mean, path.mean, 4 * std::hypot(unclamped.std_error, path.std_error));
  double previous = unclamped.mean;
  for (double clamp : {4.0, 1.0, 0.25}) {
    o.clamp = clamp;
    const MeanStd clamped = seeded_mean(scene, o, 4);
    const double bias = clamped.mean / path.mean - 1;
    std::printf("instant radiosity, clamp %g: image mean %.5f (path %.5f), bias %+.2f %%\n", clamp, clamped.mean,
                path.mean, 100 * bias);
    EXPECT_LT(clamped.mean, previous) << "clamp " << clamp;
    previous = clamped.mean;
  }
  EXPECT_LT(previous, path.mean - 4 * path.std_error) << "the tightest clamp loses light beyond the noise";
}

// Radiosity on the Cornell box against path tracing, per shape (wall): the shown radiosity is constant over
// each triangle, so its error is the mesh's (36 triangles; printed per wall). Subdividing every shape into 4 x 4
// parts per triangle ("subdivide": 4, the same surfaces) must at least halve the walls' RMS error, with final
// gather and without.
TEST(Gather, RadiosityErrorPerWallFallsWithSubdivision) {
  nlohmann::json cornell = nlohmann::json::parse(std::ifstream(kScenes + "cornell-box.json"));
  cornell["camera"]["width"] = 32;
  cornell["camera"]["height"] = 32;
  for (auto& shape : cornell["shapes"]) shape["file"] = kScenes + shape["file"].get<std::string>();
  DeviceScene coarse = scene_from("gather-cornell.json", cornell.dump());
  for (auto& shape : cornell["shapes"]) shape["subdivide"] = 4;
  DeviceScene fine = scene_from("gather-cornell-subdivided.json", cornell.dump());
  ASSERT_EQ(fine.triangle_count, 16 * coarse.triangle_count);
  Film path = render_with(coarse, gathering("path", 512, 8)).film;
  RenderOptions ids_options;
  ids_options.spp = 1;
  ids_options.aovs = 1u << PC_AOV_SHAPE_ID;
  Film ids = render(test_device(), coarse, ids_options).film;
  for (bool final_gather : {true, false}) {
    double rms[2] = {0, 0};
    for (int subdivided = 0; subdivided < 2; ++subdivided) {
      Options o = gathering("radiosity", 256, 8);
      o.final_gather = final_gather;
      Film rad = render_with(subdivided ? fine : coarse, o).film;
      size_t walls = 0;
      for (const auto& [shape, sums] : per_shape_sums(ids, path, rad)) {
        if (shape == 0 || sums.first <= 0) continue;
        const double error = sums.second / sums.first - 1;
        std::printf("radiosity%s, %s, shape %u: %+.2f %% against path\n", final_gather ? "" : " without final gather",
                    subdivided ? "subdivided 4 x 4" : "as it is", shape - 1, 100 * error);
        rms[subdivided] += error * error;
        ++walls;
      }
      ASSERT_EQ(walls, 6u);
      rms[subdivided] = std::sqrt(rms[subdivided] / walls);
    }
    EXPECT_LT(rms[1], rms[0] / 2) << (final_gather ? "final gather" : "without final gather") << ": RMS error per wall "
                                  << rms[0] << " as it is, " << rms[1] << " subdivided";
  }
}

// The image is a pure function of scene, settings and seed for both (work groups, units of any size, word
// pairs for radiosity's sums, resumed, stopped by a rule).
TEST(Gather, BitwiseDeterministic) {
  DeviceScene scene = small_cornell(12, 10);
  for (const char* integrator : {"instant_radiosity", "radiosity"}) {
    SCOPED_TRACE(integrator);
    Options o = gathering(integrator, 8, 6);
    o.light_paths = 16;
    expect_bitwise_deterministic(scene, o);
  }
}
