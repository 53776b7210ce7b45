// Camera sampling (kernels/camera.cl): the pixel filters' 1-D distributions (filter importance sampling)
// against their own CDFs by chi-square, and the thin lens's geometry.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "chi2.h"
#include "test_support.h"

namespace {

constexpr size_t kSamples = 1000000;

std::vector<float> sample_filter(const SceneHeader& h, uint32_t seed, size_t n) {
  ClContext& cl = test_device();
  ClBuffer header = upload(cl, std::vector<SceneHeader>{h}), out(cl, CL_MEM_WRITE_ONLY, n * sizeof(float));
  ClKernel k(sampling_test_program().kernel("filter_sample_test"));
  k.arg(0, header.mem);
  k.arg(1, cl_uint(seed));
  k.arg(2, out.mem);
  run_kernel(cl, k.k, n);
  return read_buffer<float>(cl, out, n);
}

SceneHeader filter_header(uint32_t filter, float radius, float sigma = 0) {
  SceneHeader h{};
  h.filter = filter;
  h.filter_radius = radius;
  h.filter_sigma = sigma;
  return h;
}

struct FilterCase {
  std::string name;
  SceneHeader h;
  std::function<double(double)> cdf;  // of the offset, on [-radius, radius]
};

}  // namespace

TEST(FilterChi2, OffsetsFollowTheFiltersCdf) {
  auto tent = [](double r) {
    return [r](double x) { return x < 0 ? (x + r) * (x + r) / (2 * r * r) : 1 - (r - x) * (r - x) / (2 * r * r); };
  };
  auto gaussian = [](double r, double sigma) {  // truncated to [-r, r]
    return [r, sigma](double x) {
      double e = std::erf(r / (sigma * M_SQRT2));
      return (std::erf(x / (sigma * M_SQRT2)) + e) / (2 * e);
    };
  };
  std::vector<FilterCase> cases = {
      {"box", filter_header(PC_FILTER_BOX, 0.5f), [](double x) { return x + 0.5; }},
      {"tent radius 1", filter_header(PC_FILTER_TENT, 1), tent(1)},
      {"tent radius 2.5", filter_header(PC_FILTER_TENT, 2.5f), tent(2.5)},
      {"gaussian sigma 0.5 radius 1.5", filter_header(PC_FILTER_GAUSSIAN, 1.5f, 0.5f), gaussian(1.5, 0.5)},
      {"gaussian sigma 1 radius 1 (truncated hard)", filter_header(PC_FILTER_GAUSSIAN, 1, 1), gaussian(1, 1)},
      {"gaussian sigma 0.3 radius 2 (far tails)", filter_header(PC_FILTER_GAUSSIAN, 2, 0.3f), gaussian(2, 0.3)},
  };
  const int bins = 100;
  Chi2Family family(cases.size());
  for (size_t k = 0; k < cases.size(); ++k) {
    const FilterCase& c = cases[k];
    SCOPED_TRACE(c.name);
    double r = c.h.filter_radius;
    std::vector<float> x = sample_filter(c.h, 100 + uint32_t(k), kSamples);
    std::vector<double> observed(bins + 1, 0), expected(bins + 1, 0);  // the last cell: outside [-r, r]
    float lo = INFINITY, hi = -INFINITY;
    for (float v : x) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
      if (!(v >= -r && v <= r)) {
        observed[bins] += 1;
        continue;
      }
      observed[std::min(int((v + r) / (2 * r) * bins), bins - 1)] += 1;
    }
    for (int b = 0; b < bins; ++b)
      expected[b] = kSamples * (c.cdf(-r + 2 * r * (b + 1) / bins) - c.cdf(-r + 2 * r * b / bins));
    Chi2Result chi2 = chi2_test(observed, expected);
    family.expect_fit(c.name, chi2, "range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    EXPECT_EQ(observed[bins], 0) << "offsets beyond the radius";
  }
  family.print_summary();
}

// ---- The thin lens ----

