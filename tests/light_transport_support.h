// What the tests of the light-transport integrators (`light`, `bdpt`, `vcm`, `bpm`, `sppm`, the gathering
// `instant_radiosity` and `radiosity`, and `mlt`) share: a render with the options they
// vary, image means over independent seeds, the cap sphere and the furnace, and the per-pixel z-test of two films.
#pragma once
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_support.h"

namespace light_transport_test {

struct Options {
  uint32_t spp = 16, max_depth = 8, seed = 1, pass_spp = 0, tile_pixels = 0;
  // light, bdpt, vcm, bpm, sppm: paths or samples per work item. 1 (0: the device's width): every width gives the one-lane
  // film bit for bit (expect_one_lane_bits_at_every_width), so the estimates are checked on the one-lane
  // programs, which build faster and are GPUs' too.
  uint32_t lanes = 1;
  std::string integrator = "light";
  size_t work_group = 0;
  bool pairs = false;
  int strategy_s = -1, strategy_t = -1;  // bdpt: this strategy alone
  bool merge = true;                      // vcm: merging (false: bdpt's estimator)
  double radius = 0;                      // vcm, bpm, sppm: the first iteration's radius (0: the default)
  double merge_mis = 0;                   // vcm: merging's factor in the MIS weights (0: the default)
  uint32_t light_paths = 0;               // instant_radiosity, radiosity: light paths per iteration (0: the default)
  double clamp = 0;                       // instant_radiosity: the geometry term's clamp (0: none)
  bool final_gather = true;               // radiosity
  uint32_t bootstrap = 32768;             // mlt: bootstrap candidates per depth
  const Film* resume = nullptr;
};

// Renders on the test device; every hazard counter must stay at zero.
inline RenderResult render_with(const DeviceScene& scene, const Options& o) {
  RenderOptions opt;
  opt.spp = o.spp;
  opt.max_depth = o.max_depth;
  opt.seed = o.seed;
  opt.integrator = o.integrator;
  opt.pass_spp = o.pass_spp;
  opt.tile_pixels = o.tile_pixels;
  opt.work_group = o.work_group;
  opt.lanes = o.lanes;
  opt.debug_splat_pairs = o.pairs;
  opt.debug_bdpt_strategy_s = o.strategy_s;
  opt.debug_bdpt_strategy_t = o.strategy_t;
  opt.resume = o.resume;
  opt.merge = o.merge;
  opt.radius = o.radius;
  opt.merge_mis = o.merge_mis;
  opt.light_paths = o.light_paths;
  opt.clamp = o.clamp;
  opt.final_gather = o.final_gather;
  opt.bootstrap = o.bootstrap;
  RenderResult r = render(test_device(), scene, opt);
  EXPECT_EQ(r.nan_samples + r.inf_samples + r.negative_samples, 0u);
  EXPECT_EQ(r.splat_overflows, 0u);
  return r;
}

inline double image_mean(const Film& f) {
  double sum = 0;
  for (float v : f.mean) sum += v;
  return sum / f.mean.size();
}

// Mean and standard error of the image mean over `seeds` independent renders.
inline MeanStd seeded_mean(const DeviceScene& scene, Options o, int seeds) {
  std::vector<double> means;
  for (int s = 0; s < seeds; ++s) {
    o.seed = 1000 + s;
    means.push_back(image_mean(render_with(scene, o).film));
  }
  return mean_and_error(means);
}

inline DeviceScene scene_from(const std::string& name, const std::string& json) {
  return load_device_scene(write_temp_file(name, json));
}

// The Szirmay-Kalos sphere (scripts/make-cap-sphere: level 5, 16 x 16 pixels) and its exact values after n
// reflections: every wall pixel is f Le rho (1 - rho^n) / (1 - rho).
inline DeviceScene cap_sphere(std::vector<double>* exact) {
  std::string dir = temp_dir() + "/cap-sphere";
  std::string cmd = std::string("python3 ") + PATHCL_SOURCE_DIR + "/scripts/make-cap-sphere " + dir +
                    " --level 5 --size 16 >/dev/null";
  EXPECT_EQ(std::system(cmd.c_str()), 0);
  *exact = nlohmann::json::parse(std::ifstream(dir + "/exact.json"))["exact_sphere_value"].get<std::vector<double>>();
  return load_device_scene(dir + "/scene.json");
}

// The closed furnace of tests/furnace_test.cpp at 16 x 16: a sphere of radius 2 seen from inside, whose
// wall emits Le = 0.5 and reflects rho = 0.5 diffusely.
inline DeviceScene furnace_scene() {
  return scene_from("furnace.json", R"({"camera": {"position": [0.1, -0.2, 0.3], "look_at": [0.5, 0.4, -1],
    "fov_y_degrees": 100, "width": 16, "height": 16},
    "materials": {"grey": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}},
    "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 2, "flip_normals": true, "material": "grey", "emission": [0.5, 0.5, 0.5]}]})");
}

