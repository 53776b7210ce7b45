// The sampling routines of light tracing on the device, by chi-square against the densities they claim:
// sample_emission per light type (kernels/emission.cl: the light chosen by power, the point against
// pdf_pos binned over the emitter's domain, the direction against light_emission_pdf's pdf_dir) and the
// camera's importance (kernels/camera_importance.cl: camera rays' directions against camera_pdf_we,
// camera_sample_wi's lens directions against its pdf, raster positions against the camera's geometry).
// Every density is also checked to integrate to 1 over its domain. Significance as the other chi-square
// tests: a 1 % family-wise level, Sidak-corrected per run (Chi2Family).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "chi2.h"
#include "runtime/image_io.h"
#include "runtime/light_transport.h"
#include "test_support.h"

namespace {

constexpr double kDeg = M_PI / 180;
constexpr size_t kSamples = 1000000;

pc_float4 f4(const glm::dvec3& v) { return {float(v.x), float(v.y), float(v.z), 0.0f}; }
glm::dvec3 vec(const pc_float4& v) { return {v.x, v.y, v.z}; }

std::string scene_json(const std::string& shapes, const std::string& lights = "") {
  return R"({"camera": {"position": [0, 0, -5], "look_at": [0, 0, 0], "width": 4, "height": 4},
    "materials": {"lamp": {"type": "diffuse", "reflectance": [0, 0, 0]}}, "shapes": [)" +
         shapes + "]" + (lights.empty() ? "" : R"(, "lights": [)" + lights + "]") + "}";
}

// A scene of lights with a small dark sphere far off (so that every scene has a shape and bounds).
DeviceScene light_scene(const std::string& shapes, const std::string& lights = "") {
  std::string all = R"({"type": "sphere", "center": [0, -3, 0], "radius": 0.5, "material": "lamp"})";
  if (!shapes.empty()) all += ", " + shapes;
  return load_device_scene(write_temp_file("emission.json", scene_json(all, lights)), DeviceOrigin::world);
}

// Emission samples as emission_sample_test writes them, 16 floats each.
struct EmissionSamples {
  std::vector<float> v;
  size_t n = 0;
  glm::dvec3 p(size_t i) const { return {v[16 * i], v[16 * i + 1], v[16 * i + 2]}; }
  glm::dvec3 n_(size_t i) const { return {v[16 * i + 3], v[16 * i + 4], v[16 * i + 5]}; }
  glm::dvec3 d(size_t i) const { return {v[16 * i + 6], v[16 * i + 7], v[16 * i + 8]}; }
  bool ok(size_t i) const { return v[16 * i + 9] == 1; }
  double pdf_choice(size_t i) const { return v[16 * i + 10]; }
  double pdf_pos(size_t i) const { return v[16 * i + 11]; }
  double pdf_dir(size_t i) const { return v[16 * i + 12]; }
  double eval_pos(size_t i) const { return v[16 * i + 13]; }
  double eval_dir(size_t i) const { return v[16 * i + 14]; }
  uint32_t light(size_t i) const { return uint32_t(v[16 * i + 15]); }
};

// The scene on the device with what the light kernels take beside it.
struct EmissionScene {
  DeviceScene scene;
  SceneBuffers sb;
  LightTransportSetup lt;
  ClBuffer lt_header, cdf;
  explicit EmissionScene(DeviceScene s)
      : scene(std::move(s)), sb(test_scene_buffers(scene)), lt(light_transport_setup(scene, 1)),
        lt_header(upload(test_device(), std::vector<LightTransportHeader>{lt.header})),
        cdf(upload(test_device(), lt.emission_cdf)) {}
  glm::dvec3 centre() const { return vec(lt.header.bounds); }
  double radius() const { return lt.header.bounds.w; }
};

EmissionSamples sample_emission(const EmissionScene& es, uint32_t seed, size_t n = kSamples) {
  ClContext& cl = test_device();
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, n * 16 * sizeof(float));
  ClKernel k(sampling_test_program().kernel("emission_sample_test"));
  cl_uint a = es.sb.bind(k);
  k.arg(a++, es.lt_header.mem);
  k.arg(a++, es.cdf.mem);
  k.arg(a++, cl_uint(seed));
  k.arg(a++, out.mem);
  run_kernel(cl, k.k, n);
  return {read_buffer<float>(cl, out, n * 16), n};
}

