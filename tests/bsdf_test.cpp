// BSDF sampling against the BSDFs' own densities and values (kernels/bsdf*.cl), run on the device through
// kernels/tests_sampling.cl: chi-square tests of every non-delta sampling routine, exact checks of the
// delta lobes and of the Fresnel terms against double-precision references written here, white-furnace
// energy checks, and the Oren-Nayar directional albedo against its closed form.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "chi2.h"
#include "scene/scene_error.h"
#include "test_support.h"

namespace {

constexpr double kDeg = M_PI / 180;
constexpr size_t kChi2Samples = 1000000;

pc_float4 f4(double x, double y, double z) { return {float(x), float(y), float(z), 0.0f}; }
pc_float4 grey(double v) { return f4(v, v, v); }

// Unit direction at polar angle theta from +z and azimuth phi, in degrees.
glm::dvec3 direction(double theta_deg, double phi_deg = 17) {
  double t = theta_deg * kDeg, p = phi_deg * kDeg;
  return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

Material material(uint32_t type) {
  Material m{};
  m.type = type;
  m.color_texture = PC_INVALID;
  m.ior = 1.5f;
  m.exponent = 1;
  return m;
}
Material diffuse(pc_float4 rho) {
  Material m = material(PC_MAT_DIFFUSE);
  m.color = rho;
  return m;
}
Material oren_nayar(pc_float4 rho, double sigma_deg) {
  Material m = material(PC_MAT_OREN_NAYAR);
  m.color = rho;
  m.sigma = float(sigma_deg * kDeg);
  return m;
}
Material phong(pc_float4 kd, pc_float4 ks, float exponent) {
  Material m = material(PC_MAT_PHONG);
  m.color = kd;
  m.specular = ks;
  m.exponent = exponent;
  return m;
}
Material mirror(pc_float4 rho) {
  Material m = material(PC_MAT_MIRROR);
  m.color = rho;
  return m;
}
Material dielectric(float ior, pc_float4 transmittance) {
  Material m = material(PC_MAT_DIELECTRIC);
  m.ior = ior;
  m.color = transmittance;
  return m;
}
Material thin_dielectric(float ior, pc_float4 transmittance) {
  Material m = dielectric(ior, transmittance);
  m.type = PC_MAT_THIN_DIELECTRIC;
  return m;
}
// Gold-like complex index; alpha = roughness^2 as the scene loader sets it.
Material conductor(double roughness, pc_float4 eta = f4(0.18, 0.42, 1.37), pc_float4 k = f4(3.42, 2.35, 1.77)) {
  Material m = material(PC_MAT_ROUGH_CONDUCTOR);
  m.alpha = float(roughness * roughness);
  m.specular = eta;
  m.k = k;
  return m;
}
Material plastic(pc_float4 kd, double roughness, float ior = 1.5f) {
  Material m = material(PC_MAT_PLASTIC);
  m.color = kd;
  m.alpha = float(roughness * roughness);
  m.ior = ior;
  return m;
}

// Samples as bsdf_sample_test writes them, 12 floats each.
struct Samples {
  std::vector<float> v;
  size_t n = 0;
  glm::dvec3 wi(size_t i) const { return {v[12 * i], v[12 * i + 1], v[12 * i + 2]}; }
  int status(size_t i) const { return int(v[12 * i + 3]); }
  double pdf(size_t i) const { return v[12 * i + 4]; }
  double pdf_eval(size_t i) const { return v[12 * i + 5]; }
  glm::dvec3 weight(size_t i) const { return {v[12 * i + 6], v[12 * i + 7], v[12 * i + 8]}; }
  glm::dvec3 f(size_t i) const { return {v[12 * i + 9], v[12 * i + 10], v[12 * i + 11]}; }
};

// n samples of bsdf_sample(m, wo, u): u hashed from (item, seed), or the given u values.
Samples sample_bsdf(const Material& m, const glm::dvec3& wo, uint32_t seed, size_t n,
                    const std::vector<pc_float4>& u = {}) {
  ClContext& cl = test_device();
  ClBuffer mat = upload(cl, std::vector<Material>{m}), u_in = upload(cl, u);
  ClBuffer out(cl, CL_MEM_WRITE_ONLY, n * 12 * sizeof(float));
  ClKernel k(sampling_test_program().kernel("bsdf_sample_test"));
  k.arg(0, mat.mem);
  k.arg(1, f4(wo.x, wo.y, wo.z));
  k.arg(2, cl_uint(seed));
  k.arg(3, u_in.mem);
  k.arg(4, cl_uint(u.empty() ? 0 : 1));
  k.arg(5, out.mem);
  run_kernel(cl, k.k, n);
  return {read_buffer<float>(cl, out, n * 12), n};
}

// Integrates bsdf_pdf(m, wo, .) over bins on the device.
BinIntegrator bsdf_pdf_integrator(const Material& m, const glm::dvec3& wo, const SphereBinning& binning) {
  return [m, wo, binning](const std::vector<uint32_t>& bins, int order) {
    ClBuffer mat = upload(test_device(), std::vector<Material>{m});
    ClKernel k(sampling_test_program().kernel("bsdf_pdf_bins"));
    k.arg(0, mat.mem);
    k.arg(1, f4(wo.x, wo.y, wo.z));
    return run_pdf_bins_kernel(k, 2, binning, bins, order);
  };
}

struct Chi2Case {
  std::string name;
  Material m;
  glm::dvec3 wo;
};

struct Chi2Outcome {
  Chi2Result chi2;
  BinIntegrals integrals;
  double pdf_total = 0;         // integral of bsdf_pdf over the sphere
  double sampled_fraction = 0;  // samples that succeeded from a non-delta lobe
  size_t pdf_mismatches = 0, weight_mismatches = 0, bad_values = 0;
  std::string first_problem;
};

// Sampling and density of one case: samples from non-delta lobes are binned by direction; failures and
// delta-lobe samples form one more cell, whose expected count is the mass the density lacks.
Chi2Outcome run_chi2(const Chi2Case& c, uint32_t seed) {
  SphereBinning binning;
  const size_t n = kChi2Samples;
  Samples s = sample_bsdf(c.m, c.wo, seed, n);
  Chi2Outcome r;
  std::vector<double> observed(binning.count() + 1, 0);
  char buf[256];
  for (size_t i = 0; i < n; ++i) {
    if (s.status(i) != 1) {
      observed.back() += 1;
      continue;
    }
    glm::dvec3 wi = s.wi(i), w = s.weight(i), f = s.f(i);
    r.sampled_fraction += 1;
    observed[binning.bin_of(wi)] += 1;
    bool finite = std::isfinite(s.pdf(i)) && std::isfinite(w.x) && std::isfinite(w.y) && std::isfinite(w.z);
    if (!finite || s.pdf(i) <= 0 || w.x < 0 || w.y < 0 || w.z < 0 || std::abs(glm::length(wi) - 1) > 1e-5) {
      if (!r.bad_values++ && r.first_problem.empty()) {
        std::snprintf(buf, sizeof buf, "sample %zu: pdf %g weight (%g %g %g) |wi| %g", i, s.pdf(i), w.x, w.y, w.z,
                      glm::length(wi));
        r.first_problem = buf;
      }
      continue;
    }
    if (!close_rel(s.pdf(i), s.pdf_eval(i), 1e-3)) {
      if (!r.pdf_mismatches++ && r.first_problem.empty()) {
        std::snprintf(buf, sizeof buf, "sample %zu: sampled pdf %.7g, bsdf_pdf %.7g at wi (%g %g %g)", i, s.pdf(i),
                      s.pdf_eval(i), wi.x, wi.y, wi.z);
        r.first_problem = buf;
      }
    }
    glm::dvec3 want = f * (std::abs(wi.z) / s.pdf_eval(i));
    if (!close_rel(w.x, want.x, 1e-3) || !close_rel(w.y, want.y, 1e-3) || !close_rel(w.z, want.z, 1e-3)) {
      if (!r.weight_mismatches++ && r.first_problem.empty()) {
        std::snprintf(buf, sizeof buf, "sample %zu: weight (%.7g %.7g %.7g), f |cos| / pdf (%.7g %.7g %.7g)", i, w.x,
                      w.y, w.z, want.x, want.y, want.z);
        r.first_problem = buf;
      }
    }
  }
  r.sampled_fraction /= double(n);
  r.integrals = integrate_bins(bsdf_pdf_integrator(c.m, c.wo, binning), binning.count(), double(n));
  r.chi2 = chi2_test(observed, expected_counts(r.integrals, double(n), &r.pdf_total));
  return r;
}

// Runs every case, then checks each at the Sidak-corrected significance of the whole family.
void expect_chi2_family(const std::vector<Chi2Case>& cases, uint32_t seed) {
  Chi2Family family(cases.size());
  for (size_t i = 0; i < cases.size(); ++i) {
    const Chi2Case& c = cases[i];
    Chi2Outcome r = run_chi2(c, seed + uint32_t(i));
    family.expect_fit(c.name, r.chi2, run_detail(r.pdf_total, r.sampled_fraction, r.integrals.highest_order));
    SCOPED_TRACE(c.name);
    EXPECT_EQ(r.chi2.zero_cells_hit, 0) << "samples where bsdf_pdf integrates to 0";
    // Expected counts good to half a standard error in every bin (the refinement aims at a tenth).
    EXPECT_LT(r.integrals.worst, 0.5) << "quadrature: " << r.integrals.unconverged << " bins unconverged";
    EXPECT_EQ(r.bad_values, 0u) << r.first_problem;
    EXPECT_EQ(r.pdf_mismatches, 0u) << r.first_problem;
    EXPECT_EQ(r.weight_mismatches, 0u) << r.first_problem;
    // The density's total is the probability of a non-delta sample: 5 binomial standard errors, plus
    // 2e-4 for the single-precision quadrature.
    double f = r.sampled_fraction, se = std::sqrt(f * (1 - f) / double(kChi2Samples));
    EXPECT_NEAR(r.pdf_total, f, 5 * se + 2e-4);
  }
  family.print_summary();
}

}  // namespace

// ---- Chi-square tests of the sampling routines against bsdf_pdf ----

TEST(BsdfChi2, DiffuseAndOrenNayar) {
  std::vector<Chi2Case> cases = {
      {"diffuse wo 0", diffuse(grey(0.5)), direction(0)},
      {"diffuse wo 60", diffuse(grey(0.5)), direction(60)},
      {"diffuse wo 120 (back side)", diffuse(grey(0.5)), direction(120, -40)},
      {"oren_nayar sigma 20 wo 30", oren_nayar(grey(0.8), 20), direction(30)},
      {"oren_nayar sigma 20 wo 80", oren_nayar(grey(0.8), 20), direction(80, 200)},
      {"oren_nayar sigma 60 wo 10", oren_nayar(grey(0.8), 60), direction(10)},
      {"oren_nayar sigma 60 wo 70", oren_nayar(grey(0.8), 60), direction(70, 95)},
  };
  expect_chi2_family(cases, 1000);
}

TEST(BsdfChi2, Phong) {
  struct Lobe {
    const char* name;
    Material m;
  } lobes[] = {
      {"phong kd .5 ks .5 n 1", phong(grey(0.5), grey(0.5), 1)},
      {"phong kd .2 ks .8 n 20", phong(grey(0.2), grey(0.8), 20)},
      {"phong kd 0 ks 1 n 200", phong(grey(0), grey(1), 200)},
      {"phong coloured n 8", phong(f4(0.6, 0.2, 0.1), f4(0.1, 0.3, 0.4), 8)},
  };
  std::vector<Chi2Case> cases;
  for (const Lobe& l : lobes)
    for (double theta : {0.0, 40.0, 75.0}) cases.push_back({std::string(l.name) + " wo " + std::to_string(int(theta)), l.m, direction(theta, 33)});
  expect_chi2_family(cases, 2000);
}

TEST(BsdfChi2, RoughConductor) {
  std::vector<Chi2Case> cases;
  for (double r : {0.2, 0.5, 0.9})
    for (double theta : {10.0, 45.0, 80.0})
      cases.push_back({"rough_conductor r " + std::to_string(r).substr(0, 3) + " wo " + std::to_string(int(theta)),
                       conductor(r), direction(theta, -70)});
  cases.push_back({"rough_conductor r 0.4 wo 0 (normal)", conductor(0.4), glm::dvec3(0, 0, 1)});
  cases.push_back({"rough_conductor r 0.3 wo 135 (back side)", conductor(0.3), direction(135, 10)});
  expect_chi2_family(cases, 3000);
}

TEST(BsdfChi2, Plastic) {
  std::vector<Chi2Case> cases;
  for (double r : {0.3, 0.7})
    for (double theta : {20.0, 70.0})
      cases.push_back({"plastic r " + std::to_string(r).substr(0, 3) + " wo " + std::to_string(int(theta)),
                       plastic(f4(0.7, 0.4, 0.2), r), direction(theta, 150)});
  // A smooth coat: its delta reflection goes to the cell of the mass the density lacks.
  cases.push_back({"plastic smooth wo 30", plastic(f4(0.7, 0.4, 0.2), 0), direction(30)});
  cases.push_back({"plastic smooth wo 80", plastic(grey(0.3), 0), direction(80)});
  expect_chi2_family(cases, 4000);
}

// ---- Delta lobes, exactly ----

namespace {

// u values whose third component runs over a uniform grid (k + 0.5) / count; the others fixed.
std::vector<pc_float4> lobe_choice_grid(size_t count) {
  std::vector<pc_float4> u(count);
  for (size_t i = 0; i < count; ++i) u[i] = {0.3f, 0.7f, float((i + 0.5) / count), 0.0f};
  return u;
}

// Unpolarised Fresnel reflectance from Snell's law and the s and p amplitude coefficients, light
// arriving in index n_i at angle cos_i onto index n_t.
double fresnel_reference(double cos_i, double n_i, double n_t) {
  double sin_t = n_i / n_t * std::sqrt(std::max(0.0, 1 - cos_i * cos_i));
  if (sin_t >= 1) return 1;  // total internal reflection
  double cos_t = std::sqrt(1 - sin_t * sin_t);
  double rs = (n_i * cos_i - n_t * cos_t) / (n_i * cos_i + n_t * cos_t);
  double rp = (n_t * cos_i - n_i * cos_t) / (n_t * cos_i + n_i * cos_t);
  return 0.5 * (rs * rs + rp * rp);
}

// The same for a conductor of complex index n = eta + i k from a medium of index 1, in complex arithmetic.
double conductor_reference(double cos_i, double eta, double k) {
  std::complex<double> n(eta, k), c(cos_i, 0);
  std::complex<double> sin2_t = (1 - cos_i * cos_i) / (n * n);
  std::complex<double> cos_t = std::sqrt(1.0 - sin2_t);
  std::complex<double> rs = (c - n * cos_t) / (c + n * cos_t), rp = (n * c - cos_t) / (n * c + cos_t);
  return 0.5 * (std::norm(rs) + std::norm(rp));
}

// Tolerance of a single-precision Fresnel reflectance: 2e-6, more near the critical angle where
// cos_t = sqrt(1 - sin^2_t) loses digits (the float sin^2_t is within about 1e-7 of the exact one).
double fresnel_tolerance(double cos_i, double eta) {
  double sin2_t = (1 - cos_i * cos_i) / (eta * eta);
  return 2e-6 + (sin2_t < 1 ? 4e-7 / std::sqrt(std::max(1 - sin2_t, 1e-12)) : 0);
}

std::vector<float> run_fresnel_dielectric(const std::vector<std::pair<float, float>>& cos_eta) {
  ClContext& cl = test_device();
  std::vector<float> flat;
  for (auto [c, e] : cos_eta) flat.insert(flat.end(), {c, e});
  ClBuffer in = upload(cl, flat), out(cl, CL_MEM_WRITE_ONLY, cos_eta.size() * sizeof(float));
  ClKernel k(sampling_test_program().kernel("fresnel_dielectric_test"));
  k.arg(0, in.mem);
  k.arg(1, out.mem);
  run_kernel(cl, k.k, cos_eta.size());
  return read_buffer<float>(cl, out, cos_eta.size());
}

std::vector<pc_float4> run_fresnel_conductor(const std::vector<float>& cos_i, pc_float4 eta, pc_float4 kappa) {
  ClContext& cl = test_device();
  ClBuffer in = upload(cl, cos_i), out(cl, CL_MEM_WRITE_ONLY, cos_i.size() * sizeof(pc_float4));
  ClKernel k(sampling_test_program().kernel("fresnel_conductor_test"));
  k.arg(0, in.mem);
  k.arg(1, eta);
  k.arg(2, kappa);
  k.arg(3, out.mem);
  run_kernel(cl, k.k, cos_i.size());
  return read_buffer<pc_float4>(cl, out, cos_i.size());
}

// Inputs of the lane tests below: uniform numbers, directions on the sphere or the upper hemisphere, and
// sample numbers at the edges of [0, 1).
struct LaneInputs {
  uint32_t x;
  float uniform() { return float((x = x * 1664525u + 1013904223u) >> 8) * 0x1.0p-24f; }
  void direction(float* d, bool upper) {
    float z = upper ? uniform() : 2 * uniform() - 1, phi = 6.2831853f * uniform();
    float r = std::sqrt(std::max(0.0f, 1 - z * z));
    d[0] = r * std::cos(phi);
    d[1] = r * std::sin(phi);
    d[2] = z;
  }
};
const float kEdgeSamples[] = {0.0f, 0.5f, 0x1.fffffep-1f, 1e-7f};

}  // namespace

// The diffuse, Oren-Nayar and Phong lobes, written once over lanes (issue 15), give the one-lane bits (the
// path kernel's) at 16 and 8 lanes: both hemispheres for wo and wi, normal incidence (undefined azimuths),
// wi.z equal to wo.z, sigma 0 and rough, Phong exponents from 0.5 to 1000 and either lobe chosen, edge
// sample numbers, side by side in one vector.
TEST(BsdfLanes, LobesGiveTheOneLaneBits) {
  const size_t items = 32, lanes = 16 * items, results = 36;
  std::vector<float> in(17 * lanes);
  LaneInputs r{9001};
  auto uniform = [&] { return r.uniform(); };
  for (size_t j = 0; j < lanes; ++j) {
    float* v = &in[17 * j];
    for (int k = 0; k < 3; ++k) v[k] = uniform() * 0.6f;
    v[3] = j % 4 == 0 ? 0.0f : uniform() * 1.2f;
    r.direction(v + 4, j % 5 != 0);
    r.direction(v + 7, j % 3 != 0);
    if (j % 7 == 0) v[4] = 0, v[5] = 0, v[6] = 1;      // normal incidence: sin_o = 0
    if (j % 11 == 0) v[7] = 0, v[8] = 0, v[9] = 1;     // sin_i = 0
    if (j % 13 == 0) v[7] = -v[4], v[8] = v[5], v[9] = v[6];  // wi.z == wo.z
    if (j % 17 == 0) v[7] = -v[4], v[8] = -v[5], v[9] = v[6];  // wi the mirror direction of wo
    for (int k = 10; k < 13; ++k) v[k] = (j + k) % 6 == 0 ? kEdgeSamples[(j / 6 + k) % 4] : uniform();
    for (int k = 13; k < 16; ++k) v[k] = j % 8 == 0 ? 0.0f : uniform() * 0.4f;
    const float exponents[] = {0.5f, 1.0f, 20.0f, 1000.0f};
    v[16] = j % 3 == 0 ? exponents[j / 3 % 4] : 1 + uniform() * 200;
  }
  std::vector<uint32_t> bits = run_float_lanes_test("bsdf_lanes_test", in, items, 16 * results);
  LaneComparison lc = compare_lanes(bits, items, 16 * results, [](float f) { return bool(std::isfinite(f)); });
  EXPECT_EQ(lc.differing, 0u);
  EXPECT_GT(lc.valid, items * 16 * results * 9 / 10);  // the invalid samples' weights may be anything
  // The lobes did something at one lane: per lobe some eval is positive and some zero (wi below), and
  // Phong chose each of its two lobes (its sampled wi off and on the cosine lobe's).
  for (size_t lobe = 0; lobe < 3; ++lobe) {
    size_t positive = 0, zero = 0;
    for (size_t i = 0; i < items; ++i)
      for (size_t j = 0; j < 16; ++j) {
        float e;
        std::memcpy(&e, &bits[(3 * i + 2) * 16 * results + results * j + 12 * lobe], sizeof e);
        positive += e > 0;
        zero += e == 0;
      }
    EXPECT_GT(positive, lanes / 3) << "lobe " << lobe;
    EXPECT_GT(zero, lanes / 10) << "lobe " << lobe;
  }
  size_t specular_chosen = 0;
  for (size_t i = 0; i < items; ++i)
    for (size_t j = 0; j < 16; ++j) {
      const uint32_t* one = &bits[(3 * i + 2) * 16 * results + results * j];
      specular_chosen += one[4] != one[28];  // diffuse's cosine-lobe wi against Phong's
    }
  EXPECT_GT(specular_chosen, lanes / 20);
  EXPECT_LT(specular_chosen, lanes);
}

TEST(BsdfLanes, FresnelLobesGiveTheOneLaneBits) {
  // Mirror, dielectric, rough conductor and plastic (kernels/tests_sampling.cl, fresnel_lobes_lanes_test).
  const size_t items = 32, lanes = 16 * items, results = 56, lobe_results = 14;
  std::vector<float> in(20 * lanes);
  LaneInputs r{4242};
  auto uniform = [&] { return r.uniform(); };
  for (size_t j = 0; j < lanes; ++j) {
    float* v = &in[20 * j];
    for (int k = 0; k < 3; ++k) v[k] = j % 8 == 0 ? 0.0f : uniform() * 0.6f;  // black: the coat alone
    v[3] = j % 9 == 0 ? 1.0f : 1.1f + 1.4f * uniform();                      // ior 1: no Fresnel at all
    v[4] = j % 4 == 0 ? 0.0f : j % 4 == 1 ? 1e-4f : 0.01f + uniform();       // smooth, the smallest, rough
    for (int k = 5; k < 8; ++k) v[k] = 0.1f + 2 * uniform();
    for (int k = 8; k < 11; ++k) v[k] = 4 * uniform();
    if (j % 6 == 0) v[5] = 1, v[8] = 0;                                       // a "specular": 0 channel
    r.direction(v + 11, j % 3 != 0);                                            // inside the glass a third
    r.direction(v + 14, j % 5 != 0);
    if (j % 7 == 0) v[11] = 0, v[12] = 0, v[13] = j % 2 ? 1.0f : -1.0f;       // normal incidence
    if (j % 19 == 0) v[11] = 1, v[12] = 0, v[13] = 1e-7f;                     // grazing
    if (j % 13 == 0) v[14] = -v[11], v[15] = -v[12], v[16] = v[13];           // wi the mirror direction
    for (int k = 17; k < 20; ++k) v[k] = (j + k) % 6 == 0 ? kEdgeSamples[(j / 6 + k) % 4] : uniform();
  }
  std::vector<uint32_t> bits = run_float_lanes_test("fresnel_lobes_lanes_test", in, items, 16 * results);
  LaneComparison lc = compare_lanes(bits, items, 16 * results, [](float f) { return bool(std::isfinite(f)); });
  EXPECT_EQ(lc.differing, 0u);
  EXPECT_GT(lc.valid, items * 16 * results * 8 / 10);  // the invalid samples' values may be anything
  // What the lobes did at one lane: each case on either side of a per-lane branch occurs.
  auto one = [&](size_t lane, size_t lobe, size_t k) {
    float f;
    size_t at = (3 * (lane / 16) + 2) * 16 * results + results * (lane % 16) + lobe_results * lobe + k;
    std::memcpy(&f, &bits[at], sizeof f);
    return f;
  };
  size_t reflected = 0, refracted = 0, total_reflection = 0, coat_delta = 0, coat_rough = 0, base = 0;
  size_t conductor_positive = 0, conductor_zero = 0, plastic_positive = 0, plastic_zero = 0;
  for (size_t j = 0; j < lanes; ++j) {
    if (one(j, 1, 11) == 1) {
      bool refraction = one(j, 1, 13) != 1;
      refracted += refraction;
      reflected += !refraction;
      total_reflection += !refraction && one(j, 1, 7) == 1;
    }
    if (one(j, 3, 11) == 1) {  // the rough coat's wi is the rough conductor's (the same alpha, wo and u)
      bool delta = one(j, 3, 12) == 1, conductor_wi = one(j, 3, 4) == one(j, 2, 4) && one(j, 3, 6) == one(j, 2, 6);
      coat_delta += delta;
      coat_rough += !delta && conductor_wi;
      base += !delta && !conductor_wi;
    }
    conductor_positive += one(j, 2, 0) > 0;
    conductor_zero += one(j, 2, 0) == 0;
    plastic_positive += one(j, 3, 0) > 0;
    plastic_zero += one(j, 3, 0) == 0;
  }
  EXPECT_GT(reflected, lanes / 50);
  EXPECT_GT(refracted, lanes / 3);
  EXPECT_GT(total_reflection, 0u);
  EXPECT_GT(coat_delta, lanes / 50);
  EXPECT_GT(coat_rough, lanes / 50);
  EXPECT_GT(base, lanes / 3);
  EXPECT_GT(conductor_positive, lanes / 5);
  EXPECT_GT(conductor_zero, lanes / 10);
  EXPECT_GT(plastic_positive, lanes / 5);
  EXPECT_GT(plastic_zero, lanes / 10);
}

TEST(BsdfExact, FresnelDielectricMatchesSnellAndTheFresnelEquations) {
  const double ior = 1.5, critical = std::asin(1 / ior) / kDeg;  // 41.81 degrees
  std::vector<std::pair<float, float>> queries;
  std::vector<double> want;
  std::vector<std::string> names;
  // The reference takes the float cosine the kernel gets, so only the kernel's arithmetic is compared.
  auto add = [&](double theta, bool inside) {
    float c = float(std::cos(theta * kDeg));
    queries.push_back({c, inside ? float(1 / ior) : float(ior)});
    want.push_back(inside ? fresnel_reference(c, ior, 1) : fresnel_reference(c, 1, ior));
    names.push_back((inside ? "inside, theta " : "outside, theta ") + std::to_string(theta));
  };
  for (double t : {0.0, 10.0, 30.0, 45.0, 56.31, 60.0, 75.0, 85.0, 89.0, 89.9}) add(t, false);  // 56.31: Brewster
  for (double t : {0.0, 10.0, 20.0, 30.0, 33.69, 40.0, 41.5, critical - 0.05}) add(t, true);    // 33.69: Brewster
  for (double t : {critical + 0.05, 45.0, 60.0, 89.0}) add(t, true);                          // total reflection
  std::vector<float> got = run_fresnel_dielectric(queries);
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_NEAR(got[i], want[i], fresnel_tolerance(queries[i].first, queries[i].second)) << names[i];
  }
  // Normal incidence ((n - 1) / (n + 1))^2 = 0.04 from both sides; total internal reflection gives exactly 1.
  EXPECT_NEAR(got[0], 0.04, 1e-7);
  EXPECT_NEAR(got[10], 0.04, 1e-7);
  for (size_t i = got.size() - 4; i < got.size(); ++i) EXPECT_EQ(got[i], 1.0f) << names[i];
}

