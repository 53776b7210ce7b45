// Light sampling (kernels/lights.cl, kernels/environment.cl) against the densities the integrator uses
// for the same directions: chi-square tests of area lights (triangles by area; spheres by cone from
// outside, by area from inside) and of synthetic environment maps (lat-long and pbrt-v4's equal-area
// squares), every sample checked against the light it points at; the equal-area mapping on the device
// against double precision; spot and point lights exactly.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/vec2.hpp>
#include <gtest/gtest.h>

#include "chi2.h"
#include "runtime/image_io.h"
#include "runtime/kernel_sources.h"
#include "scene/scene_error.h"
#include "test_support.h"

namespace {

// The test kernels take shading points in world coordinates: flatten around the world origin.
DeviceScene load_world_scene(const std::string& path) { return load_device_scene(path, DeviceOrigin::world); }

constexpr double kDeg = M_PI / 180;
constexpr size_t kChi2Samples = 1000000;

pc_float4 f4(const glm::dvec3& v) { return {float(v.x), float(v.y), float(v.z), 0.0f}; }

std::string scene_json(const std::string& shapes, const std::string& lights = "") {
  return R"({"camera": {"position": [0, 0, -5], "look_at": [0, 0, 0], "width": 4, "height": 4},
    "materials": {"lamp": {"type": "diffuse", "reflectance": [0, 0, 0]}}, "shapes": [)" +
         shapes + "]" + (lights.empty() ? "" : R"(, "lights": [)" + lights + "]") + "}";
}

// Light samples as light_sample_test writes them, 12 floats each.
struct LightSamples {
  std::vector<float> v;
  size_t n = 0;
  glm::dvec3 wi(size_t i) const { return {v[12 * i], v[12 * i + 1], v[12 * i + 2]}; }
  int status(size_t i) const { return int(v[12 * i + 3]); }
  double pdf(size_t i) const { return v[12 * i + 4]; }
  double pdf_eval(size_t i) const { return v[12 * i + 5]; }
  glm::dvec3 le(size_t i) const { return {v[12 * i + 6], v[12 * i + 7], v[12 * i + 8]}; }
  double le_seen(size_t i) const { return v[12 * i + 9]; }
  double distance(size_t i) const { return v[12 * i + 10]; }
  double hit_t(size_t i) const { return v[12 * i + 11]; }
};

LightSamples sample_lights(const SceneBuffers& sb, const glm::dvec3& x, uint32_t seed, size_t n) {
  ClContext& cl = test_device();
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, n * 12 * sizeof(float));
  ClKernel k(sampling_test_program().kernel("light_sample_test"));
  cl_uint a = sb.bind(k);
  k.arg(a++, f4(x));
  k.arg(a++, cl_uint(seed));
  k.arg(a++, out.mem);
  run_kernel(cl, k.k, n);
  return {read_buffer<float>(cl, out, n * 12), n};
}

BinIntegrator light_pdf_integrator(const SceneBuffers& sb, const glm::dvec3& x, const SphereBinning& binning) {
  return [&sb, x, binning](const std::vector<uint32_t>& bins, int order) {
    ClKernel k(sampling_test_program().kernel("light_pdf_bins"));
    cl_uint a = sb.bind(k);
    k.arg(a++, f4(x));
    return run_pdf_bins_kernel(k, a, binning, bins, order);
  };
}

struct LightCase {
  std::string name;
  DeviceScene scene;
  glm::dvec3 x;           // the shading point
  SphereBinning binning;  // directions from x
  double emission = 1;    // expected Le (first channel) of every sample
};

struct LightOutcome {
  Chi2Result chi2;
  BinIntegrals integrals;
  double pdf_total = 0, sampled_fraction = 0;
  size_t mismatches = 0;
  std::string first_problem;
};

// Samples are binned by direction (failures in the cell beyond the bins); each one must point at the
// light it claims (hit distance = distance to the sampled point, radiance seen = Le = emission) with the
// density the integrator would find for that direction.
LightOutcome run_light_chi2(const LightCase& c, uint32_t seed, size_t n = kChi2Samples) {
  SceneBuffers sb = test_scene_buffers(c.scene);
  LightSamples s = sample_lights(sb, c.x, seed, n);
  LightOutcome r;
  std::vector<double> observed(c.binning.count() + 1, 0);
  for (size_t i = 0; i < n; ++i) {
    if (s.status(i) == 0) {
      observed.back() += 1;
      continue;
    }
    r.sampled_fraction += 1;
    glm::dvec3 wi = s.wi(i);
    observed[c.binning.bin_of(wi)] += 1;
    bool far = std::isinf(s.distance(i));
    bool ok = s.status(i) == 1 && std::abs(glm::length(wi) - 1) < 1e-5 && close_rel(s.pdf(i), s.pdf_eval(i), 1e-3) &&
              close_rel(s.le(i).x, c.emission, 1e-6) && close_rel(s.le_seen(i), c.emission, 1e-6) &&
              (far ? std::isinf(s.hit_t(i)) : close_rel(s.hit_t(i), s.distance(i), 1e-4));
    if (!ok && !r.mismatches++) {
      char buf[300];
      std::snprintf(buf, sizeof buf,
                    "sample %zu: wi (%g %g %g) status %d pdf %.7g, pdf of the direction %.7g, Le %g, seen %g, "
                    "distance %.7g, hit at %.7g",
                    i, wi.x, wi.y, wi.z, s.status(i), s.pdf(i), s.pdf_eval(i), s.le(i).x, s.le_seen(i), s.distance(i),
                    s.hit_t(i));
      r.first_problem = buf;
    }
  }
  r.sampled_fraction /= double(n);
  r.integrals = integrate_bins(light_pdf_integrator(sb, c.x, c.binning), c.binning.count(), double(n), 0.1, 256);
  r.chi2 = chi2_test(observed, expected_counts(r.integrals, double(n), &r.pdf_total));
  return r;
}

void expect_light_family(const std::vector<LightCase>& cases, uint32_t seed) {
  Chi2Family family(cases.size());
  for (size_t i = 0; i < cases.size(); ++i) {
    const LightCase& c = cases[i];
    LightOutcome r = run_light_chi2(c, seed + uint32_t(i));
    family.expect_fit(c.name, r.chi2, run_detail(r.pdf_total, r.sampled_fraction, r.integrals.highest_order));
    SCOPED_TRACE(c.name);
    // Expected counts good to half a standard error in every bin (the refinement aims at a tenth).
    EXPECT_LT(r.integrals.worst, 0.5) << "quadrature: " << r.integrals.unconverged << " bins unconverged";
    // Samples whose ray just grazes the light's outline may see no light in single precision: at most 1e-5.
    EXPECT_LE(r.mismatches, kChi2Samples / 100000) << r.mismatches << " samples, first: " << r.first_problem;
    double f = r.sampled_fraction, se = std::sqrt(f * (1 - f) / double(kChi2Samples));
    EXPECT_NEAR(r.pdf_total, f, 5 * se + 5e-4);  // 5e-4: quadrature of the density's discontinuous outline
    EXPECT_GT(r.sampled_fraction, 0.999);
  }
  family.print_summary();
}