BinIntegrator emission_pdf_integrator(const EmissionScene& es, uint32_t light, const glm::dvec3& p,
                                      const glm::dvec3& n, const SphereBinning& binning) {
  return [&es, light, p, n, binning](const std::vector<uint32_t>& bins, int order) {
    ClKernel k(sampling_test_program().kernel("emission_pdf_bins"));
    cl_uint a = es.sb.bind(k);
    k.arg(a++, es.lt_header.mem);
    k.arg(a++, cl_uint(light));
    k.arg(a++, f4(p));
    k.arg(a++, f4(n));
    return run_pdf_bins_kernel(k, a, binning, bins, order);
  };
}

// Directions (or failures, in the cell beyond the bins) against a density's bin integrals: the chi-square
// run, and its integral over the binned domain in *pdf_total.
Chi2Result direction_fit(const std::vector<glm::dvec3>& dirs, size_t failed, const SphereBinning& binning,
                         const BinIntegrator& integrate, double* pdf_total, int* order, int max_order = 256) {
  std::vector<double> observed(binning.count() + 1, 0);
  for (const glm::dvec3& d : dirs) observed[binning.bin_of(d)] += 1;
  observed.back() += double(failed);
  double n = double(dirs.size() + failed);
  BinIntegrals integrals = integrate_bins(integrate, binning.count(), n, 0.1, max_order);
  *order = integrals.highest_order;
  EXPECT_LT(integrals.worst, 0.5) << "quadrature: " << integrals.unconverged << " bins unconverged";
  return chi2_test(observed, expected_counts(integrals, n, pdf_total));
}

// Per-sample consistency: sampled, the only light's choice 1, the pdfs as sampled equal to
// light_emission_pdf's for the same point and direction. Returns the first problem ("" if none) when
// more than 1e-5 of the samples have one: a direction drawn within rounding of an environment texel's
// edge may find the neighbour texel's density (as in light_sampling_test).
std::string check_samples(const EmissionSamples& s) {
  size_t bad = 0;
  std::string first;
  for (size_t i = 0; i < s.n; ++i) {
    bool ok = s.ok(i) && s.pdf_choice(i) == 1 && close_rel(s.pdf_pos(i), s.eval_pos(i), 1e-5) &&
              close_rel(s.pdf_dir(i), s.eval_dir(i), 1e-4) && std::abs(glm::length(s.d(i)) - 1) < 1e-5;
    if (!ok && !bad++) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "sample %zu: ok %d choice %g pdf_pos %g (eval %g) pdf_dir %g (eval %g)", i, s.ok(i),
                    s.pdf_choice(i), s.pdf_pos(i), s.eval_pos(i), s.pdf_dir(i), s.eval_dir(i));
      first = buf;
    }
  }
  return bad > s.n / 100000 ? std::to_string(bad) + " bad samples, first: " + first : "";
}

// An orthonormal frame (t, b) about unit n.
void frame_of(const glm::dvec3& n, glm::dvec3* t, glm::dvec3* b) {
  glm::dvec3 other = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  *t = glm::normalize(glm::cross(other, n));
  *b = glm::cross(n, *t);
}

// Points of a disk of radius r about c facing w, binned by (rho / r)^2 (rings bins) and angle (sectors):
// equal areas. With sectors 0 only rings (for disks whose frame varies). Observed counts per cell, one
// more cell for points off the disk or off its plane.
std::vector<double> disk_cells(const std::vector<glm::dvec3>& points, const std::vector<glm::dvec3>& normals,
                               const glm::dvec3& c_of_zero, double r, uint32_t rings, uint32_t sectors) {
  std::vector<double> observed(size_t(rings) * std::max(sectors, 1u) + 1, 0);
  for (size_t i = 0; i < points.size(); ++i) {
    glm::dvec3 w = normals[i], q = points[i] - c_of_zero;
    double off_plane = std::abs(glm::dot(q, w)), rho2 = (glm::dot(q, q) - off_plane * off_plane) / (r * r);
    if (off_plane > 1e-4 * r || rho2 >= 1 + 1e-5) {
      observed.back() += 1;
      continue;
    }
    uint32_t ring = std::min(uint32_t(rho2 * rings), rings - 1), sector = 0;
    if (sectors) {
      glm::dvec3 t, b;
      frame_of(w, &t, &b);
      double a = std::atan2(glm::dot(q, b), glm::dot(q, t));
      if (a < 0) a += 2 * M_PI;
      sector = std::min(uint32_t(a / (2 * M_PI) * sectors), sectors - 1);
    }
    observed[size_t(ring) * std::max(sectors, 1u) + sector] += 1;
  }
  return observed;
}