TEST(BsdfExact, FresnelConductorMatchesComplexFresnelEquations) {
  struct Metal {
    double eta[3], k[3];
  } metals[] = {{{0.18, 0.42, 1.37}, {3.42, 2.35, 1.77}},  // gold
                {{1, 1, 1}, {0.5, 2, 8}},
                {{2.5, 1.2, 0.05}, {0.1, 4.0, 1.0}}};
  std::vector<float> cos_i;
  for (double t : {0.0, 20.0, 45.0, 60.0, 80.0, 89.0}) cos_i.push_back(float(std::cos(t * kDeg)));
  for (const Metal& m : metals) {
    std::vector<pc_float4> got = run_fresnel_conductor(cos_i, f4(m.eta[0], m.eta[1], m.eta[2]), f4(m.k[0], m.k[1], m.k[2]));
    for (size_t i = 0; i < cos_i.size(); ++i) {
      float g[3] = {got[i].x, got[i].y, got[i].z};
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(g[c], conductor_reference(cos_i[i], m.eta[c], m.k[c]), 1e-5)
            << "eta " << m.eta[c] << " k " << m.k[c] << " cos " << cos_i[i];
        if (i == 0) {  // normal incidence in closed form
          double e = m.eta[c], k = m.k[c];
          EXPECT_NEAR(g[c], ((e - 1) * (e - 1) + k * k) / ((e + 1) * (e + 1) + k * k), 1e-6);
        }
      }
    }
  }
}

