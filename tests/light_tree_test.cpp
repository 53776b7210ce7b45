// Light choice from a shading point (kernels/light_tree.cl, scene/light_bvh_build.h): the probabilities
// the kernel reports for every light against the counts of its choices (chi-square), and the renders the
// light BVH is for: a point and a spot light beside an environment over a floor of any size, and a
// thousand small emitters.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "chi2.h"
#include "runtime/film.h"
#include "runtime/renderer.h"
#include "test_support.h"

namespace {

pc_float4 f4(double x, double y, double z) { return {float(x), float(y), float(z), 0.0f}; }

std::string triangle(const double (&v)[9], const std::string& extra) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                R"({"type": "triangles", "positions": [[%.9g, %.9g, %.9g], [%.9g, %.9g, %.9g], [%.9g, %.9g, %.9g]],
                   "indices": [[0, 1, 2]], "material": "m", %s})",
                v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], extra.c_str());
  return buf;
}

std::string emission(double e) {
  char buf[80];
  std::snprintf(buf, sizeof buf, R"("emission": [%.9g, %.9g, %.9g])", e, e, e);
  return buf;
}

// Every kind of light: triangles of many sizes, facings and strengths (some two-sided), spheres, point and
// spot lights, a directional light and an environment.
std::string mixed_lights_scene() {
  std::mt19937 rng(16);
  std::uniform_real_distribution<double> u(0, 1);
  std::string shapes;
  for (int i = 0; i < 40; ++i) {
    double c[3] = {8 * u(rng) - 4, 8 * u(rng) - 4, 8 * u(rng) - 4}, s = 0.05 + 0.5 * u(rng);
    double v[9];
    for (int k = 0; k < 9; ++k) v[k] = c[k % 3] + s * (2 * u(rng) - 1);
    shapes += (i ? ", " : "") + triangle(v, emission(0.5 + 10 * u(rng)) + (i % 3 == 0 ? R"(, "two_sided": true)" : ""));
  }
  // Open fans of n triangles around a centre, of unequal areas, in a tilted plane: emitter groups of 2, 5 (two-
  // sided), 8 and 16 triangles (more than 8, but small beside the scene); left apart, 12 triangles spanning
  // more than a quarter of the scene's diagonal and 4 bent out of their plane (each triangle its own leaf).
  struct Fan { int n; bool bent; double size; };
  const Fan fans[] = {{2, false, 1}, {5, false, 1}, {8, false, 1}, {16, false, 1}, {12, false, 6}, {4, true, 1}};
  for (int f = 0; f < 6; ++f) {
    const int n = fans[f].n;
    const bool bent = fans[f].bent;
    double c[3] = {8 * u(rng) - 4, 8 * u(rng) - 4, 8 * u(rng) - 4};
    std::string positions = "[" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " + std::to_string(c[2]) + "]";
    std::string indices;
    for (int k = 0; k <= n; ++k) {
      double angle = 2 * M_PI * k / (n + 1), r = fans[f].size * (0.2 + 0.6 * u(rng)), x = r * std::cos(angle), y = r * std::sin(angle);
      double lift = bent && k % 2 ? 0.3 : 0;  // tilted plane (x, y, 0.5 x + 0.25 y), lifted off it where bent
      char v[160];
      std::snprintf(v, sizeof v, ", [%.9g, %.9g, %.9g]", c[0] + x, c[1] + y, c[2] + 0.5 * x + 0.25 * y + lift);
      positions += v;
      if (k < n) indices += (k ? ", [0, " : "[0, ") + std::to_string(k + 1) + ", " + std::to_string(k + 2) + "]";
    }
    shapes += R"(, {"type": "triangles", "positions": [)" + positions + R"(], "indices": [)" + indices +
              R"(], "material": "m", )" + emission(1 + 4 * u(rng)) + (f == 1 ? R"(, "two_sided": true)" : "") + "}";
  }
  for (int i = 0; i < 5; ++i) {
    char buf[200];
    std::snprintf(buf, sizeof buf, R"(, {"type": "sphere", "center": [%.6g, %.6g, %.6g], "radius": %.6g, "material": "m", %s})",
                  8 * u(rng) - 4, 8 * u(rng) - 4, 8 * u(rng) - 4, 0.1 + 0.3 * u(rng), emission(1 + 5 * u(rng)).c_str());
    shapes += buf;
  }
  std::string lights = R"({"type": "environment", "radiance": [0.2, 0.3, 0.4]},
                          {"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": [1, 1, 1]})";
  for (int i = 0; i < 5; ++i) {
    char buf[300];
    std::snprintf(buf, sizeof buf, R"(, {"type": "point", "position": [%.6g, %.6g, %.6g], "intensity": [%.6g, 1, 1]})",
                  8 * u(rng) - 4, 8 * u(rng) - 4, 8 * u(rng) - 4, 1 + 20 * u(rng));
    lights += buf;
    std::snprintf(buf, sizeof buf,
                  R"(, {"type": "spot", "position": [%.6g, %.6g, %.6g], "direction": [%.6g, -1, %.6g], "intensity": [5, 5, 5],
                        "outer_angle_degrees": 30, "inner_angle_degrees": 20})",
                  8 * u(rng) - 4, 8 * u(rng) - 4, 8 * u(rng) - 4, u(rng) - 0.5, u(rng) - 0.5);
    lights += buf;
  }
  return R"({"camera": {"position": [0, 0, -10], "look_at": [0, 0, 0], "width": 4, "height": 4},
    "materials": {"m": {"type": "diffuse", "reflectance": [0, 0, 0]}}, "shapes": [)" +
         shapes + R"(], "lights": [)" + lights + "]}";
}

}  // namespace