std::string triangle_json(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const std::string& extra) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                R"({"type": "triangles", "positions": [[%.9g, %.9g, %.9g], [%.9g, %.9g, %.9g], [%.9g, %.9g, %.9g]],
                   "indices": [[0, 1, 2]], "material": "lamp", %s})",
                a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, extra.c_str());
  return buf;
}

const glm::dvec3 kA(-1, -0.5, 2), kB(0.2, 1.2, 1.8), kC(1.5, -1, 2.5);

// The point's barycentrics (of a, b; c the rest) by least squares in double.
glm::dvec2 barycentrics(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  glm::dvec3 e0 = a - c, e1 = b - c, q = p - c;
  double m00 = glm::dot(e0, e0), m01 = glm::dot(e0, e1), m11 = glm::dot(e1, e1), r0 = glm::dot(q, e0), r1 = glm::dot(q, e1);
  double det = m00 * m11 - m01 * m01;
  return {(r0 * m11 - r1 * m01) / det, (m00 * r1 - m01 * r0) / det};
}

}  // namespace

// The emitted directions against the directional density, for each light type's sampler.
TEST(EmissionChi2, DirectionsFollowTheDirectionalPdf) {
  const glm::dvec3 spot_axis = glm::normalize(glm::dvec3(0.2, -1, 0.3));
  struct Case {
    std::string name, shapes, lights;
    // Directions from the sample in the frame the density is integrated in; normal passed to the density.
    bool canonical_normal;  // sphere lights: each sample's direction in its own normal's frame, about +z
    SphereBinning binning;
  };
  std::vector<Case> cases = {
      {"triangle", triangle_json(kA, kB, kC, R"("emission": [2, 2, 2])"), "", false, SphereBinning()},
      {"triangle, two-sided", triangle_json(kA, kB, kC, R"("emission": [2, 2, 2], "two_sided": true)"), "", false,
       SphereBinning()},
      {"sphere, directions in the frame of each point's normal",
       R"({"type": "sphere", "center": [0.3, 0.2, 1], "radius": 0.7, "material": "lamp", "emission": [2, 2, 2]})", "",
       true, SphereBinning()},
      {"point", "", R"({"type": "point", "position": [1, 2, 3], "intensity": [5, 5, 5]})", false, SphereBinning()},
      {"spot", "",
       R"({"type": "spot", "position": [0.5, 2, -1], "direction": [0.2, -1, 0.3], "intensity": [7, 7, 7],
           "inner_angle_degrees": 25, "outer_angle_degrees": 40})",
       false, SphereBinning::about(spot_axis, 45 * kDeg)},
  };
  Chi2Family family(cases.size());
  for (size_t k = 0; k < cases.size(); ++k) {
    const Case& c = cases[k];
    SCOPED_TRACE(c.name);
    EmissionScene es(light_scene(c.shapes, c.lights));
    ASSERT_EQ(es.lt.emission_cdf.size(), 2u) << "one light";
    EmissionSamples s = sample_emission(es, 700 + uint32_t(k));
    EXPECT_EQ(check_samples(s), "");
    std::vector<glm::dvec3> dirs(s.n);
    glm::dvec3 n0 = s.n_(0);
    if (c.canonical_normal) n0 = {0, 0, 1};
    for (size_t i = 0; i < s.n; ++i) {
      dirs[i] = s.d(i);
      if (c.canonical_normal) {
        glm::dvec3 n = glm::normalize(s.n_(i)), t, b;
        frame_of(n, &t, &b);
        dirs[i] = {glm::dot(dirs[i], t), glm::dot(dirs[i], b), glm::dot(dirs[i], n)};
      } else if (c.name == "triangle, two-sided") {
        n0 = glm::normalize(glm::cross(kB - kA, kC - kA));  // either side: the density is symmetric
      }
    }
    double pdf_total = 0;
    int order = 0;
    Chi2Result chi2 = direction_fit(dirs, 0, c.binning, emission_pdf_integrator(es, 0, s.p(0), n0, c.binning),
                                    &pdf_total, &order);
    family.expect_fit(c.name, chi2, run_detail(pdf_total, 1, order));
    EXPECT_NEAR(pdf_total, 1, 1e-3) << "the directional density integrates to 1";
  }
  family.print_summary();
}