TEST(BsdfExact, SpecularColourOfARoughConductorIsItsNormalReflectance) {
  // scene_load.cpp turns "specular" r into eta = 1, k = 2 sqrt(r / (1 - r)); r = 1 is clamped to 0.9999.
  std::string scene = R"({"camera": {"position": [0, 0, 1], "look_at": [0, 0, 0], "width": 4, "height": 4},
    "materials": {"a": {"type": "rough_conductor", "roughness": 0.5, "specular": [0.04, 0.5, 0.95]},
                  "b": {"type": "rough_conductor", "roughness": 0.5, "specular": [0.0, 0.2, 1.0]}},
    "shapes": [{"type": "sphere", "radius": 1, "material": "a"}, {"type": "sphere", "radius": 1, "material": "b"}]})";
  DeviceScene s = load_device_scene(write_temp_file("specular.json", scene));
  ASSERT_EQ(s.materials.size(), 2u);
  const double want[2][3] = {{0.04, 0.5, 0.95}, {0.0, 0.2, 0.9999}};
  for (int i = 0; i < 2; ++i) {
    const Material& m = s.materials[i];
    EXPECT_EQ(m.type, PC_MAT_ROUGH_CONDUCTOR);
    pc_float4 r = run_fresnel_conductor({1.0f}, m.specular, m.k)[0];
    EXPECT_NEAR(r.x, want[i][0], 1e-5 + 1e-5 * want[i][0]);
    EXPECT_NEAR(r.y, want[i][1], 1e-5 * want[i][1] + 1e-6);
    EXPECT_NEAR(r.z, want[i][2], 1e-5 * want[i][2] + 1e-6);
  }
}