std::string triangle_json(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const std::string& extra) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                R"({"type": "triangles", "positions": [[%.9g, %.9g, %.9g], [%.9g, %.9g, %.9g], [%.9g, %.9g, %.9g]],
                   "indices": [[0, 1, 2]], "material": "lamp", %s})",
                a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, extra.c_str());
  return buf;
}

std::string sphere_json(const glm::dvec3& c, double r, const std::string& extra) {
  char buf[512];
  std::snprintf(buf, sizeof buf, R"({"type": "sphere", "center": [%.9g, %.9g, %.9g], "radius": %.9g, "material": "lamp", %s})",
                c.x, c.y, c.z, r, extra.c_str());
  return buf;
}

}  // namespace

TEST(LightChi2, AreaLights) {
  std::vector<LightCase> cases;
  auto add = [&](const std::string& name, const std::string& shape, const glm::dvec3& x, const SphereBinning& b) {
    cases.push_back({name, load_world_scene(write_temp_file("light.json", scene_json(shape))), x, b, 2.5});
  };
  // A triangle above x, its front (counter-clockwise) side facing x; binned over the whole sphere.
  glm::dvec3 a(-1, -0.5, 2), b(0.2, 1.2, 1.8), c(1.5, -1, 2.5);
  add("triangle", triangle_json(a, b, c, R"("emission": [2.5, 2.5, 2.5])"), {0.1, 0.2, 0}, SphereBinning());
  add("triangle, two-sided, seen from behind", triangle_json(a, c, b, R"("emission": [2.5, 2.5, 2.5], "two_sided": true)"),
      {0.1, 0.2, 0}, SphereBinning());
  // Binned finely about the direction of a small, oblique triangle.
  glm::dvec3 x(0.3, -0.4, 0.1), t0(2, 0.1, 0.5), t1(2.2, 0.5, 0.3), t2(1.9, 0.4, 0.9);
  glm::dvec3 centre = (t0 + t1 + t2) / 3.0;
  add("small oblique triangle", triangle_json(t0, t2, t1, R"("emission": [2.5, 2.5, 2.5])"), x,
      SphereBinning::about(centre - x, 20 * kDeg));
  // Spheres from outside: sampled by the cone they subtend.
  glm::dvec3 origin(0, 0, 0);
  add("sphere by cone, near", sphere_json({0.2, -0.1, 1.4}, 1, R"("emission": [2.5, 2.5, 2.5])"), origin, SphereBinning());
  add("sphere by cone, far", sphere_json({0.5, 3, 1}, 0.8, R"("emission": [2.5, 2.5, 2.5])"), origin,
      SphereBinning::about({0.5, 3, 1}, 18 * kDeg));
  // sin^2(theta_max) = 4e-4, below the small-cone threshold of sample_sphere_cone_lanes (sin^2(1.5 degrees)).
  glm::dvec3 tiny(0.6, -0.8, 0);
  add("tiny sphere by cone", sphere_json(tiny, 0.02, R"("emission": [2.5, 2.5, 2.5])"), origin,
      SphereBinning::about(tiny, 1.5 * kDeg));
  // From inside a sphere emitting inwards: sampled by area.
  add("sphere by area from inside", sphere_json({0.1, 0.2, -0.3}, 1.5, R"("emission": [2.5, 2.5, 2.5], "flip_normals": true)"),
      origin, SphereBinning());
  add("two-sided sphere by area, off centre",
      sphere_json({0.1, 0.2, -0.3}, 1.5, R"("emission": [2.5, 2.5, 2.5], "two_sided": true)"), {1.0, 0.8, -0.5},
      SphereBinning());
  // Two lights, apart as seen from x: one is chosen through the light BVH, and the density of a
  // direction is the probability of choosing that light from x times its own.
  add("triangle and sphere, chosen through the light BVH",
      triangle_json(a, b, c, R"("emission": [2.5, 2.5, 2.5])") + ", " +
          sphere_json({-2, -1.5, -1}, 0.6, R"("emission": [2.5, 2.5, 2.5])"),
      {0.1, 0.2, 0}, SphereBinning());
  expect_light_family(cases, 5000);
}

TEST(LightSampling, OneSidedLightsSeenFromBehindGiveNoSamples) {
  glm::dvec3 a(-1, -0.5, 2), b(0.2, 1.2, 1.8), c(1.5, -1, 2.5);
  for (const std::string& shape :
       {triangle_json(a, c, b, R"("emission": [1, 1, 1])"), sphere_json({0, 0, 0.5}, 2, R"("emission": [1, 1, 1])")}) {
    SceneBuffers sb = test_scene_buffers(load_world_scene(write_temp_file("behind.json", scene_json(shape))));
    LightSamples s = sample_lights(sb, {0.1, 0.2, 0}, 3, 10000);
    for (size_t i = 0; i < s.n; ++i) ASSERT_EQ(s.status(i), 0) << shape;
  }
}

TEST(LightChi2, ConstantEnvironment) {
  // Uniform over the sphere; a constant environment needs no map.
  std::vector<LightCase> cases = {{"constant environment",
                                   load_world_scene(write_temp_file(
                                       "sky.json", scene_json("", R"({"type": "environment", "radiance": [0.7, 0.7, 0.7]})"))),
                                   {0.5, -2, 1}, SphereBinning(), 0.7}};
  expect_light_family(cases, 5500);
}

// ---- The environment map ----

