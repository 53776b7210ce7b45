// Light choice from a shading point (kernels/light_tree.cl, scene/light_bvh_build.h): the probabilities
// the kernel reports for every light against the counts of its choices (chi-square), and the renders the
// light BVH is for: a point and a spot light beside an environment over a floor of any size, and a
// thousand small emitters.
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
  ASSERT_EQ(lights, 40u + 5u + 10u + 2u);
  ASSERT_EQ(scene.header.tree_light_count, lights - 2);
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