TEST(BsdfExact, MirrorReflectsExactly) {
  std::vector<pc_float4> u = lobe_choice_grid(16);
  for (glm::dvec3 wo : {direction(0), direction(35, 10), direction(89, 200), direction(120, 45)}) {
    Samples s = sample_bsdf(mirror(f4(0.9, 0.5, 0.25)), wo, 0, u.size(), u);
    glm::vec3 wof(wo);
    for (size_t i = 0; i < s.n; ++i) {
      ASSERT_EQ(s.status(i), 2) << "a mirror sample is a delta sample";
      EXPECT_EQ(s.wi(i), glm::dvec3(-wof.x, -wof.y, wof.z));
      EXPECT_EQ(s.pdf(i), 1.0);
      EXPECT_EQ(s.weight(i), glm::dvec3(0.9f, 0.5f, 0.25f));
      EXPECT_EQ(s.pdf_eval(i), 0.0);  // a delta lobe has no density for bsdf_pdf
      EXPECT_EQ(s.f(i), glm::dvec3(0.0));
    }
  }
}

TEST(BsdfExact, MetalMirrorReflectsItsFresnelTerm) {
  // A mirror with eta and k (Mitsuba's and pbrt's smooth conductor): the mirror direction, weight the
  // reflectance times the complex Fresnel equations at the incident angle, the conductor_reference.
  const double eta[3] = {0.18, 0.42, 1.37}, k[3] = {3.42, 2.35, 1.77}, rho[3] = {0.9, 0.8, 1.0};
  Material m = mirror(f4(rho[0], rho[1], rho[2]));
  m.specular = f4(eta[0], eta[1], eta[2]);
  m.k = f4(k[0], k[1], k[2]);
  std::vector<pc_float4> u = lobe_choice_grid(4);
  for (double theta : {0.0, 35.0, 70.0, 89.0}) {
    const glm::dvec3 wo = direction(theta, 20);
    Samples s = sample_bsdf(m, wo, 0, u.size(), u);
    const glm::vec3 wof(wo);
    for (size_t i = 0; i < s.n; ++i) {
      ASSERT_EQ(s.status(i), 2) << "a mirror sample is a delta sample";
      EXPECT_EQ(s.wi(i), glm::dvec3(-wof.x, -wof.y, wof.z));
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(s.weight(i)[c], rho[c] * conductor_reference(wof.z, eta[c], k[c]), 2e-5) << theta;
    }
  }
  // Loaded from a scene: eta and k go to the material; both are needed.
  const std::string scene = R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "width": 4, "height": 4},
    "materials": {"gold": {"type": "mirror", "eta": [0.18, 0.42, 1.37], "k": [3.42, 2.35, 1.77)";
  DeviceScene d = load_device_scene(write_temp_file("metal-mirror.json", scene + R"(]}},
    "shapes": [{"type": "sphere", "radius": 1, "material": "gold"}]})"));
  EXPECT_EQ(d.materials[0].type, PC_MAT_MIRROR);
  EXPECT_FLOAT_EQ(d.materials[0].specular.z, 1.37f);
  EXPECT_FLOAT_EQ(d.materials[0].k.x, 3.42f);
  try {
    load_scene(write_temp_file("metal-mirror.json", R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0],
      "width": 4, "height": 4}, "materials": {"gold": {"type": "mirror", "eta": [1, 1, 1]}}, "shapes": []})"));
    ADD_FAILURE() << "loaded";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("materials.gold: a metal mirror needs both eta and k"), std::string::npos)
        << e.what();
  }
}