struct PixelComparison {
  size_t compared = 0, failed = 0;  // channels compared, and those with |z| > 4
  double sum_a = 0, sum_b = 0, sum_var = 0;  // sums of the compared means, and of their variances
  // |z| of the difference of the two images' sums (pixels taken as independent).
  double sum_z() const { return sum_var > 0 ? std::fabs(sum_b - sum_a) / std::sqrt(sum_var) : 0; }
};

// Per channel z = (b - a) / sqrt(var_a + var_b) over the pixels `skip` does not leave out.
inline PixelComparison compare_pixels(const Film& a, const Film& b, const std::function<bool(size_t pixel)>& skip) {
  PixelComparison c;
  for (size_t i = 0; i < a.mean.size(); ++i) {
    if (skip && skip(i / 3)) continue;
    double var = double(a.variance[i]) + b.variance[i];
    double d = double(b.mean[i]) - a.mean[i];
    ++c.compared;
    c.sum_var += var;
    c.sum_a += a.mean[i];
    c.sum_b += b.mean[i];
    if (var <= 0 ? d != 0 : std::fabs(d) / std::sqrt(var) > 4) ++c.failed;
  }
  return c;
}

// Films a and b estimate the same pixels (those `skip` does not leave out): per channel |z| > 4, with
// probability 6e-5 for correct estimators, in at most 1 in 200 channels (heavier tails of a few allowed),
// and the image sums within 4 standard errors. Returns the comparison.
inline PixelComparison expect_same_pixels(const Film& a, const Film& b, const std::function<bool(size_t pixel)>& skip = nullptr) {
  PixelComparison c = compare_pixels(a, b, skip);
  EXPECT_LE(c.failed, c.compared / 200) << c.failed << " of " << c.compared;
  EXPECT_LE(c.sum_z(), 4.0) << "image sums " << c.sum_a << " and " << c.sum_b;
  return c;
}

// The image is a pure function of scene, settings and seed: the same bits as a render with options o for
// a work-group size of 16, units of 3 spp over 37 paths, 32-bit word pairs instead of 64-bit atomics, and
// a render resumed from the half-way film of another (o.spp a power of two), and renders that a stop rule
// (target error, time) ended.
// The integrator over 8 and 16 lanes gives its one-lane film bit for bit, ray counts included, with every
// material and light type (materials.json: area, point, spot, directional and environment lights, a thin
// lens, a gaussian filter) and with instances and cut-outs, on a film whose path count is no multiple of
// the lanes, whole and in units that split a work item's paths. Without `instances`, materials.json alone.
inline void expect_one_lane_bits_at_every_width(const std::string& integrator, bool instances = true) {
  std::vector<std::string> files = {std::string(PATHCL_SOURCE_DIR) + "/scenes/materials.json"};
  if (instances) files.push_back(std::string(PATHCL_TEST_SCENES) + "/instances.json");
  for (const std::string& file : files) {
    DeviceScene scene = load_device_scene(file);
    scene.header.width = 23;
    scene.header.height = 17;
    Options o;
    o.integrator = integrator;
    o.spp = 4;
    o.max_depth = 6;
    o.lanes = 1;
    RenderResult one = render_with(scene, o);
    ASSERT_GT(image_mean(one.film), 0.0) << file;
    Options split_one = o;
    split_one.pass_spp = 3, split_one.tile_pixels = 37;
    // The rays of the one-lane render split alike (a merging unit traces every camera path of its iteration).
    const uint64_t split_rays = render_with(scene, split_one).rays;
    for (uint32_t lanes : {8u, 16u}) {
      for (bool split : {false, true}) {
        Options l = split ? split_one : o;
        l.lanes = lanes;
        RenderResult r = render_with(scene, l);
        std::string what = file + ", " + std::to_string(lanes) + " lanes" + (split ? ", split" : "");
        EXPECT_EQ(r.film.words, one.film.words) << what;
        EXPECT_EQ(r.rays, split ? split_rays : one.rays) << what;
      }
    }
  }
}