// From points inside, beside and far from the lights: the reported probability of each choice is the
// probability light_choice_pdf gives that light (bit for bit: MIS reads the second), those sum to 1, and
// the choices' counts follow them (chi-square, a Sidak-corrected 1 % family over the points).
TEST(LightTree, ChoiceProbabilitiesAreThePdfsTheKernelReports) {
  DeviceScene scene = load_device_scene(write_temp_file("mixed-lights.json", mixed_lights_scene()), DeviceOrigin::world);
  const uint32_t lights = scene.header.light_count;
  ASSERT_EQ(lights, 40u + (2u + 5u + 8u + 16u + 12u + 4u) + 5u + 10u + 2u);
  ASSERT_EQ(scene.header.tree_light_count, lights - 2);
  // The four small planar fans are emitter groups, one leaf each; every other light is a leaf alone.
  std::vector<uint32_t> group_sizes;
  for (const LightBvhNode& n : scene.light_bvh)
    if (n.second == PC_INVALID && n.light_count > 1) group_sizes.push_back(n.light_count);
  std::sort(group_sizes.begin(), group_sizes.end());
  EXPECT_EQ(group_sizes, (std::vector<uint32_t>{2, 5, 8, 16}));
  EXPECT_EQ(scene.light_bvh.size(), 2 * (scene.header.tree_light_count - (1 + 4 + 7 + 15)) - 1);
  SceneBuffers sb = test_scene_buffers(scene);
  ClContext& cl = test_device();
  const size_t n = 1000000;
  const std::vector<pc_float4> points = {f4(0, 0, 0), f4(3.9, -3.9, 3.9), f4(0.5, 2, -1), f4(40, 10, -30), f4(-2, 0.1, 3)};
  Chi2Family family(points.size());
  for (size_t pi = 0; pi < points.size(); ++pi) {
    ClBuffer chosen(cl, CL_MEM_WRITE_ONLY, n * sizeof(cl_uint)), p(cl, CL_MEM_WRITE_ONLY, n * sizeof(float)),
        pdf(cl, CL_MEM_WRITE_ONLY, lights * sizeof(float));
    ClKernel k(sampling_test_program().kernel("light_choice_test"));
    cl_uint a = sb.bind(k);
    k.arg(a++, points[pi]);
    k.arg(a++, cl_uint(7 + pi));
    k.arg(a++, chosen.mem);
    k.arg(a++, p.mem);
    k.arg(a++, pdf.mem);
    run_kernel(cl, k.k, n);
    std::vector<cl_uint> c = read_buffer<cl_uint>(cl, chosen, n);
    std::vector<float> reported = read_buffer<float>(cl, p, n), pdf_of = read_buffer<float>(cl, pdf, lights);
    double total = 0;
    for (float q : pdf_of) {
      EXPECT_TRUE(q >= 0 && q <= 1) << q;
      total += q;
    }
    EXPECT_NEAR(total, 1.0, 1e-5) << "point " << pi;
    std::vector<double> observed(lights, 0), expected(lights);
    size_t mismatches = 0;
    for (size_t i = 0; i < n; ++i) {
      ASSERT_LT(c[i], lights);
      observed[c[i]] += 1;
      mismatches += reported[i] != pdf_of[c[i]];
    }
    EXPECT_EQ(mismatches, 0u) << "point " << pi << ": the probability of a choice differs from the pdf of its light";
    for (uint32_t l = 0; l < lights; ++l) expected[l] = double(pdf_of[l]) * double(n);
    char name[64];
    std::snprintf(name, sizeof name, "light choice from point %zu", pi);
    family.expect_fit(name, chi2_test(observed, expected), "");
  }
  family.print_summary();
}