TEST(BsdfExact, DielectricReflectsWithFresnelProbabilityAndRefractsBySnell) {
  const size_t grid = 4096;
  std::vector<pc_float4> u = lobe_choice_grid(grid);
  const glm::dvec3 tint(0.9, 0.8, 0.7);
  // Glass, and an ior below 1 (a bubble) where total internal reflection happens from the outside.
  for (double ior : {1.5, 0.75}) {
    double critical = std::asin(std::min(ior, 1 / ior)) / kDeg;
    double tir_theta = ior > 1 ? 180 - critical - 0.1 : critical + 0.1, edge_theta = ior > 1 ? 180 - critical + 0.1 : critical - 0.1;
    for (double theta : {0.0, 20.0, 45.0, 70.0, 88.0, 100.0, 120.0, 135.0, 150.0, 178.0, tir_theta, edge_theta}) {
      SCOPED_TRACE("ior " + std::to_string(ior) + " theta " + std::to_string(theta));
      glm::dvec3 wo = direction(theta, 40);
      glm::vec3 wof(wo);
      bool inside = wo.z < 0;
      double cos_i = std::abs(double(wof.z));
      double fr = inside ? fresnel_reference(cos_i, ior, 1) : fresnel_reference(cos_i, 1, ior);
      double eta = inside ? 1 / ior : ior;  // n_t / n_i
      double tol = fresnel_tolerance(cos_i, eta);
      Samples s = sample_bsdf(dielectric(float(ior), f4(tint.x, tint.y, tint.z)), wo, 0, grid, u);
      size_t reflected = 0;
      for (size_t i = 0; i < s.n; ++i) {
        ASSERT_EQ(s.status(i), 2);
        glm::dvec3 wi = s.wi(i);
        EXPECT_NEAR(glm::length(wi), 1, 2e-7);
        if (wi.z * wo.z > 0) {  // reflection: the mirror direction, chosen with probability F
          ++reflected;
          EXPECT_EQ(wi, glm::dvec3(-wof.x, -wof.y, wof.z));
          EXPECT_NEAR(s.pdf(i), fr, tol);
          EXPECT_NEAR(s.weight(i).x, 1, 1e-6);  // F / F
          EXPECT_NEAR(s.weight(i).z, 1, 1e-6);
        } else {  // refraction: opposite azimuth, sin_t = sin_i / eta, weight T / eta^2 (radiance scaling)
          double sin_i = std::sqrt(1 - cos_i * cos_i), sin_t = std::hypot(wi.x, wi.y);
          EXPECT_NEAR(sin_t, sin_i / eta, 1e-6);
          if (sin_i > 1e-6) {  // in the plane of incidence, on the far side of the normal
            double along = -(wi.x * wo.x + wi.y * wo.y) / (sin_t * std::hypot(wo.x, wo.y));
            EXPECT_NEAR(along, 1, 1e-6);
          }
          EXPECT_NEAR(s.pdf(i), 1 - fr, tol);
          for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.weight(i)[c], tint[c] / (eta * eta), 1e-6);
        }
      }
      // The lobe is chosen by u.z < F: over the grid the reflected fraction is F to within one grid step.
      EXPECT_NEAR(double(reflected) / grid, fr, 1.0 / grid) << "F " << fr;
      if (std::sqrt(1 - cos_i * cos_i) / eta >= 1) {  // total internal reflection
        EXPECT_EQ(fr, 1.0);
        EXPECT_EQ(reflected, grid);
      }
    }
  }
}