inline void expect_bitwise_deterministic(const DeviceScene& scene, const Options& o) {
  Film reference = render_with(scene, o).film;
  ASSERT_GT(image_mean(reference), 0.0);
  auto same = [&](const Film& f, const char* what) {
    EXPECT_EQ(f.words, reference.words) << what;
    EXPECT_EQ(f.mean, reference.mean) << what;
  };
  Options w = o;
  w.work_group = 16;
  same(render_with(scene, w).film, "work group 16");
  Options split = o;
  split.pass_spp = 3;
  split.tile_pixels = 37;
  same(render_with(scene, split).film, "units of 3 spp over 37 paths");
  Options pairs = o;
  pairs.pairs = true;
  same(render_with(scene, pairs).film, "32-bit word pairs");
  RenderOptions partial;
  partial.max_depth = o.max_depth;
  partial.seed = o.seed;
  partial.integrator = o.integrator;
  partial.merge = o.merge;
  partial.radius = o.radius;
  partial.merge_mis = o.merge_mis;
  partial.light_paths = o.light_paths;
  partial.clamp = o.clamp;
  partial.final_gather = o.final_gather;
  partial.bootstrap = o.bootstrap;
  Film start;
  {
    // Render o.spp with power-of-two horizons and keep the half-way film from the horizon callback.
    RenderOptions p = partial;
    p.spp = o.spp;
    p.power_of_two_horizons = true;
    RenderCallbacks cb;
    cb.horizon = [&](const Film& f, double, double) {
      if (f.spp == o.spp / 2) start = f;
    };
    render(test_device(), scene, p, cb);
  }
  ASSERT_EQ(start.spp, o.spp / 2);
  Options resumed = o;
  resumed.resume = &start;
  same(render_with(scene, resumed).film, "resumed half-way");
  // Stop rules end a render of these commutative units at a horizon, leaving the film that the render
  // without the rule has there (not that of a render asked for fewer spp: the splat scale depends on the
  // spp asked for), whatever the split into units.
  RenderOptions planned = partial;
  planned.spp = 8 * o.spp;
  planned.power_of_two_horizons = true;
  std::map<uint32_t, std::vector<uint32_t>> horizons;
  RenderCallbacks at_horizons;
  at_horizons.horizon = [&](const Film& f, double, double) { horizons[f.spp] = f.words; };
  render(test_device(), scene, planned, at_horizons);
  for (const char* rule : {"target_error", "time"}) {
    RenderOptions p = planned;
    p.tile_pixels = 37;
    if (std::string(rule) == "time") p.time_budget = 1e-9;  // over at the first horizon
    else p.target_error = 1e30;                             // met at the first check (8 spp)
    RenderResult stopped = render(test_device(), scene, p);
    EXPECT_EQ(stopped.stop_reason, rule);
    ASSERT_LT(stopped.film.spp, p.spp) << rule;
    ASSERT_EQ(horizons.count(stopped.film.spp), 1u) << rule << " stopped at " << stopped.film.spp << " spp";
    EXPECT_EQ(stopped.film.words, horizons[stopped.film.spp]) << rule << " at " << stopped.film.spp << " spp";
  }
}

}  // namespace light_transport_test