namespace {

// An environment map's parameterisation and lookup (the light's "mapping" and "filter").
enum class EnvMapping { lat_long, equal_area, equal_area_nearest };

std::string mapping_json(EnvMapping m) {
  if (m == EnvMapping::equal_area) return R"(, "mapping": "equal_area")";
  if (m == EnvMapping::equal_area_nearest) return R"(, "mapping": "equal_area", "filter": "nearest")";
  return "";
}

bool is_equal_area(EnvMapping m) { return m != EnvMapping::lat_long; }

// A 32 x 16 map (32 x 32 for an equal-area map): a smooth background with a dark row, a dark block and
// single dark texels (all exactly 0) and one bright texel; colours differ per channel so that luminance is
// not one channel. The square one also has bright texels on two edges and in a corner, whose light the
// lookup carries across the square's folded edges.
Image synthetic_env_map(bool square = false) {
  Image img;
  img.width = 32;
  img.height = square ? 32 : 16;
  img.rgb.resize(size_t(img.width) * img.height * 3);
  for (uint32_t r = 0; r < img.height; ++r)
    for (uint32_t c = 0; c < img.width; ++c) {
      float v = 0.3f + 0.2f * std::sin(0.4f * c) * std::cos(0.7f * r);
      bool dark = r == 4 || (r >= 9 && r <= 11 && c >= 3 && c <= 8) || (r * 7 + c * 3) % 23 == 0;
      float* t = &img.rgb[3 * (size_t(r) * img.width + c)];
      t[0] = dark ? 0 : v;
      t[1] = dark ? 0 : 0.5f * v;
      t[2] = dark ? 0 : 1.5f * v;
      if (r == 6 && c == 21) t[0] = 40, t[1] = 30, t[2] = 20;
      if (square && r == 0 && c == 5) t[0] = 8, t[1] = 6, t[2] = 4;
      if (square && r == 20 && c == 0) t[0] = 6, t[1] = 6, t[2] = 6;
      if (square && r == 31 && c == 31) t[0] = 5, t[1] = 3, t[2] = 1;
    }
  return img;
}

// pbrt-v4's equal-area square <-> sphere (Clarberg's mapping) in double, as kernels/environment.cl states
// it: +z at the square's centre, the circle z = 0 on the diamond through the middles of its edges, -z at its
// corners; x has the sign of u - 1/2, y that of v - 1/2.
glm::dvec3 equal_area_square_to_sphere(glm::dvec2 p) {
  double u = 2 * p.x - 1, v = 2 * p.y - 1, up = std::abs(u), vp = std::abs(v);
  double signed_distance = 1 - (up + vp), r = 1 - std::abs(signed_distance);
  double phi = (r == 0 ? 1 : (vp - up) / r + 1) * M_PI / 4;
  double k = r * std::sqrt(std::max(0.0, 2 - r * r));
  return {std::copysign(std::cos(phi), u) * k, std::copysign(std::sin(phi), v) * k,
          std::copysign(1 - r * r, signed_distance)};
}

glm::dvec2 equal_area_sphere_to_square(glm::dvec3 d) {
  d = glm::normalize(d);
  double x = std::abs(d.x), y = std::abs(d.y), z = std::abs(d.z);
  double r = std::min(1.0, std::sqrt((x * x + y * y) / (1 + z)));  // sqrt(1 - |z|)
  double phi = std::atan2(std::min(x, y), std::max(x, y)) * 2 / M_PI;
  if (x < y) phi = 1 - phi;
  double v = phi * r, u = r - v;
  if (d.z < 0) {
    std::swap(u, v);
    u = 1 - u;
    v = 1 - v;
  }
  return {0.5 * (std::copysign(u, d.x) + 1), 0.5 * (std::copysign(v, d.y) + 1)};
}

// Image coordinates in texels (x from the left, y from the top) of a direction under environment.cl's
// documented conventions. Lat-long: +y up, v = theta / pi from +y (row 0 at the top), u = phi / (2 pi)
// with phi = atan2(z, x). Equal-area: (u, v) = equal_area_sphere_to_square, column u w, row v h.
glm::dvec2 env_texel_coordinates(const Image& img, const glm::dvec3& d, EnvMapping m = EnvMapping::lat_long) {
  if (is_equal_area(m)) {
    glm::dvec2 uv = equal_area_sphere_to_square(d);
    return {uv.x * img.width, uv.y * img.height};
  }
  double u = std::atan2(d.z, d.x) / (2 * M_PI);
  if (u < 0) u += 1;
  double v = std::atan2(std::hypot(d.x, d.z), d.y) / M_PI;
  return {u * img.width, v * img.height};
}

// The texel a direction falls in.
void env_texel(const Image& img, const glm::dvec3& d, uint32_t* row, uint32_t* col, EnvMapping m = EnvMapping::lat_long) {
  glm::dvec2 p = env_texel_coordinates(img, d, m);
  *col = std::min(uint32_t(p.x), img.width - 1);
  *row = std::min(uint32_t(p.y), img.height - 1);
}

// Within eps texels of a texel edge, where a float direction may round into either texel.
bool near_texel_edge(const Image& img, const glm::dvec3& d, EnvMapping m = EnvMapping::lat_long, double eps = 1e-4) {
  glm::dvec2 p = env_texel_coordinates(img, d, m);
  return std::abs(p.x - std::round(p.x)) < eps || std::abs(p.y - std::round(p.y)) < eps;
}

// Texel (r, c) under the environment's wrapping, at most one texel beyond an edge. Lat-long: columns
// repeat, rows clamp at the poles. Equal-area: the square's edges fold at their middles, so the texel
// beyond an edge is the one mirrored across the edge's middle (column -1 of row r is column 0 of row
// h - 1 - r; beyond a corner, the opposite corner).
const float* env_texel_at(const Image& img, int64_t r, int64_t c, EnvMapping m = EnvMapping::lat_long) {
  const int64_t w = img.width, h = img.height;
  if (is_equal_area(m)) {
    if (c < 0 || c >= w) c = c < 0 ? -1 - c : 2 * w - 1 - c, r = h - 1 - r;
    if (r < 0 || r >= h) r = r < 0 ? -1 - r : 2 * h - 1 - r, c = w - 1 - c;
  } else {
    r = std::clamp<int64_t>(r, 0, h - 1);
    c = ((c % w) + w) % w;
  }
  return &img.rgb[3 * (size_t(r) * img.width + size_t(c))];
}

// The map's value at texel coordinates p (x from the left, y from the top, texel centres at
// half-integers), in double: bilinear (environment.cl's lookup as documented), or the texel p lies in.
glm::dvec3 env_lookup_at(const Image& img, glm::dvec2 p, EnvMapping m = EnvMapping::lat_long) {
  if (m == EnvMapping::equal_area_nearest) {
    const float* t = env_texel_at(img, std::min<int64_t>(int64_t(p.y), img.height - 1),
                                  std::min<int64_t>(int64_t(p.x), img.width - 1), m);
    return {t[0], t[1], t[2]};
  }
  double x = p.x - 0.5, y = p.y - 0.5, fx = std::floor(x), fy = std::floor(y), ax = x - fx, ay = y - fy;
  int64_t c = int64_t(fx), r = int64_t(fy);
  glm::dvec3 v(0);
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const float* t = env_texel_at(img, r + dy, c + dx, m);
      v += (dx ? ax : 1 - ax) * (dy ? ay : 1 - ay) * glm::dvec3(t[0], t[1], t[2]);
    }
  return v;
}

// How far a device lookup at texel coordinates p may be from env_lookup_at: the float texel
// coordinates, the kernel's and those of the float direction the host reads back, are each good to
// about 2^-24 x the image's size in texels, and the lookup changes by at most the largest texel around
// p per texel moved. `moved`: further texels the direction may have moved (a rotated map's float rotation).
double env_lookup_tolerance(const Image& img, glm::dvec2 p, double moved = 0, EnvMapping m = EnvMapping::lat_long) {
  double largest = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const float* t = env_texel_at(img, int64_t(std::floor(p.y)) + dy, int64_t(std::floor(p.x)) + dx, m);
      largest = std::max({largest, double(t[0]), double(t[1]), double(t[2])});
    }
  return (8 * std::ldexp(1.0, -24) * std::max(img.width, img.height) + moved) * largest;
}

double luminance_of(const glm::dvec3& v) { return 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z; }