TEST(BsdfExact, SmoothPlasticCoatIsAFresnelWeightedMirror) {
  const double ior = 1.5;
  const size_t grid = 4096;
  std::vector<pc_float4> u = lobe_choice_grid(grid);
  for (double kd : {0.0, 0.3, 0.9})
    for (double theta : {0.0, 30.0, 60.0, 85.0, 110.0}) {
      SCOPED_TRACE("kd " + std::to_string(kd) + " theta " + std::to_string(theta));
      glm::dvec3 wo = direction(theta, -25);
      glm::vec3 wof(wo);
      double fr = fresnel_reference(std::abs(double(wof.z)), 1, ior);
      // The coat is chosen with probability F against (1 - F) times the base's largest reflectance.
      double pc = fr / (fr + (1 - fr) * kd);
      Samples s = sample_bsdf(plastic(f4(kd, 0.5 * kd, 0.2 * kd), 0, float(ior)), wo, 0, grid, u);
      size_t coat = 0;
      for (size_t i = 0; i < s.n; ++i) {
        if (s.status(i) != 2) continue;
        ++coat;
        EXPECT_EQ(s.wi(i), glm::dvec3(-wof.x, -wof.y, wof.z));
        EXPECT_NEAR(s.pdf(i), pc, 2e-6);
        EXPECT_NEAR(s.weight(i).x, fr / pc, 2e-6 * (1 + fr / pc));
        EXPECT_EQ(s.weight(i).x, s.weight(i).z);
      }
      EXPECT_NEAR(double(coat) / grid, pc, 1.0 / grid);
    }
}