// An environment map: light paths travel along -(the direction towards the sky), drawn by the map's
// distribution; binned in the map's frame, 5 x 5 bins per texel (so the density has no edge in a bin).
TEST(EmissionChi2, EnvironmentDirectionsAndDiskPositions) {
  Image img;
  img.width = 32;
  img.height = 16;
  for (uint32_t r = 0; r < img.height; ++r)
    for (uint32_t c = 0; c < img.width; ++c) {
      float v = 0.3f + 0.25f * std::sin(0.5f * c) * std::cos(0.9f * r) + (r == 5 && c == 20 ? 30.0f : 0.0f);
      img.rgb.insert(img.rgb.end(), {v, 0.6f * v, 1.3f * v});
    }
  write_exr(temp_dir() + "/emission-env.exr", img);
  EmissionScene es(light_scene("", R"({"type": "environment", "file": "emission-env.exr", "scale": 2})"));
  ASSERT_EQ(es.lt.emission_cdf.size(), 2u);
  EmissionSamples s = sample_emission(es, 800);
  EXPECT_EQ(check_samples(s), "");
  SphereBinning aligned;
  aligned.x = {1, 0, 0};
  aligned.y = {0, 0, 1};
  aligned.z = {0, 1, 0};
  std::vector<glm::dvec3> dirs(s.n), points(s.n), normals(s.n), zeros(s.n);
  for (size_t i = 0; i < s.n; ++i) {
    dirs[i] = s.d(i);
    points[i] = s.p(i) - (es.centre() - es.radius() * s.d(i));  // relative to its disk's centre
    normals[i] = s.d(i);
  }
  Chi2Family family(2);
  double pdf_total = 0;
  int order = 0;
  Chi2Result chi2 =
      direction_fit(dirs, 0, aligned, emission_pdf_integrator(es, 0, s.p(0), s.d(0), aligned), &pdf_total, &order);
  family.expect_fit("environment directions", chi2, run_detail(pdf_total, 1, order));
  EXPECT_NEAR(pdf_total, 1, 1e-3);
  // Positions on the disk facing each direction: uniform by area, (rho / r)^2 in 40 equal rings.
  const uint32_t rings = 40;
  std::vector<double> observed = disk_cells(points, normals, glm::dvec3(0), es.radius(), rings, 0);
  std::vector<double> expected(rings + 1, 0);
  double disk_area = M_PI * es.radius() * es.radius();
  for (uint32_t b = 0; b < rings; ++b) expected[b] = double(s.n) * s.pdf_pos(0) * disk_area / rings;
  EXPECT_NEAR(s.pdf_pos(0) * disk_area, 1, 1e-5) << "the positional density integrates to 1";
  family.expect_fit("environment disk positions", chi2_test(observed, expected), "");
  family.print_summary();
}