// The sampling weight each texel's cell should have: the largest luminance of the lookup in the cell,
// found on a 9 x 9 grid over the cell (which holds the corners of the four bilinear patches in it, where
// their largest values lie), times sin(theta at the row's centre) on a lat-long map; a nearest-texel
// map's texel.
std::vector<double> env_cell_weights(const Image& img, EnvMapping m = EnvMapping::lat_long) {
  std::vector<double> weights(size_t(img.width) * img.height);
  for (uint32_t r = 0; r < img.height; ++r)
    for (uint32_t c = 0; c < img.width; ++c) {
      double largest = 0;
      for (int i = 0; i <= 8; ++i)
        for (int j = 0; j <= 8; ++j) {
          // A nearest lookup is constant over the cell: its inside only (its edges belong to neighbours).
          glm::dvec2 p = m == EnvMapping::equal_area_nearest ? glm::dvec2(c + 0.5, r + 0.5) : glm::dvec2(c + i / 8.0, r + j / 8.0);
          largest = std::max(largest, luminance_of(env_lookup_at(img, p, m)));
        }
      weights[size_t(r) * img.width + c] = largest * (is_equal_area(m) ? 1.0 : std::sin(M_PI * (r + 0.5) / img.height));
    }
  return weights;
}

// The solid angle per unit area of the (u, v) square at direction d of the map's frame: 2 pi^2 sin(theta)
// on a lat-long map, 4 pi everywhere on an equal-area one.
double env_jacobian(const glm::dvec3& d, EnvMapping m) {
  return is_equal_area(m) ? 4 * M_PI : 2 * M_PI * M_PI * std::hypot(d.x, d.z) / glm::length(d);
}

// `extra`: more keys of the environment, e.g. R"(, "transform": {...})", or empty.
DeviceScene env_scene(const Image& img, double scale, const std::string& extra = "") {
  write_exr(temp_dir() + "/env.exr", img);
  return load_world_scene(write_temp_file(
      "env.json", scene_json("", R"({"type": "environment", "file": "env.exr", "scale": )" + std::to_string(scale) +
                                     extra + "}")));
}

// The map sampled and looked up in its own frame, which `rotation` takes to the world's: the map placed as
// it is, and rotated by the environment's transform.
void check_environment_map(const glm::dmat3& rotation, const std::string& transform, EnvMapping m = EnvMapping::lat_long) {
  const Image img = synthetic_env_map(is_equal_area(m));
  const double scale = 2;
  DeviceScene scene = env_scene(img, scale, transform + mapping_json(m));
  ASSERT_EQ(scene.lights.size(), 1u);
  ASSERT_EQ(scene.header.env_light, 0u);
  ASSERT_EQ(scene.lights[0].slot, m == EnvMapping::lat_long     ? PC_ENV_LAT_LONG
                                  : m == EnvMapping::equal_area ? PC_ENV_EQUAL_AREA
                                                                : PC_ENV_EQUAL_AREA_NEAREST);
  const glm::dmat3 to_map = glm::transpose(rotation);
  // A lat-long map: binned in the map's own frame (polar axis +y, phi from +x towards +z), 5 x 5 bins per
  // texel, so the piecewise-constant density has no edge inside a bin and its 1 / sin(theta) peak at the
  // poles is cancelled by the bins' own Jacobian. (About any other axis the quadrature of that integrable
  // singularity converges too slowly for a million samples.) The expected counts integrate the device's
  // density over the bins.
  SphereBinning aligned;
  aligned.x = rotation * glm::dvec3(1, 0, 0);
  aligned.y = rotation * glm::dvec3(0, 0, 1);
  aligned.z = rotation * glm::dvec3(0, 1, 0);
  // An equal-area map: binned in the square, 2 x 2 bins per texel, each expected to hold a quarter of its
  // cell's probability: the mapping preserves area, so the density of a direction is its cell's weight
  // over the weights' total, times w h / (4 pi), and a square bin's probability is its share of the cell.
  const uint32_t square_bins = 4 * img.width * img.height;
  auto square_bin_of = [&](const glm::dvec3& world) {
    glm::dvec2 p = env_texel_coordinates(img, to_map * world, m);
    uint32_t x = std::min(uint32_t(2 * p.x), 2 * img.width - 1), y = std::min(uint32_t(2 * p.y), 2 * img.height - 1);
    return y * 2 * img.width + x;
  };
  std::vector<LightCase> cases = {{is_equal_area(m) ? "equal-area map, 2 x 2 bins per texel" : "environment map, texel-aligned bins",
                                   scene, {0, 0, 0}, aligned, 0}};
  Chi2Family family(cases.size());

  // The density the map should have, from the cells' weights (env_cell_weights), normalised over the
  // (u, v) square, over the Jacobian.
  const std::vector<double> weights = env_cell_weights(img, m);
  double total = 0;
  for (double w : weights) total += w;
  auto expected_pdf = [&](const glm::dvec3& world) {
    const glm::dvec3 d = to_map * world;
    uint32_t r, c;
    env_texel(img, d, &r, &c, m);
    double p_uv = weights[r * img.width + c] / total * img.width * img.height;
    return p_uv / env_jacobian(d, m);
  };

  for (size_t k = 0; k < cases.size(); ++k) {
    const LightCase& c = cases[k];
    SCOPED_TRACE(c.name);
    SceneBuffers sb = test_scene_buffers(c.scene);
    LightSamples s = sample_lights(sb, c.x, 6000 + uint32_t(k), kChi2Samples);
    const uint32_t bin_count = is_equal_area(m) ? square_bins : c.binning.count();
    auto bin_of = [&](const glm::dvec3& world) { return is_equal_area(m) ? square_bin_of(world) : c.binning.bin_of(world); };
    std::vector<double> observed(bin_count + 1, 0);
    size_t dark_hits = 0, mismatches = 0, failed = 0;
    std::string first;
    for (size_t i = 0; i < s.n; ++i) {
      const glm::dvec3 world = s.wi(i), wi = to_map * world;  // wi: in the map's frame
      if (s.status(i) == 0) {
        // Drawn where the bilinear radiance is 0 (a cell's weight is its largest radiance; part of a cell
        // next to a dark one can be black), which is no failure of the sampling: binned with the others.
        glm::dvec2 p = env_texel_coordinates(img, wi, m);
        bool black = glm::length(wi) > 0 && glm::length(env_lookup_at(img, p, m)) <= env_lookup_tolerance(img, p, 0, m);
        if (!black) ++failed;
        observed[black ? bin_of(world) : bin_count] += 1;
        continue;
      }
      observed[bin_of(world)] += 1;
      uint32_t r, col;
      env_texel(img, wi, &r, &col, m);
      const glm::dvec2 p = env_texel_coordinates(img, wi, m);
      // At a cell edge the sample's cell is ambiguous (the test below checks those samples).
      if (near_texel_edge(img, wi, m)) continue;
      // A rotated lat-long map: within 1e-3 of a pole (one sample in 10^5 or so), the float rotation's
      // error of about 1e-7 in x and z is a fraction of sin(theta) that the density's 1e-3 would not cover.
      if (!is_equal_area(m) && rotation != glm::dmat3(1.0) && std::hypot(wi.x, wi.z) < 1e-3) continue;
      dark_hits += weights[r * img.width + col] == 0;
      // Radiance = scale x the lookup under the documented convention, within the rounding of the float
      // direction; the pdf as sampled = env_pdf = the density computed here from the cells.
      glm::dvec3 want = scale * env_lookup_at(img, p, m);
      // A rotated map: the kernel's float rotation moves the direction by up to about 8 float ulps (2^-21),
      // which moves a lat-long map's u by that over 2 pi sin(theta) and v by that over pi, and an
      // equal-area map's (u, v) by less than that (its stretch is below 1 per radian) times its size.
      double moved = 0;
      if (rotation != glm::dmat3(1.0))
        moved = is_equal_area(m) ? std::ldexp(1.0, -21) * std::max(img.width, img.height)
                                 : std::ldexp(1.0, -21) * (img.width / (2 * M_PI * std::max(std::hypot(wi.x, wi.z), 1e-6)) +
                                                           img.height / M_PI);
      double tol = scale * env_lookup_tolerance(img, p, moved, m);
      bool ok = s.status(i) == 1 && std::isinf(s.distance(i)) && std::isinf(s.hit_t(i)) &&
                std::abs(s.le(i).x - want.x) <= tol && std::abs(s.le(i).y - want.y) <= tol &&
                std::abs(s.le(i).z - want.z) <= tol && close_rel(s.pdf(i), s.pdf_eval(i), 1e-3) &&
                close_rel(s.pdf(i), expected_pdf(world), 1e-3);
      if (!ok && !mismatches++) {
        char buf[300];
        std::snprintf(buf, sizeof buf,
                      "sample %zu: wi (%g %g %g) cell row %u col %u: Le (%g %g %g), lookup x scale (%g %g %g), pdf %.7g, "
                      "env_pdf %.7g, from the cells %.7g",
                      i, wi.x, wi.y, wi.z, r, col, s.le(i).x, s.le(i).y, s.le(i).z, want.x, want.y, want.z, s.pdf(i),
                      s.pdf_eval(i), expected_pdf(world));
        first = buf;
      }
    }
    double pdf_total = 0;
    Chi2Result chi2;
    int highest_order = 0;
    if (is_equal_area(m)) {
      std::vector<double> expected(bin_count + 1, 0.0);
      for (uint32_t b = 0; b < bin_count; ++b) {
        uint32_t x = b % (2 * img.width), y = b / (2 * img.width);
        double p = weights[(y / 2) * img.width + x / 2] / total / 4;
        expected[b] = p * double(kChi2Samples);
        pdf_total += p;
      }
      chi2 = chi2_test(observed, expected);
      // The device's density over the sphere, integrated on 20 x 40 bins about the world's z (a rotated map's
      // cells cut them obliquely): a whole, so the 4 pi of env_pdf is the mapping's area.
      if (rotation != glm::dmat3(1.0)) {
        SphereBinning coarse;
        coarse.theta_bins = 20;
        coarse.phi_bins = 40;
        BinIntegrals integrals = integrate_bins(light_pdf_integrator(sb, c.x, coarse), coarse.count(), double(kChi2Samples), 0.1, 256);
        double integral = 0;
        for (double v : integrals.value) integral += v;
        std::printf("  the device's density integrates to %.6f over the sphere\n", integral);
        EXPECT_NEAR(integral, 1, 1e-3) << "the device's density over the sphere (quadrature to " << integrals.worst << ")";
      }
    } else {
      BinIntegrals integrals =
          integrate_bins(light_pdf_integrator(sb, c.x, c.binning), c.binning.count(), double(kChi2Samples), 0.1, 256);
      chi2 = chi2_test(observed, expected_counts(integrals, double(kChi2Samples), &pdf_total));
      highest_order = integrals.highest_order;
      EXPECT_LT(integrals.worst, 0.5) << "quadrature: " << integrals.unconverged << " bins unconverged";
    }
    std::string detail = run_detail(pdf_total, 1.0 - failed / double(kChi2Samples), highest_order);
    if (is_equal_area(m)) detail = detail.substr(0, detail.find(", quadrature")) + ", expected counts from the cells' weights";
    family.expect_fit(c.name, chi2, detail);
    EXPECT_EQ(failed, 0u) << "failed samples where the radiance is not 0";
    EXPECT_EQ(dark_hits, 0u) << "samples in cells where nothing is emitted";
    EXPECT_EQ(mismatches, 0u) << first;
    EXPECT_NEAR(pdf_total, 1, 5e-4);
  }
}