namespace {

struct Rays {
  std::vector<float> v;
  glm::dvec3 o(size_t i) const { return {v[6 * i], v[6 * i + 1], v[6 * i + 2]}; }
  glm::dvec3 d(size_t i) const { return {v[6 * i + 3], v[6 * i + 4], v[6 * i + 5]}; }
};

// camera_ray for pixel (px, py): the position in the pixel fixed at u_pixel (or hashed when u_pixel.x < 0),
// the lens position hashed.
Rays camera_rays(const SceneHeader& h, uint32_t px, uint32_t py, float ux, float uy, uint32_t seed, size_t n) {
  ClContext& cl = test_device();
  ClBuffer header = upload(cl, std::vector<SceneHeader>{h}), out(cl, CL_MEM_WRITE_ONLY, n * 6 * sizeof(float));
  ClKernel k(sampling_test_program().kernel("camera_ray_test"));
  k.arg(0, header.mem);
  k.arg(1, cl_uint(px));
  k.arg(2, cl_uint(py));
  cl_float2 u = {{ux, uy}};
  k.arg(3, u);
  k.arg(4, cl_uint(seed));
  k.arg(5, out.mem);
  run_kernel(cl, k.k, n);
  return {read_buffer<float>(cl, out, n * 6)};
}

SceneHeader camera_header(const std::string& camera) {
  std::string scene = R"({"camera": )" + camera + R"(, "materials": {"m": {"type": "diffuse"}},
    "shapes": [{"type": "sphere", "radius": 1, "material": "m"}]})";
  return load_device_scene(write_temp_file("camera.json", scene)).header;
}

glm::dvec3 vec(const pc_float4& v) { return {v.x, v.y, v.z}; }

}  // namespace

TEST(ThinLens, RaysOfOnePixelPositionMeetInThePlaneInFocus) {
  const double aperture = 0.25, focus = 3.5;
  SceneHeader lens = camera_header(R"({"type": "thin_lens", "position": [1, 2, 5], "look_at": [0, 0.5, 0],
      "up": [0, 1, 0.2], "fov_y_degrees": 50, "width": 64, "height": 48, "aperture_radius": 0.25, "focus_distance": 3.5,
      "filter": {"type": "tent", "radius": 1.5}})");
  SceneHeader pinhole = lens;
  pinhole.lens_radius = 0;
  const glm::dvec3 cam = vec(lens.cam_position), forward = vec(lens.cam_forward);
  const size_t n = 20000;
  for (auto [px, py, ux, uy] : {std::tuple{10u, 20u, 0.3f, 0.8f}, {0u, 0u, 0.01f, 0.99f}, {63u, 47u, 0.5f, 0.5f}}) {
    SCOPED_TRACE("pixel " + std::to_string(px) + ", " + std::to_string(py));
    Rays center = camera_rays(pinhole, px, py, ux, uy, 1, 1);
    EXPECT_EQ(center.o(0), cam);
    glm::dvec3 d0 = center.d(0);
    glm::dvec3 target = cam + d0 * (focus / glm::dot(d0, forward));  // the pinhole ray in the plane in focus
    Rays rays = camera_rays(lens, px, py, ux, uy, 2, n);
    double r2_sum = 0, r2_sq = 0, max_r = 0;
    glm::dvec3 offset_sum(0);
    size_t off_focus = 0, off_lens = 0;
    for (size_t i = 0; i < n; ++i) {
      glm::dvec3 o = rays.o(i), d = rays.d(i), offset = o - cam;
      // On the lens: in the plane through the camera position facing forward, within the aperture.
      double r = glm::length(offset);
      off_lens += std::abs(glm::dot(offset, forward)) > 1e-6 || r > aperture * (1 + 1e-6);
      EXPECT_NEAR(glm::length(d), 1, 1e-6);
      glm::dvec3 p = o + d * ((focus - glm::dot(offset, forward)) / glm::dot(d, forward));
      off_focus += glm::length(p - target) > 2e-6 * (focus + glm::length(cam));  // float rounding
      r2_sum += r * r / (aperture * aperture);
      r2_sq += std::pow(r / aperture, 4);
      offset_sum += offset / aperture;
      max_r = std::max(max_r, r);
    }
    EXPECT_EQ(off_focus, 0u);
    EXPECT_EQ(off_lens, 0u);
    // Uniform over the disk: E[r^2] = R^2 / 2 (Var[r^2 / R^2] = 1/12), E[offset] = 0 (Var = R^2 / 4 per axis).
    double mean_r2 = r2_sum / n;
    EXPECT_NEAR(mean_r2, 0.5, 4 * std::sqrt(1.0 / 12 / n));
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(offset_sum[a] / n, 0, 4 * std::sqrt(0.25 / n));
    EXPECT_GT(max_r, 0.99 * aperture);
  }
}