// Points over the emitter's domain against pdf_pos: the triangle's barycentric domain, the sphere's
// surface, the directional light's disk; and the directional light's one direction.
TEST(EmissionChi2, PositionsFollowThePositionalPdf) {
  Chi2Family family(3);
  {
    EmissionScene es(light_scene(triangle_json(kA, kB, kC, R"("emission": [2, 2, 2])")));
    EmissionSamples s = sample_emission(es, 900);
    EXPECT_EQ(check_samples(s), "");
    // Barycentrics (u, v) in a K x K grid over the unit square: cells inside the triangle u + v <= 1 whole,
    // cells on its diagonal half, each of world area 2 A (cell area) with A the triangle's.
    const int K = 24;
    const double area = 0.5 * glm::length(glm::cross(kB - kA, kC - kA));
    std::vector<double> observed(K * K + 1, 0), expected(K * K + 1, 0);
    size_t off_plane = 0;
    for (size_t i = 0; i < s.n; ++i) {
      glm::dvec2 b = barycentrics(s.p(i), kA, kB, kC);
      glm::dvec3 back = b.x * kA + b.y * kB + (1 - b.x - b.y) * kC;
      off_plane += glm::length(back - s.p(i)) > 1e-5;
      int u = std::clamp(int(b.x * K), 0, K - 1), v = std::clamp(int(b.y * K), 0, K - 1);
      bool inside = b.x >= -1e-6 && b.y >= -1e-6 && b.x + b.y <= 1 + 1e-6;
      observed[inside ? u * K + v : K * K] += 1;
    }
    double total = 0;
    for (int u = 0; u < K; ++u)
      for (int v = 0; v < K; ++v) {
        double cell = u + v < K - 1 ? 1.0 : u + v == K - 1 ? 0.5 : 0.0;  // fraction of the cell inside
        expected[u * K + v] = double(s.n) * s.pdf_pos(0) * 2 * area * cell / (K * K);
        total += s.pdf_pos(0) * 2 * area * cell / (K * K);
      }
    EXPECT_EQ(off_plane, 0u);
    EXPECT_NEAR(total, 1, 1e-5) << "the positional density integrates to 1 over the triangle";
    family.expect_fit("triangle points, barycentric grid", chi2_test(observed, expected), "");
  }
  {
    const glm::dvec3 c(0.3, 0.2, 1);
    const double r = 0.7;
    EmissionScene es(light_scene(R"({"type": "sphere", "center": [0.3, 0.2, 1], "radius": 0.7, "material": "lamp",
                                     "emission": [2, 2, 2]})"));
    EmissionSamples s = sample_emission(es, 901);
    EXPECT_EQ(check_samples(s), "");
    SphereBinning binning;
    binning.theta_bins = 40;
    binning.phi_bins = 80;
    std::vector<double> observed(binning.count() + 1, 0), expected(binning.count() + 1, 0);
    for (size_t i = 0; i < s.n; ++i) {
      glm::dvec3 q = s.p(i) - c;
      observed[std::abs(glm::length(q) - r) < 1e-5 ? binning.bin_of(q) : binning.count()] += 1;
    }
    double total = 0;
    for (uint32_t t = 0; t < binning.theta_bins; ++t)
      for (uint32_t p = 0; p < binning.phi_bins; ++p) {
        double solid = (std::cos(M_PI * t / binning.theta_bins) - std::cos(M_PI * (t + 1) / binning.theta_bins)) * 2 *
                       M_PI / binning.phi_bins;
        expected[t * binning.phi_bins + p] = double(s.n) * s.pdf_pos(0) * r * r * solid;
        total += s.pdf_pos(0) * r * r * solid;
      }
    EXPECT_NEAR(total, 1, 1e-5) << "the positional density integrates to 1 over the sphere";
    family.expect_fit("sphere points over its surface", chi2_test(observed, expected), "");
  }
  {
    const glm::dvec3 dir = glm::normalize(glm::dvec3(0.3, -1, 0.2));
    EmissionScene es(light_scene("", R"({"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": [3, 2, 1]})"));
    EmissionSamples s = sample_emission(es, 902);
    EXPECT_EQ(check_samples(s), "");
    std::vector<glm::dvec3> points(s.n), normals(s.n, dir);
    size_t off_direction = 0;
    for (size_t i = 0; i < s.n; ++i) {
      points[i] = s.p(i);
      off_direction += glm::length(s.d(i) - dir) > 1e-6 || s.pdf_dir(i) != 1;
    }
    EXPECT_EQ(off_direction, 0u) << "a directional light emits along its direction only (a delta, pdf_dir 1)";
    const uint32_t rings = 16, sectors = 24;
    std::vector<double> observed =
        disk_cells(points, normals, es.centre() - es.radius() * dir, es.radius(), rings, sectors);
    double disk_area = M_PI * es.radius() * es.radius();
    std::vector<double> expected(rings * sectors + 1, double(s.n) * s.pdf_pos(0) * disk_area / (rings * sectors));
    expected.back() = 0;
    EXPECT_NEAR(s.pdf_pos(0) * disk_area, 1, 1e-5) << "the positional density integrates to 1 over the disk";
    family.expect_fit("directional light, points on the scene-bounds disk", chi2_test(observed, expected), "");
  }
  family.print_summary();
}