namespace {

RenderResult render_scene(const DeviceScene& scene, uint32_t spp, uint32_t max_depth, uint32_t seed) {
  RenderOptions opt;
  opt.spp = spp;
  opt.max_depth = max_depth;
  opt.seed = seed;
  RenderResult r = render(test_device(), scene, opt);
  EXPECT_EQ(r.nan_samples + r.inf_samples + r.negative_samples, 0u);
  return r;
}

// The issue's scene: a diffuse floor of width x depth, a point and a spot light and a constant
// environment, seen from straight above so that the image shows the middle 5.6 x 5.6 of any floor.
DeviceScene floor_scene(double width, double depth) {
  char buf[1600];
  std::snprintf(buf, sizeof buf, R"({"camera": {"position": [0, 5, 0], "look_at": [0, 0, 0], "up": [0, 0, -1],
      "fov_y_degrees": 60, "width": 32, "height": 32},
    "materials": {"floor": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}},
    "shapes": [{"type": "triangles", "positions": [[%g, 0, %g], [%g, 0, %g], [%g, 0, %g], [%g, 0, %g]],
                "indices": [[0, 2, 1], [0, 3, 2]], "material": "floor"}],
    "lights": [{"type": "point", "position": [-1, 1.5, 0.5], "intensity": [4, 4, 4]},
               {"type": "spot", "position": [1.5, 2.5, -1], "direction": [0, -1, 0], "intensity": [20, 20, 20],
                "outer_angle_degrees": 35, "inner_angle_degrees": 25},
               {"type": "environment", "radiance": [0.3, 0.3, 0.3]}]})",
                -width / 2, -depth / 2, width / 2, -depth / 2, width / 2, depth / 2, -width / 2, depth / 2);
  return load_device_scene(write_temp_file("floor.json", buf));
}

}  // namespace

// Choice by power weighed the environment by the scene's bounding radius squared: a 60 x 60 floor
// starved the point and the spot light of samples (the issue: relMSE 0.063 against 0.020 for a 16 x 8
// floor). The light choice now depends on the shading point only, so the floor's size leaves the
// error of the same view unchanged: the two estimated relMSEs (from the half images, each known to a few
// per cent over 1024 pixels) agree within 15 %.
TEST(LightTree, BigFloorReachesTheSmallFloorsError) {
  const uint32_t spp = 32;
  double small = estimated_rel_mse(render_scene(floor_scene(16, 8), spp, 3, 5).film);
  double big = estimated_rel_mse(render_scene(floor_scene(60, 60), spp, 3, 5).film);
  std::printf("estimated relMSE at %u spp: 16 x 8 floor %.4f, 60 x 60 floor %.4f\n", spp, small, big);
  EXPECT_GT(small, 0.0);
  EXPECT_LT(big, 1.15 * small);
}