TEST(ThinLens, WithoutApertureEveryRayStartsAtTheCamera) {
  SceneHeader pinhole = camera_header(R"({"position": [1, 2, 5], "look_at": [0, 0.5, 0], "width": 32, "height": 32,
      "filter": {"type": "gaussian", "sigma": 0.7}})");
  ASSERT_EQ(pinhole.lens_radius, 0.0f);
  Rays rays = camera_rays(pinhole, 5, 7, -1, -1, 3, 1000);  // pixel positions hashed too
  for (size_t i = 0; i < 1000; ++i) EXPECT_EQ(rays.o(i), vec(pinhole.cam_position));
}

// Camera rays and the warps give the same bits at 16, 8 and one lane (camera.cl, sampling.cl: written once
// over lanes for issue 15's lane-generic kernel), for every filter, pinhole and thin lens, with lanes on
// either side of every per-lane branch (tent halves, erf_inverse's two ranges, the disk's octants and
// centre) side by side.
TEST(CameraLanes, LanesGiveTheOneLaneBits) {
  const size_t items = 32, lanes = 16 * items;
  std::vector<uint32_t> px(lanes), py(lanes);
  std::vector<float> u(4 * lanes);
  uint32_t x = 777;
  auto next = [&] { return x = x * 1664525u + 1013904223u; };
  for (size_t i = 0; i < lanes; ++i) {
    px[i] = next() % 640;
    py[i] = next() % 480;
    for (int k = 0; k < 4; ++k) u[4 * i + k] = float(next() >> 8) * 0x1.0p-24f;
  }
  // Edge values in some lanes: the disk's centre, 0, just below 1, the tent's and erf's switch points.
  const float edges[] = {0.5f, 0.0f, 0x1.fffffep-1f, 0.49999997f, 0.99999f, 1e-7f};
  for (size_t e = 0; e < 6; ++e)
    for (int k = 0; k < 4; ++k) u[4 * (21 * e + 3) + k] = edges[(e + k) % 6];
  ClContext& cl = test_device();
  ClBuffer bx = upload(cl, px), by = upload(cl, py), bu = upload(cl, u);
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, items * 3 * 256 * sizeof(uint32_t));
  struct Case { const char* name; uint32_t filter; float radius, sigma, lens; };
  for (const Case& c : {Case{"box pinhole", PC_FILTER_BOX, 0.5f, 0, 0}, Case{"tent thin lens", PC_FILTER_TENT, 1.5f, 0, 0.2f},
                        Case{"gaussian pinhole", PC_FILTER_GAUSSIAN, 1.5f, 0.5f, 0},
                        Case{"gaussian thin lens", PC_FILTER_GAUSSIAN, 2, 0.3f, 0.05f}}) {
    SceneHeader h = filter_header(c.filter, c.radius, c.sigma);
    h.width = 640;
    h.height = 480;
    h.cam_position = {1.5f, -2, 3, 0};
    h.cam_forward = {0.1f, 0.2f, -1, 0};
    h.cam_right = {0.55f, 0, 0.05f, 0};
    h.cam_up = {0, 0.41f, 0.08f, 0};
    h.lens_radius = c.lens;
    h.focus_distance = 4.5f;
    ClBuffer header = upload(cl, std::vector<SceneHeader>{h});
    ClKernel k(sampling_test_program().kernel("camera_lanes_test"));
    k.arg(0, header.mem);
    k.arg(1, bx.mem);
    k.arg(2, by.mem);
    k.arg(3, bu.mem);
    k.arg(4, out.mem);
    run_kernel(cl, k.k, items);
    std::vector<uint32_t> bits = read_buffer<uint32_t>(cl, out, items * 3 * 256);
    LaneComparison lc = compare_lanes(bits, items, 256, [](float f) { return bool(std::isfinite(f)); });
    EXPECT_EQ(lc.differing, 0u) << c.name;
    EXPECT_EQ(lc.valid, items * 256) << c.name;
  }
}