// A sample's radiance must be the lookup at its direction and its density that of the cell its direction
// lies in, or, within 1e-4 texels of an edge, of one of the cells meeting there; the density bounds the
// radiance, so radiance / density (luminance) never exceeds the weights' integral (no fireflies) times
// `ratio_bound`. A bilinear equal-area sample may be drawn where the radiance is 0 (part of a cell next to
// black texels).
void check_samples_against_cells(const Image& img, EnvMapping m, double ratio_bound) {
  const double scale = 1;
  SceneBuffers sb = test_scene_buffers(env_scene(img, scale, mapping_json(m)));
  // Each cell's probability: its row's, times its own within the row.
  const std::vector<double> weights = env_cell_weights(img, m);
  std::vector<double> row_sum(img.height, 0);
  double total = 0;
  for (uint32_t r = 0; r < img.height; ++r) {
    for (uint32_t c = 0; c < img.width; ++c) row_sum[r] += weights[r * img.width + c];
    total += row_sum[r];
  }
  LightSamples s = sample_lights(sb, {0, 0, 0}, 21, kChi2Samples);
  size_t inconsistent = 0, near_edges = 0;
  double worst_ratio = 0;
  std::string first;
  for (size_t i = 0; i < s.n; ++i) {
    glm::dvec3 d = s.wi(i);
    glm::dvec2 p = env_texel_coordinates(img, d, m);
    if (s.status(i) == 0 && is_equal_area(m)) {
      // Drawn where the bilinear radiance is 0 (part of a cell next to black texels can be black).
      ASSERT_LE(glm::length(env_lookup_at(img, p, m)), env_lookup_tolerance(img, p, 0, m)) << "sample " << i;
      continue;
    }
    ASSERT_EQ(s.status(i), 1);
    std::vector<std::pair<uint32_t, uint32_t>> candidates;
    for (double du : {-1e-4, 1e-4})
      for (double dv : {-1e-4, 1e-4}) {
        uint32_t c = is_equal_area(m) ? uint32_t(std::clamp(std::floor(p.x + du), 0.0, img.width - 1.0))
                                      : uint32_t(std::floor(p.x + du) + img.width) % img.width;
        uint32_t r = uint32_t(std::clamp(std::floor(p.y + dv), 0.0, img.height - 1.0));
        if (std::find(candidates.begin(), candidates.end(), std::pair{r, c}) == candidates.end()) candidates.push_back({r, c});
      }
    near_edges += candidates.size() > 1;
    glm::dvec3 want = scale * env_lookup_at(img, p, m);
    double tol = scale * env_lookup_tolerance(img, p, 0, m);
    bool ok = false;
    double cell_pdf = 0;  // the density of the cell that matched, from the weights
    for (auto [r, c] : candidates) {
      double p_row = row_sum[r] / total, p_col = weights[r * img.width + c] / row_sum[r];
      double pdf = p_row * p_col * img.width * img.height / env_jacobian(d, m);
      // The device takes each probability as the difference of two float cdf entries, each within
      // 3e-8 of its exact value.
      double pdf_tol = 1e-4 + 6e-8 / p_row + 6e-8 / p_col;
      // A nearest lookup at an edge may take either texel.
      glm::dvec3 texel = m == EnvMapping::equal_area_nearest ? scale * env_lookup_at(img, {c + 0.5, r + 0.5}, m) : want;
      if (!ok && std::abs(s.le(i).x - texel.x) <= tol && std::abs(s.le(i).z - texel.z) <= tol &&
          close_rel(s.pdf(i), pdf, pdf_tol)) {
        ok = true;
        cell_pdf = pdf;
      }
    }
    // Lat-long: L / p = luminance x 2 pi^2 sin(theta) / p_uv <= 2 pi^2 total / (w h) x sin(theta) /
    // sin(theta at the row's centre), and that last ratio is at most about 2 (next to the poles).
    // Equal-area: L / p = luminance x 4 pi / p_uv <= 4 pi total / (w h), the Jacobian being constant: p
    // the cell's density from its weight (the device's, from float cdfs, is checked against it above;
    // a cell with a millionth of its row's weight takes its share as a difference of two floats near the
    // row's middle, good to a few per cent only).
    double lum = luminance_of(s.le(i));
    double bound = (is_equal_area(m) ? 4 * M_PI : 2 * M_PI * M_PI) * total / (img.width * img.height);
    worst_ratio = std::max(worst_ratio, lum / (is_equal_area(m) && ok ? cell_pdf : s.pdf(i)) / bound);
    if (!ok && !inconsistent++) {
      char buf[300];
      std::snprintf(buf, sizeof buf, "sample %zu: wi (%.9g %.9g %.9g) at texel coordinates (%.9f, %.9f): Le %g (lookup %g), pdf %g", i,
                    d.x, d.y, d.z, p.x, p.y, s.le(i).x, want.x, s.pdf(i));
      first = buf;
    }
  }
  std::printf("  %zu of %zu samples within 1e-4 texels of an edge; largest L / p over its bound %.6f\n", near_edges, s.n,
              worst_ratio);
  EXPECT_EQ(inconsistent, 0u) << first;
  EXPECT_LE(worst_ratio, ratio_bound);
}