// The light a path starts on, against pdf_choice, which must be proportional to the lights' power.
TEST(EmissionChi2, LightsAreChosenByPower) {
  EmissionScene es(light_scene(
      triangle_json(kA, kB, kC, R"("emission": [2, 2, 2])") +
          R"(, {"type": "sphere", "center": [0.3, 0.2, 1], "radius": 0.4, "material": "lamp", "emission": [1, 3, 1]})",
      R"({"type": "point", "position": [1, 2, 3], "intensity": [5, 5, 5]},
         {"type": "spot", "position": [0.5, 2, -1], "direction": [0.2, -1, 0.3], "intensity": [7, 7, 7],
          "inner_angle_degrees": 25, "outer_angle_degrees": 40},
         {"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": [0.1, 0.1, 0.1]})"));
  const size_t lights = es.lt.power.size();
  ASSERT_EQ(lights, 5u);
  EmissionSamples s = sample_emission(es, 950);
  std::vector<double> observed(lights, 0), expected(lights, 0);
  double power_total = 0;
  for (double p : es.lt.power) power_total += p;
  size_t wrong_pdf = 0;
  for (size_t i = 0; i < s.n; ++i) {
    ASSERT_TRUE(s.ok(i));
    uint32_t l = s.light(i);
    observed[l] += 1;
    wrong_pdf += !close_rel(s.pdf_choice(i), es.lt.power[l] / power_total, 1e-5);
  }
  for (size_t l = 0; l < lights; ++l) expected[l] = double(s.n) * es.lt.power[l] / power_total;
  EXPECT_EQ(wrong_pdf, 0u) << "pdf_choice is the light's share of the power";
  Chi2Family family(1);
  family.expect_fit("light choice by power", chi2_test(observed, expected), "");
}

// ---- The camera ----

namespace {

SceneHeader camera_header(const std::string& camera) {
  std::string scene = R"({"camera": )" + camera + R"(, "materials": {"m": {"type": "diffuse"}},
    "shapes": [{"type": "sphere", "radius": 1, "material": "m"}]})";
  return load_device_scene(write_temp_file("camera.json", scene), DeviceOrigin::world).header;
}

const char* kPinhole = R"({"position": [1, 2, 5], "look_at": [0, 0.5, 0], "up": [0, 1, 0.2], "fov_y_degrees": 50,
    "width": 32, "height": 24})";
const char* kLens = R"({"type": "thin_lens", "position": [1, 2, 5], "look_at": [0, 0.5, 0], "up": [0, 1, 0.2],
    "fov_y_degrees": 50, "width": 32, "height": 24, "aperture_radius": 0.25, "focus_distance": 3.5})";

struct CameraRays {
  std::vector<float> v;
  glm::dvec3 o(size_t i) const { return {v[12 * i], v[12 * i + 1], v[12 * i + 2]}; }
  glm::dvec3 d(size_t i) const { return {v[12 * i + 3], v[12 * i + 4], v[12 * i + 5]}; }
  glm::dvec2 drawn(size_t i) const { return {v[12 * i + 6], v[12 * i + 7]}; }
  glm::dvec2 raster(size_t i) const { return {v[12 * i + 8], v[12 * i + 9]}; }
  double pdf_dir(size_t i) const { return v[12 * i + 10]; }
  double we(size_t i) const { return v[12 * i + 11]; }
};

ClBuffer header_buffer(const SceneHeader& h) { return upload(test_device(), std::vector<SceneHeader>{h}); }

// The sum of the pixels' importance a ray carries, from the camera's geometry in double: W H over the
// image area at distance 1 (A), cos^4 and the lens area (pbrt-v4's We).
double we_expected(const SceneHeader& h, const glm::dvec3& d) {
  double area = 4 * glm::length(vec(h.cam_right)) * glm::length(vec(h.cam_up)), c = glm::dot(d, vec(h.cam_forward));
  double lens = h.lens_radius > 0 ? M_PI * h.lens_radius * h.lens_radius : 1;
  return double(h.width) * h.height / (area * c * c * c * c * lens);
}