// make_frame, offset_ray_origin, power_heuristic and the origin's rounding step (math.cl, written once over
// lanes) give the one-lane bits at 16 and 8 lanes: normals of both hemispheres, offsets to both sides and zero
// error bounds, pdfs whose squares overflow or underflow and zero pdfs, side by side in one vector; and the
// step, pc_offset_component_(x, offset), is std::nextafter(x + offset) towards offset's infinity (x + offset
// for a zero offset): zeros, denormals, the largest finite floats, infinities, NaN and floats of random bits.
TEST(CameraLanes, FrameOffsetMisWeightAndNextFloatGiveTheOneLaneBits) {
  const size_t items = 32, lanes = 16 * items, results = 13;
  std::vector<float> in(15 * lanes);
  uint32_t x = 4242;
  auto next = [&] { return x = x * 1664525u + 1013904223u; };
  auto uniform = [&] { return float(next() >> 8) * 0x1.0p-24f; };
  const float special[] = {0.0f, -0.0f, 0x1.0p-149f, -0x1.0p-149f, 0x1.fffffcp-127f, -0x1.fffffcp-127f, FLT_MIN,
                           -FLT_MIN, FLT_MAX, -FLT_MAX, INFINITY, -INFINITY, NAN, 1.0f, -1.0f, 0x1.fffffep-1f};
  const size_t specials = sizeof special / sizeof special[0];
  size_t not_finite = 0;  // results that are infinite or NaN (inputs of the next floats)
  for (size_t j = 0; j < lanes; ++j) {
    float* v = &in[15 * j];
    float n[3] = {2 * uniform() - 1, 2 * uniform() - 1, 2 * uniform() - 1};
    float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; ++k) v[k] = n[k] / len;
    for (int k = 3; k < 6; ++k) v[k] = j % 7 == 0 ? 0.0f : uniform() * 1e-5f;
    for (int k = 6; k < 12; ++k) v[k] = (2 * uniform() - 1) * 10;
    const float pdfs[] = {0.0f, 1e-30f, 1e30f, 1.0f};
    v[12] = j % 5 == 0 ? pdfs[j / 5 % 4] : uniform() * 4;
    v[13] = j % 3 == 0 ? pdfs[j / 3 % 4] : uniform() * 4;
    uint32_t b = next();
    std::memcpy(&v[14], &b, 4);
    if (j % 3 == 0) v[14] = special[j / 3 % specials];
    not_finite += !std::isfinite(std::nextafter(v[14] + 0x1p-149f, INFINITY)) +
                  !std::isfinite(std::nextafter(v[14] - 0x1p-149f, -INFINITY)) + !std::isfinite(v[14] + 0.0f);
  }
  std::vector<uint32_t> bits = run_float_lanes_test("math_lanes_test", in, items, 16 * results);
  LaneComparison lc = compare_lanes(bits, items, 16 * results, [](float f) { return bool(std::isfinite(f)); });
  EXPECT_EQ(lc.differing, 0u);
  EXPECT_EQ(lc.valid, items * 16 * results - not_finite);
  for (size_t j = 0; j < lanes; ++j) {
    const float v = in[15 * j + 14];
    const uint32_t* one = &bits[(3 * (j / 16) + 2) * 16 * results + (j % 16) * results];  // the one-lane results
    const float wants[3] = {std::nextafter(v + 0x1p-149f, INFINITY), std::nextafter(v - 0x1p-149f, -INFINITY),
                            v + 0.0f};
    for (int k = 0; k < 3; ++k) {
      float got, want = wants[k];
      std::memcpy(&got, &one[10 + k], 4);
      uint32_t want_bits, v_bits;
      std::memcpy(&want_bits, &want, 4);
      std::memcpy(&v_bits, &v, 4);
      if (std::isnan(want))
        EXPECT_TRUE(std::isnan(got)) << "the step from NaN";
      else
        EXPECT_EQ(one[10 + k], want_bits) << (k == 0 ? "up" : k == 1 ? "down" : "no offset") << " from bits "
                                          << std::hex << v_bits;
    }
  }
}