// ---- Energy: white furnace and the Oren-Nayar albedo ----

namespace {

struct Albedo {
  glm::dvec3 mean{0}, std_error{0};
  size_t failed = 0;
};

// The directional albedo for wo: the mean sample weight (a failed sample counts as 0). With
// undo_radiance_scaling a transmitted weight is multiplied by eta^2 (n_t / n_i, as the dielectric
// divides by it), so that a lossless dielectric has albedo 1.
Albedo albedo(const Material& m, const glm::dvec3& wo, uint32_t seed, size_t n, bool undo_radiance_scaling = false) {
  Samples s = sample_bsdf(m, wo, seed, n);
  glm::dvec3 sum(0), sum2(0);
  Albedo a;
  for (size_t i = 0; i < n; ++i) {
    if (s.status(i) == 0) {
      ++a.failed;
      continue;
    }
    glm::dvec3 w = s.weight(i);
    if (undo_radiance_scaling && s.wi(i).z * wo.z < 0) {
      double eta = wo.z > 0 ? m.ior : 1 / double(m.ior);
      w *= eta * eta;
    }
    sum += w;
    sum2 += w * w;
  }
  a.mean = sum / double(n);
  a.std_error = glm::sqrt(glm::max(sum2 / double(n) - a.mean * a.mean, glm::dvec3(0)) / double(n - 1));
  return a;
}

std::vector<glm::dvec3> furnace_directions() {
  std::vector<glm::dvec3> wo;
  for (double t : {0.0, 5.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0, 89.0, 89.9}) wo.push_back(direction(t, 3 * t));
  for (double t : {100.0, 150.0, 180.0}) wo.push_back(direction(t, 71));  // back side
  return wo;
}

constexpr size_t kFurnaceSamples = 40000;

}  // namespace

TEST(BsdfExact, ThinDielectricReflectsItsBouncesAndPassesStraightThrough) {
  // Mitsuba's and pbrt's thin dielectric: reflected with R' = 2R / (1 + R) (the sheet's inner bounces
  // summed), else straight through, tinted; alike from both sides.
  const size_t grid = 4096;
  std::vector<pc_float4> u = lobe_choice_grid(grid);
  const glm::dvec3 tint(0.9, 0.8, 0.7);
  const Material m = thin_dielectric(1.5f, f4(tint.x, tint.y, tint.z));
  for (double theta : {0.0, 30.0, 60.0, 85.0, 120.0, 170.0}) {
    SCOPED_TRACE("theta " + std::to_string(theta));
    const glm::dvec3 wo = direction(theta, 25);
    const glm::vec3 wof(wo);
    const double cos_i = std::abs(double(wof.z));
    const double r = fresnel_reference(cos_i, 1, 1.5), want = 2 * r / (1 + r);
    Samples s = sample_bsdf(m, wo, 0, grid, u);
    size_t reflected = 0;
    for (size_t i = 0; i < s.n; ++i) {
      ASSERT_EQ(s.status(i), 2);
      const glm::dvec3 wi = s.wi(i);
      if (wi.z * wo.z > 0) {
        ++reflected;
        EXPECT_EQ(wi, glm::dvec3(-wof.x, -wof.y, wof.z));
        EXPECT_NEAR(s.pdf(i), want, 1e-5);
        EXPECT_EQ(s.weight(i), glm::dvec3(1.0));
      } else {
        EXPECT_EQ(wi, glm::dvec3(-wof.x, -wof.y, -wof.z));
        EXPECT_NEAR(s.pdf(i), 1 - want, 1e-5);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.weight(i)[c], tint[c], 1e-7);
      }
    }
    EXPECT_NEAR(double(reflected) / grid, want, 1.0 / grid);
  }
}

TEST(BsdfEnergy, LosslessMaterialsReflectEverything) {
  struct Case {
    const char* name;
    Material m;
    bool undo_radiance_scaling;
  } cases[] = {
      {"diffuse rho 1", diffuse(grey(1)), false},
      {"oren_nayar sigma 0 rho 1", oren_nayar(grey(1), 0), false},
      {"mirror rho 1", mirror(grey(1)), false},
      {"dielectric ior 1.5", dielectric(1.5f, grey(1)), true},
      {"dielectric ior 1.33", dielectric(1.33f, grey(1)), true},
      {"thin dielectric ior 1.5", thin_dielectric(1.5f, grey(1)), false},
  };
  for (const Case& c : cases)
    for (const glm::dvec3& wo : furnace_directions()) {
      if (c.m.type == PC_MAT_MIRROR && wo.z == 0) continue;
      Albedo a = albedo(c.m, wo, 7, kFurnaceSamples, c.undo_radiance_scaling);
      // Every sample's weight is exactly 1 here: no statistical error, only float rounding.
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(a.mean[k], 1.0, 1e-5) << c.name << ", wo.z " << wo.z;
      EXPECT_EQ(a.failed, 0u) << c.name << ", wo.z " << wo.z;
    }
}