// The image position of the ray from lens point p through x (or along d), from the geometry in double.
glm::dvec2 raster_expected(const SceneHeader& h, const glm::dvec3& p, const glm::dvec3& d) {
  glm::dvec3 fwd = vec(h.cam_forward), cam = vec(h.cam_position), right = vec(h.cam_right), up = vec(h.cam_up);
  double focus = h.lens_radius > 0 ? h.focus_distance : 1;
  glm::dvec3 q = p + d * (focus / glm::dot(d, fwd)), pin = (q - cam) / focus;
  double sx = glm::dot(pin, right) / glm::dot(right, right), sy = glm::dot(pin, up) / glm::dot(up, up);
  return {0.5 * (sx + 1) * h.width, 0.5 * (1 - sy) * h.height};
}

}  // namespace

// Camera rays of uniform image positions (box filter) against camera_pdf_we from their lens point: a
// pinhole, and a thin lens with the lens point fixed; camera_raster inverts camera_ray, and camera_we is
// W H / (A cos^4 theta lens area).
TEST(CameraImportanceChi2, RayDirectionsFollowThePdfWe) {
  Chi2Family family(2);
  for (const char* camera : {kPinhole, kLens}) {
    SceneHeader h = camera_header(camera);
    const std::string name = h.lens_radius > 0 ? "thin lens, lens point fixed" : "pinhole";
    SCOPED_TRACE(name);
    ClContext& cl = test_device();
    ClBuffer hb = header_buffer(h), out(cl, CL_MEM_WRITE_ONLY, kSamples * 12 * sizeof(float));
    ClKernel k(sampling_test_program().kernel("camera_we_test"));
    k.arg(0, hb.mem);
    cl_float2 u_lens = {{0.8f, 0.3f}};
    k.arg(1, u_lens);
    k.arg(2, cl_uint(1000));
    k.arg(3, out.mem);
    run_kernel(cl, k.k, kSamples);
    CameraRays r{read_buffer<float>(cl, out, kSamples * 12)};
    size_t raster_off = 0, we_off = 0;
    std::vector<glm::dvec3> dirs(kSamples);
    for (size_t i = 0; i < kSamples; ++i) {
      dirs[i] = r.d(i);
      raster_off += glm::length(r.raster(i) - r.drawn(i)) > 2e-3;
      we_off += !close_rel(r.we(i), we_expected(h, r.d(i)), 1e-4) ||
                !close_rel(r.pdf_dir(i), we_expected(h, r.d(i)) * glm::dot(r.d(i), vec(h.cam_forward)) *
                                             (h.lens_radius > 0 ? M_PI * h.lens_radius * h.lens_radius : 1) /
                                             (double(h.width) * h.height),
                           1e-4);
    }
    EXPECT_EQ(raster_off, 0u) << "camera_raster of a camera ray gives the image position it was drawn at";
    EXPECT_EQ(we_off, 0u) << "camera_we and camera_pdf_we against the camera's geometry";
    // Binned about the axis out to beyond the image's corners (half-diagonal 37.8 degrees).
    SphereBinning binning = SphereBinning::about(vec(h.cam_forward), 45 * kDeg);
    binning.theta_bins = 40;
    binning.phi_bins = 80;
    glm::dvec3 o = r.o(0);
    BinIntegrator integrate = [&h, o, binning](const std::vector<uint32_t>& bins, int order) {
      ClKernel k(sampling_test_program().kernel("camera_we_pdf_bins"));
      ClBuffer hb = header_buffer(h);
      k.arg(0, hb.mem);
      k.arg(1, f4(o));
      return run_pdf_bins_kernel(k, 2, binning, bins, order);
    };
    double pdf_total = 0;
    int order = 0;
    Chi2Result chi2 = direction_fit(dirs, 0, binning, integrate, &pdf_total, &order);
    family.expect_fit(name, chi2, run_detail(pdf_total, 1, order));
    EXPECT_NEAR(pdf_total, 1, 1e-3) << "camera_pdf_we integrates to 1 over the image";
  }
  family.print_summary();
}