// A width x height map of texels spread over six decades, a tenth of them black.
Image random_env_map(uint32_t width, uint32_t height) {
  Image img;
  img.width = width;
  img.height = height;
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> decade(-3, 3), unit(0, 1);
  for (size_t i = 0; i < size_t(img.width) * img.height; ++i) {
    float v = unit(rng) < 0.1f ? 0 : std::pow(10.0f, decade(rng));
    img.rgb.insert(img.rgb.end(), {v, 0.8f * v, 1.2f * v});
  }
  return img;
}

// The equal-area mapping as environment.cl computes it, for the round trips below: a program of its own.
const char* const kEqualAreaKernels = R"(
#include "shared/types.h"
#include "math.cl"
#include "sampling.cl"
#include "environment.cl"
__kernel void equal_area_to_sphere(__global const float2* in, __global float4* out) {
  uint i = get_global_id(0);
  out[i] = (float4)(env_square_to_sphere(in[i]), 0.0f);
}
__kernel void equal_area_to_square(__global const float4* in, __global float2* out) {
  uint i = get_global_id(0);
  out[i] = env_sphere_to_square(in[i].xyz);
}
)";

const KernelProgram& equal_area_program() {
  static KernelProgram program = [] {
    register_kernel_source("tests_equal_area.cl", kEqualAreaKernels);
    return build_kernel_program(test_device(), "tests_equal_area.cl", kernel_options(kFeatureAll));
  }();
  return program;
}

std::vector<glm::dvec3> device_square_to_sphere(const std::vector<glm::dvec2>& points) {
  ClContext& cl = test_device();
  std::vector<float> in;
  for (const glm::dvec2& p : points) in.insert(in.end(), {float(p.x), float(p.y)});
  ClBuffer in_buffer = upload(cl, in), out(cl, CL_MEM_WRITE_ONLY, points.size() * 4 * sizeof(float));
  ClKernel k(equal_area_program().kernel("equal_area_to_sphere"));
  k.arg(0, in_buffer.mem);
  k.arg(1, out.mem);
  run_kernel(cl, k.k, points.size());
  std::vector<float> v = read_buffer<float>(cl, out, points.size() * 4);
  std::vector<glm::dvec3> d;
  for (size_t i = 0; i < points.size(); ++i) d.push_back({v[4 * i], v[4 * i + 1], v[4 * i + 2]});
  return d;
}

std::vector<glm::dvec2> device_sphere_to_square(const std::vector<glm::vec3>& directions) {
  ClContext& cl = test_device();
  std::vector<float> in;
  for (const glm::vec3& d : directions) in.insert(in.end(), {d.x, d.y, d.z, 0.0f});
  ClBuffer in_buffer = upload(cl, in), out(cl, CL_MEM_WRITE_ONLY, directions.size() * 2 * sizeof(float));
  ClKernel k(equal_area_program().kernel("equal_area_to_square"));
  k.arg(0, in_buffer.mem);
  k.arg(1, out.mem);
  run_kernel(cl, k.k, directions.size());
  std::vector<float> v = read_buffer<float>(cl, out, directions.size() * 2);
  std::vector<glm::dvec2> uv;
  for (size_t i = 0; i < directions.size(); ++i) uv.push_back({v[2 * i], v[2 * i + 1]});
  return uv;
}

}  // namespace

TEST(LightChi2, EnvironmentMap) { check_environment_map(glm::dmat3(1.0), ""); }

// The map placed by a rotation (as Mitsuba's envmap to_world imports): sampled, looked up and its density
// evaluated in its own frame.
TEST(LightChi2, RotatedEnvironmentMap) {
  const glm::dvec3 axis = glm::normalize(glm::dvec3(1, 2, 3));
  const glm::dmat3 rotation(glm::rotate(glm::dmat4(1.0), glm::radians(70.0), axis));
  check_environment_map(rotation, R"(, "transform": {"rotate": {"axis": [1, 2, 3], "degrees": 70}})");
}

// pbrt-v4's equal-area octahedral maps, bilinear and at the nearest texel, as placed and rotated.
TEST(LightChi2, EqualAreaEnvironmentMap) { check_environment_map(glm::dmat3(1.0), "", EnvMapping::equal_area); }

TEST(LightChi2, RotatedEqualAreaEnvironmentMap) {
  const glm::dmat3 rotation(glm::rotate(glm::dmat4(1.0), glm::radians(70.0), glm::normalize(glm::dvec3(1, 2, 3))));
  check_environment_map(rotation, R"(, "transform": {"rotate": {"axis": [1, 2, 3], "degrees": 70}})", EnvMapping::equal_area);
}