TEST(BsdfEnergy, NoMaterialReflectsMoreThanItReceives) {
  // White versions of every material; albedo <= 1 within 4 standard errors (one-sided), and 1e-6.
  std::vector<std::pair<std::string, Material>> materials = {
      {"oren_nayar sigma 20", oren_nayar(grey(1), 20)},
      {"oren_nayar sigma 60", oren_nayar(grey(1), 60)},
      {"oren_nayar sigma 90", oren_nayar(grey(1), 90)},
      {"phong .5 .5 n 1", phong(grey(0.5), grey(0.5), 1)},
      {"phong .1 .9 n 30", phong(grey(0.1), grey(0.9), 30)},
      {"phong 0 1 n 1000", phong(grey(0), grey(1), 1000)},
      {"plastic smooth", plastic(grey(1), 0)},
      {"plastic r .3", plastic(grey(1), 0.3)},
      {"plastic r 1", plastic(grey(1), 1)},
  };
  for (double r : {0.1, 0.5, 1.0})  // eta = 1, k = 200: reflects 0.9999 at normal incidence, more elsewhere
    materials.push_back({"rough_conductor r " + std::to_string(r), conductor(r, grey(1), grey(200))});
  for (const auto& [name, m] : materials)
    for (const glm::dvec3& wo : furnace_directions()) {
      Albedo a = albedo(m, wo, 11, kFurnaceSamples);
      for (int k = 0; k < 3; ++k)
        EXPECT_LE(a.mean[k], 1 + 4 * a.std_error[k] + 1e-6) << name << ", wo.z " << wo.z << " +- " << a.std_error[k];
    }
}

TEST(BsdfEnergy, PhongWithDiffusePlusSpecularOneIsLosslessAtNormalIncidence) {
  // At normal incidence the specular lobe (n + 2) / (2 pi) cos^n integrates against cos to exactly 1.
  for (auto [kd, n] : {std::pair{0.5, 1.0f}, {0.2, 10.0f}, {0.7, 100.0f}, {0.0, 1000.0f}}) {
    Albedo a = albedo(phong(grey(kd), grey(1 - kd), n), direction(0), 13, kFurnaceSamples);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(a.mean[k], 1.0, 4 * a.std_error[k] + 1e-6) << "kd " << kd << " n " << n;
    EXPECT_EQ(a.failed, 0u);
    // Away from the normal some of the lobe falls below the horizon: strictly less than 1.
    Albedo b = albedo(phong(grey(kd), grey(1 - kd), n), direction(80), 13, kFurnaceSamples);
    if (kd < 0.5) {
      EXPECT_LT(b.mean.x + 4 * b.std_error.x, 1.0) << "kd " << kd << " n " << n;
    }
  }
}

namespace {

// Directional albedo of the qualitative Oren-Nayar model (pbrt-v3) in closed form. With
// f = rho / pi (A + B max(0, cos(phi_i - phi_o)) sin(alpha) tan(beta)), alpha = max, beta = min of the
// two polar angles, the azimuthal integral of max(0, cos) is 2 and the polar one splits at theta_o:
//   theta_i < theta_o: sin(theta_o) int_0^theta_o sin^2 = sin(theta_o) (theta_o / 2 - sin(2 theta_o) / 4)
//   theta_i > theta_o: tan(theta_o) int_theta_o^(pi/2) sin^2 cos = tan(theta_o) (1 - sin^3(theta_o)) / 3
double oren_nayar_albedo(double rho, double sigma, double theta_o) {
  double s2 = sigma * sigma, a = 1 - s2 / (2 * (s2 + 0.33)), b = 0.45 * s2 / (s2 + 0.09);
  double so = std::sin(theta_o);
  double tail = theta_o < M_PI / 2 ? std::tan(theta_o) * (1 - so * so * so) / 3 : 0;
  return rho * a + 2 * rho * b / M_PI * (so * (theta_o / 2 - std::sin(2 * theta_o) / 4) + tail);
}

// The same integral by brute-force quadrature of the model, to check the closed form itself.
double oren_nayar_albedo_quadrature(double rho, double sigma, double theta_o) {
  double s2 = sigma * sigma, a = 1 - s2 / (2 * (s2 + 0.33)), b = 0.45 * s2 / (s2 + 0.09);
  const int nt = 2000, np = 400;
  double sum = 0;
  for (int i = 0; i < nt; ++i) {
    double ti = (i + 0.5) * (M_PI / 2) / nt;
    for (int j = 0; j < np; ++j) {
      double dphi = (j + 0.5) * 2 * M_PI / np;
      double alpha = std::max(ti, theta_o), beta = std::min(ti, theta_o);
      double f = rho / M_PI * (a + b * std::max(0.0, std::cos(dphi)) * std::sin(alpha) * std::tan(beta));
      sum += f * std::cos(ti) * std::sin(ti);
    }
  }
  return sum * (M_PI / 2 / nt) * (2 * M_PI / np);
}

}  // namespace

TEST(BsdfEnergy, OrenNayarAlbedoMatchesItsClosedForm) {
  const double rho = 0.8;
  for (double sigma_deg : {0.0, 20.0, 60.0, 90.0})
    for (double theta_deg : {0.0, 20.0, 45.0, 70.0, 85.0}) {
      double sigma = sigma_deg * kDeg, theta = theta_deg * kDeg;
      double exact = oren_nayar_albedo(rho, sigma, theta);
      ASSERT_NEAR(exact, oren_nayar_albedo_quadrature(rho, sigma, theta), 1e-4) << "the closed form itself";
      Albedo a = albedo(oren_nayar(grey(rho), sigma_deg), direction(theta_deg, 50), 17, kFurnaceSamples);
      EXPECT_NEAR(a.mean.x, exact, 4 * a.std_error.x + 1e-6)
          << "sigma " << sigma_deg << " theta_o " << theta_deg << " +- " << a.std_error.x;
    }
}