// camera_sample_wi: through a thin lens the directions from x towards the lens against the pdf it
// returns (integrated over the lens's solid angle), and the raster position of every sample against the
// lens geometry; through a pinhole the one direction, its raster position and We.
TEST(CameraImportanceChi2, SampleWiDirectionsAndRasterPositions) {
  SceneHeader lens = camera_header(kLens), pinhole = lens;
  pinhole.lens_radius = 0;
  const glm::dvec3 x(0.3, 0.9, 1.2);  // in front of the camera, nearer than the plane in focus
  ClContext& cl = test_device();
  auto sample = [&](const SceneHeader& h, uint32_t seed, size_t n) {
    ClBuffer hb = header_buffer(h), out(cl, CL_MEM_WRITE_ONLY, n * 12 * sizeof(float));
    ClKernel k(sampling_test_program().kernel("camera_wi_test"));
    k.arg(0, hb.mem);
    k.arg(1, f4(x));
    k.arg(2, cl_uint(seed));
    k.arg(3, out.mem);
    run_kernel(cl, k.k, n);
    return read_buffer<float>(cl, out, n * 12);
  };
  {
    std::vector<float> v = sample(lens, 1100, kSamples);
    std::vector<glm::dvec3> dirs;
    size_t failed = 0, bad = 0;
    std::string first;
    for (size_t i = 0; i < kSamples; ++i) {
      const float* s = &v[12 * i];
      if (s[3] != 1) {
        ++failed;
        continue;
      }
      glm::dvec3 wi(s[0], s[1], s[2]), p(s[9], s[10], s[11]);
      dirs.push_back(wi);
      glm::dvec2 want = raster_expected(lens, p, -wi);
      bool ok = close_rel(s[4], s[5], 1e-3) && std::abs(s[7] - want.x) < 2e-3 && std::abs(s[8] - want.y) < 2e-3 &&
                close_rel(s[6], we_expected(lens, -wi), 1e-4);
      if (!ok && !bad++) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "sample %zu: pdf %g (density %g), raster (%g %g) want (%g %g), We %g want %g", i,
                      s[4], s[5], s[7], s[8], want.x, want.y, s[6], we_expected(lens, -wi));
        first = buf;
      }
    }
    EXPECT_EQ(failed, 0u);
    EXPECT_EQ(bad, 0u) << first;
    glm::dvec3 to_cam = vec(lens.cam_position) - x;
    SphereBinning binning = SphereBinning::about(to_cam, 1.3 * std::atan(lens.lens_radius / glm::length(to_cam)));
    binning.theta_bins = 30;
    binning.phi_bins = 60;
    BinIntegrator integrate = [&lens, x, binning](const std::vector<uint32_t>& bins, int order) {
      ClKernel k(sampling_test_program().kernel("camera_wi_pdf_bins"));
      ClBuffer hb = header_buffer(lens);
      k.arg(0, hb.mem);
      k.arg(1, f4(x));
      return run_pdf_bins_kernel(k, 2, binning, bins, order);
    };
    double pdf_total = 0;
    int order = 0;
    // The lens's outline crosses bins obliquely: up to order 512 there.
    Chi2Result chi2 = direction_fit(dirs, failed, binning, integrate, &pdf_total, &order, 512);
    Chi2Family family(1);
    family.expect_fit("thin lens, directions towards the lens", chi2, run_detail(pdf_total, 1, order));
    EXPECT_NEAR(pdf_total, 1, 1e-3) << "the density towards the lens integrates to 1";
  }
  {
    std::vector<float> v = sample(pinhole, 1101, 4);
    glm::dvec3 cam = vec(pinhole.cam_position), wi = glm::normalize(cam - x);
    glm::dvec2 want = raster_expected(pinhole, cam, -wi);
    for (size_t i = 0; i < 4; ++i) {
      const float* s = &v[12 * i];
      ASSERT_EQ(s[3], 1);
      EXPECT_NEAR(glm::length(glm::dvec3(s[0], s[1], s[2]) - wi), 0, 1e-6);
      EXPECT_NEAR(s[4], glm::dot(cam - x, cam - x) / glm::dot(-wi, vec(pinhole.cam_forward)),
                  1e-5 * s[4]);  // dist^2 / cos at the (delta) lens
      EXPECT_NEAR(s[7], want.x, 2e-3);
      EXPECT_NEAR(s[8], want.y, 2e-3);
      EXPECT_NEAR(s[6], we_expected(pinhole, -wi), 1e-4 * s[6]);
    }
  }
}