TEST(LightChi2, NearestEqualAreaEnvironmentMap) {
  // pbrt's usual placement: Rotate -90 1 0 0 takes the map's +z (the square's centre) to the world's +y.
  const glm::dmat3 rotation(glm::rotate(glm::dmat4(1.0), glm::radians(-90.0), glm::dvec3(1, 0, 0)));
  ASSERT_LT(glm::length(rotation * glm::dvec3(0, 0, 1) - glm::dvec3(0, 1, 0)), 1e-15);
  check_environment_map(rotation, R"(, "transform": {"rotate": {"axis": [1, 0, 0], "degrees": -90}})",
                        EnvMapping::equal_area_nearest);
}

TEST(LightSampling, EnvironmentTransformMayOnlyRotate) {
  const Image img = synthetic_env_map();
  for (const char* transform : {R"(, "transform": {"scale": 2})", R"(, "transform": {"translate": [0, 1, 0]})",
                                R"(, "transform": {"scale": [1, 1, -1]})"}) {
    SCOPED_TRACE(transform);
    try {
      env_scene(img, 1, transform);
      ADD_FAILURE() << "loaded";
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find("lights[0].transform: an environment's transform may only rotate"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(LightSampling, EqualAreaMapsAreSquareAndTheKeysChecked) {
  const Image wide = synthetic_env_map();  // 32 x 16
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"(, "mapping": "equal_area")", "lights[0].file: " + temp_dir() + "/env.exr is 32 x 16 texels: an equal_area map is a square image"},
      {R"(, "mapping": "octahedral")", "lights[0].mapping: unknown mapping \"octahedral\" (expected lat_long or equal_area)"},
      {R"(, "mapping": "equal_area", "filter": "box")", "lights[0].filter: unknown filter \"box\""},
      {R"(, "filter": "nearest")", "lights[0].filter: a lat_long map is looked up bilinearly"},
  };
  for (const auto& [keys, message] : cases) {
    SCOPED_TRACE(keys);
    try {
      env_scene(wide, 1, keys);
      ADD_FAILURE() << "loaded";
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
  const std::string constant = write_temp_file(
      "constant.json", scene_json("", R"({"type": "environment", "radiance": [1, 1, 1], "mapping": "equal_area"})"));
  EXPECT_NE(scene_load_error(constant).find("lights[0].mapping: mapping goes with file"), std::string::npos)
      << scene_load_error(constant);
}

TEST(LightSampling, EnvironmentSampleRadianceIsBilinearAndItsDensityItsCells) {
  // A 256 x 128 map: L / p at most about 2 times the bound (sin theta within a cell next to the poles).
  check_samples_against_cells(random_env_map(256, 128), EnvMapping::lat_long, 2.01);
}

TEST(LightSampling, EqualAreaSampleRadianceIsTheLookupAndItsDensityItsCells) {
  // A 128 x 128 equal-area map: the density's Jacobian is constant, so L / p never exceeds the bound (up to
  // the floats' rounding); at the nearest texel the sampling is exactly in proportion to the radiance.
  {
    SCOPED_TRACE("bilinear");
    check_samples_against_cells(random_env_map(128, 128), EnvMapping::equal_area, 1.0001);
  }
  SCOPED_TRACE("nearest");
  check_samples_against_cells(random_env_map(128, 128), EnvMapping::equal_area_nearest, 1.0001);
}

// The device's equal-area mapping (kernels/environment.cl) against the mapping in double: directions of
// points all over the square (its centre, edges, corners and diagonals included) and back, and the square
// points of random directions, of unnormalised ones and of directions close to the poles and axes.
TEST(EqualAreaMapping, DeviceMatchesDoublePrecisionBothWays) {
  // Known points: the centre is +z, the corners -z, the middles of the edges +-x and +-y on the equator.
  const std::vector<std::pair<glm::dvec2, glm::dvec3>> known = {
      {{0.5, 0.5}, {0, 0, 1}}, {{0, 0}, {0, 0, -1}}, {{1, 1}, {0, 0, -1}}, {{1, 0.5}, {1, 0, 0}},
      {{0, 0.5}, {-1, 0, 0}}, {{0.5, 1}, {0, 1, 0}}, {{0.5, 0}, {0, -1, 0}}, {{0.75, 0.75}, {std::sqrt(0.5), std::sqrt(0.5), 0}}};
  for (const auto& [p, d] : known) EXPECT_LT(glm::length(equal_area_square_to_sphere(p) - d), 1e-15) << p.x << " " << p.y;
  // The mapping in double preserves area: a uniform grid of square points gives z uniform in [-1, 1].
  double sum_z = 0, sum_z2 = 0;
  const int grid = 400;
  for (int i = 0; i < grid; ++i)
    for (int j = 0; j < grid; ++j) {
      double z = equal_area_square_to_sphere({(i + 0.5) / grid, (j + 0.5) / grid}).z;
      sum_z += z;
      sum_z2 += z * z;
    }
  EXPECT_NEAR(sum_z / (grid * grid), 0, 1e-4);
  EXPECT_NEAR(sum_z2 / (grid * grid), 1.0 / 3, 1e-4);

  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<glm::dvec2> points;
  for (int i = 0; i <= 64; ++i)
    for (int j = 0; j <= 64; ++j) points.push_back({i / 64.0, j / 64.0});
  for (int i = 0; i < 20000; ++i) points.push_back({unit(rng), unit(rng)});
  for (double e : {1e-7, 1e-5, 1e-3}) {  // next to the centre, the corners and the diagonals
    points.push_back({0.5 + e, 0.5 - 2 * e});
    points.push_back({e, 3 * e});
    points.push_back({1 - e, 1 - 2 * e});
    points.push_back({0.75 + e, 0.75 - e});
    points.push_back({0.25 - e, 0.75 + e});
  }
  for (glm::dvec2& p : points) p = glm::dvec2(glm::vec2(p));  // as the device takes them
  const std::vector<glm::dvec3> dirs = device_square_to_sphere(points);
  double worst_direction = 0, worst_length = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    worst_direction = std::max(worst_direction, glm::length(dirs[i] - equal_area_square_to_sphere(points[i])));
    worst_length = std::max(worst_length, std::abs(glm::length(dirs[i]) - 1));
  }
  // And back: the device's float directions to the square; the point's direction again (edges fold, so a
  // point on one may come back as its mirror image, the same direction).
  std::vector<glm::vec3> fdirs(dirs.begin(), dirs.end());
  const std::vector<glm::dvec2> back = device_sphere_to_square(fdirs);
  double worst_round_trip = 0;
  for (size_t i = 0; i < points.size(); ++i)
    worst_round_trip = std::max(worst_round_trip, glm::length(equal_area_square_to_sphere(back[i]) - equal_area_square_to_sphere(points[i])));

  // Directions: random ones, unnormalised (x 3.7 and x 1e-3), and near the poles and the axes, where a
  // float z keeps few digits of 1 - |z|.
  std::vector<glm::vec3> directions;
  std::normal_distribution<double> normal;
  for (int i = 0; i < 20000; ++i) {
    glm::dvec3 d = glm::normalize(glm::dvec3(normal(rng), normal(rng), normal(rng)));
    directions.push_back(glm::vec3(d * (i % 3 == 0 ? 3.7 : i % 3 == 1 ? 1e-3 : 1.0)));
  }
  for (double e : {1e-6, 3e-5, 1e-4, 1e-3}) {
    for (double sz : {1.0, -1.0}) {
      directions.push_back(glm::vec3(glm::normalize(glm::dvec3(e, -0.7 * e, sz))));
      directions.push_back(glm::vec3(glm::normalize(glm::dvec3(-0.3 * e, e, sz))));
    }
    directions.push_back(glm::vec3(glm::normalize(glm::dvec3(1, e, -e))));
    directions.push_back(glm::vec3(glm::normalize(glm::dvec3(-e, 1, 2 * e))));
  }
  const std::vector<glm::dvec2> uv = device_sphere_to_square(directions);
  double worst_square = 0;
  for (size_t i = 0; i < directions.size(); ++i)
    worst_square = std::max(worst_square, glm::length(uv[i] - equal_area_sphere_to_square(glm::dvec3(directions[i]))));
  std::printf("  square to sphere within %.3g (length within %.3g), sphere to square within %.3g, round trips within %.3g\n",
              worst_direction, worst_length, worst_square, worst_round_trip);
  // A few float ulps: of a unit vector (2^-24 = 6e-8) and of a point of the square.
  EXPECT_LT(worst_direction, 5e-7);
  EXPECT_LT(worst_length, 5e-7);
  EXPECT_LT(worst_square, 5e-7);
  EXPECT_LT(worst_round_trip, 1e-6);
}

// ---- Delta lights, exactly ----

TEST(LightSampling, SpotLightFallsOffSmoothlyBetweenItsCones) {
  const glm::dvec3 pos(0.5, 2, -1), axis = glm::normalize(glm::dvec3(0.2, -1, 0.3));
  const double intensity = 7, inner = 25, outer = 40;
  char lights[400];
  std::snprintf(lights, sizeof lights,
                R"({"type": "spot", "position": [%.9g, %.9g, %.9g], "direction": [%.9g, %.9g, %.9g],
                    "intensity": [%g, %g, %g], "inner_angle_degrees": %g, "outer_angle_degrees": %g})",
                pos.x, pos.y, pos.z, axis.x, axis.y, axis.z, intensity, 2 * intensity, intensity, inner, outer);
  SceneBuffers sb = test_scene_buffers(load_world_scene(write_temp_file("spot.json", scene_json(
      R"({"type": "sphere", "center": [0, 100, 0], "radius": 0.1, "material": "lamp"})", lights))));
  SphereBinning frame = SphereBinning::about(axis, M_PI);
  for (double angle : {0.0, 10.0, 24.9, 25.1, 28.0, 32.5, 37.0, 39.9, 40.1, 60.0, 150.0})
    for (double dist : {0.7, 3.0}) {
      SCOPED_TRACE("angle " + std::to_string(angle) + " distance " + std::to_string(dist));
      double a = angle * kDeg;
      glm::dvec3 x = pos + dist * (std::cos(a) * axis + std::sin(a) * glm::normalize(frame.x + 0.5 * frame.y));
      LightSamples s = sample_lights(sb, x, 9, 4);
      glm::vec3 xf(x);  // the kernel sees x in single precision
      glm::dvec3 d = glm::dvec3(xf) - pos;
      double cos_t = glm::dot(axis, glm::normalize(d)), cos_i = std::cos(inner * kDeg), cos_o = std::cos(outer * kDeg);
      double falloff = 1;
      if (cos_t <= cos_o) falloff = 0;
      else if (cos_t < cos_i) {
        double t = (cos_t - cos_o) / (cos_i - cos_o);
        falloff = t * t * (3 - 2 * t);  // smoothstep
      }
      double want = intensity * falloff / glm::dot(d, d);
      for (size_t i = 0; i < s.n; ++i) {
        if (falloff == 0) {  // no light reaches x: no sample
          EXPECT_EQ(s.status(i), 0);
          continue;
        }
        ASSERT_EQ(s.status(i), 2);
        // The falloff's slope in cos is at most 1.5 / (cos_inner - cos_outer) = 11: float cosines leave it
        // 2e-6 (of the unattenuated value) uncertain.
        double unattenuated = intensity / glm::dot(d, d);
        EXPECT_NEAR(s.le(i).x, want, 1e-5 * want + 2e-6 * unattenuated);
        EXPECT_NEAR(s.le(i).y, 2 * want, 2 * (1e-5 * want + 2e-6 * unattenuated));
        EXPECT_NEAR(s.pdf(i), 1, 1e-6);  // the only light
        EXPECT_NEAR(glm::length(s.wi(i) + glm::normalize(d)), 0, 1e-6);
        EXPECT_NEAR(s.distance(i), glm::length(d), 1e-5 * glm::length(d));
      }
    }
}

TEST(LightSampling, DirectionalLightArrivesFromOneDirectionAtInfinity) {
  SceneBuffers sb = test_scene_buffers(load_world_scene(write_temp_file(
      "sun.json", scene_json(R"({"type": "sphere", "center": [0, 100, 0], "radius": 0.1, "material": "lamp"})",
                             R"({"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": [3, 2, 1]})"))));
  glm::dvec3 towards_light = -glm::normalize(glm::dvec3(0.3, -1, 0.2));
  for (glm::dvec3 x : {glm::dvec3(0, 0, 0), glm::dvec3(-10, 4, 20)}) {
    LightSamples s = sample_lights(sb, x, 1, 1);
    ASSERT_EQ(s.status(0), 2);
    EXPECT_NEAR(glm::length(s.wi(0) - towards_light), 0, 1e-6);
    EXPECT_EQ(s.le(0), glm::dvec3(3, 2, 1));
    EXPECT_TRUE(std::isinf(s.distance(0)));
  }
}

TEST(LightSampling, PointLightFollowsTheInverseSquareLaw) {
  SceneBuffers sb = test_scene_buffers(load_world_scene(write_temp_file(
      "point.json", scene_json(R"({"type": "sphere", "center": [0, 100, 0], "radius": 0.1, "material": "lamp"})",
                               R"({"type": "point", "position": [1, 2, 3], "intensity": [5, 5, 5]})"))));
  for (glm::dvec3 x : {glm::dvec3(0, 0, 0), glm::dvec3(1, 2, 3.5), glm::dvec3(-10, 4, 20)}) {
    LightSamples s = sample_lights(sb, x, 1, 1);
    glm::dvec3 d = glm::dvec3(1, 2, 3) - x;
    ASSERT_EQ(s.status(0), 2);
    EXPECT_NEAR(s.le(0).x, 5 / glm::dot(d, d), 1e-5 * 5 / glm::dot(d, d));
    EXPECT_NEAR(glm::length(s.wi(0) - glm::normalize(d)), 0, 1e-6);
  }
}