namespace {

// A thousand small one-sided emitters of random strengths facing down from a ceiling over a diffuse
// floor: from any floor point a few nearby emitters give most of the light.
DeviceScene many_emitters_scene() {
  std::mt19937 rng(1000);
  std::uniform_real_distribution<double> u(0, 1);
  std::string shapes = R"({"type": "triangles", "positions": [[-20, 0, -20], [20, 0, -20], [20, 0, 20], [-20, 0, 20]],
                           "indices": [[0, 2, 1], [0, 3, 2]], "material": "floor"})";
  for (int i = 0; i < 1000; ++i) {
    double x = 40 * u(rng) - 20, z = 40 * u(rng) - 20, y = 1 + 2 * u(rng), s = 0.05;
    // Wound so that the normal points down (-y).
    double v[9] = {x - s, y, z - s, x + s, y, z - s, x, y, z + s};
    char extra[120];
    std::snprintf(extra, sizeof extra, R"("emission": [%.6g, %.6g, %.6g])", 50 * u(rng), 40.0, 30.0);
    shapes += ", " + triangle(v, extra);
  }
  std::string json = R"({"camera": {"position": [0, 6, 12], "look_at": [0, 0, 0], "fov_y_degrees": 60, "width": 32, "height": 24},
    "materials": {"floor": {"type": "diffuse", "reflectance": [0.6, 0.6, 0.6]}, "m": {"type": "diffuse", "reflectance": [0, 0, 0]}},
    "shapes": [)" + shapes + "]}";
  return load_device_scene(write_temp_file("many-emitters.json", json));
}

// Power-proportional choice made of the same tree: every node given the root's box and the whole sphere of
// directions weighs its children by their intensities alone, whatever the shading point.
DeviceScene with_power_proportional_choice(DeviceScene scene) {
  const LightBvhNode root = scene.light_bvh[0];
  for (LightBvhNode& n : scene.light_bvh) {
    n.lo = {root.lo.x, root.lo.y, root.lo.z, n.lo.w};
    n.hi = {root.hi.x, root.hi.y, root.hi.z, -1.0f};
    n.axis.w = 0;
    n.two_sided = 0;
  }
  return scene;
}

double image_mean(const Film& f) {
  double sum = 0;
  for (float v : f.mean) sum += v;
  return sum / double(f.mean.size());
}

double image_mean_error(const Film& f) {
  double var = 0;
  for (float v : f.variance) var += v;
  return std::sqrt(var) / double(f.variance.size());
}

}  // namespace

// With a thousand emitters the tree finds the near ones: at equal samples its error is well below that of
// choice by power (measured: 0.006 against 0.10), and both estimate the same image (means within 4 standard
// errors: the tree's probabilities are exact, so it changes the noise only).
TEST(LightTree, ThousandEmittersBeatChoiceByPower) {
  DeviceScene tree = many_emitters_scene();
  ASSERT_EQ(tree.header.tree_light_count, 1000u);
  DeviceScene power = with_power_proportional_choice(tree);
  const uint32_t spp = 16;
  RenderResult a = render_scene(tree, spp, 2, 3), b = render_scene(power, spp, 2, 3);
  double tree_error = estimated_rel_mse(a.film), power_error = estimated_rel_mse(b.film);
  std::printf("estimated relMSE at %u spp: light BVH %.4f, by power %.4f\n", spp, tree_error, power_error);
  EXPECT_LT(tree_error, 0.25 * power_error);
  double ma = image_mean(a.film), mb = image_mean(b.film);
  double se = std::hypot(image_mean_error(a.film), image_mean_error(b.film));
  EXPECT_LT(std::abs(ma - mb), 4 * se) << ma << " vs " << mb << ", standard error " << se;
}
