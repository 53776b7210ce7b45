// Spectra of imported scenes as linear sRGB (scene/spectrum.cpp) against closed forms: Mitsuba 3's RGB
// conventions, whose tables scripts/make-spectral-tables writes.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "scene/spectrum.h"

namespace {

void expect_grey(const glm::dvec3& rgb, double value, double tolerance) {
  EXPECT_NEAR(rgb.x, value, tolerance);
  EXPECT_NEAR(rgb.y, value, tolerance);
  EXPECT_NEAR(rgb.z, value, tolerance);
}

}  // namespace

TEST(Spectrum, AFlatReflectanceStaysFlat) {
  // Weighted by D65, whose colour is sRGB's white: a flat reflectance r is the grey r, within the
  // 1000-point sum's error.
  for (double r : {0.0, 0.25, 0.5, 1.0}) expect_grey(reflectance_spectrum_to_srgb({360, 830}, {r, r}), r, 2e-3 * r + 1e-12);
  // Given at many wavelengths, linear in between: the same.
  std::vector<double> w, v;
  for (double nm = 300; nm <= 900; nm += 7) {
    w.push_back(nm);
    v.push_back(0.3);
  }
  expect_grey(reflectance_spectrum_to_srgb(w, v), 0.3, 1e-3);
}

TEST(Spectrum, D65IsWhiteAndAFlatEmissionIsMitsubasPurple) {
  expect_grey(d65_to_srgb(), 1.0, 2e-3);
  // The equal-energy spectrum has XYZ (1, 1, 1) (normalised to luminance 1), which is not sRGB's white:
  // its RGB is the sum of each row of the XYZ-to-sRGB matrix.
  const glm::dvec3 e = uniform_emission_to_srgb(2.0);
  EXPECT_NEAR(e.x, 2 * (3.240479 - 1.537150 - 0.498535), 1e-6);
  EXPECT_NEAR(e.y, 2 * (-0.969256 + 1.875991 + 0.041556), 1e-6);
  EXPECT_NEAR(e.z, 2 * (0.055648 - 0.204043 + 1.057311), 1e-6);
  // The same spectrum given as a list: within the sum's and the tables' error.
  const glm::dvec3 listed = emission_spectrum_to_srgb({360, 830}, {2, 2});
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(listed[c], e[c], 0.01 * e[c]);
}

TEST(Spectrum, OutOfRangeColoursAreClampedAndSaid) {
  bool clamped = false;
  // A narrow green line: outside sRGB's gamut (negative red and blue), and above 1 as a reflectance.
  glm::dvec3 g = reflectance_spectrum_to_srgb({520, 530, 540}, {0, 50, 0}, &clamped);
  EXPECT_TRUE(clamped);
  EXPECT_EQ(g.x, 0);
  EXPECT_EQ(g.y, 1);
  EXPECT_EQ(g.z, 0);
  glm::dvec3 e = emission_spectrum_to_srgb({520, 530, 540}, {0, 50, 0}, &clamped);
  EXPECT_TRUE(clamped);
  EXPECT_EQ(e.x, 0);
  EXPECT_GT(e.y, 1);  // an emission is not bounded above
  reflectance_spectrum_to_srgb({360, 830}, {0.5, 0.5}, &clamped);
  EXPECT_FALSE(clamped);
}

TEST(Spectrum, BlackbodiesFollowTheirTemperature) {
  // Normalised as pbrt normalises them (peak 1): a 6504 K body is close to D65's white, a 2700 K one
  // (a tungsten lamp) red over blue, a 10000 K one blue over red.
  const glm::dvec3 white = normalized_blackbody_to_srgb(6504);
  EXPECT_NEAR(white.x / white.y, 1, 0.1);
  EXPECT_NEAR(white.z / white.y, 1, 0.1);
  const glm::dvec3 warm = normalized_blackbody_to_srgb(2700), cold = normalized_blackbody_to_srgb(10000);
  EXPECT_GT(warm.x, 1.5 * warm.z);
  EXPECT_GT(cold.z, 1.2 * cold.x);
  // Planck's law unnormalised (Mitsuba's units, W m^-2 sr^-1 nm^-1): the ratio of the two is the peak.
  const glm::dvec3 planck = blackbody_to_srgb(6504);
  const double c = 2.99792458e8, h = 6.62607004e-34, k = 1.38064852e-23, peak = 2.8977721e-3 / 6504;
  const double peak_radiance = 2 * h * c * c / std::pow(peak, 5) / std::expm1(h * c / (k * peak * 6504)) * 1e-9;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(planck[i] / white[i], peak_radiance, 1e-9 * peak_radiance);
}

TEST(Spectrum, NamedMaterials) {
  glm::dvec3 eta, k;
  ASSERT_TRUE(named_conductor("Au", &eta, &k));
  // Gold: its reflectance at normal incidence ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2) is yellow.
  auto normal_reflectance = [&](int c) {
    return ((eta[c] - 1) * (eta[c] - 1) + k[c] * k[c]) / ((eta[c] + 1) * (eta[c] + 1) + k[c] * k[c]);
  };
  EXPECT_GT(normal_reflectance(0), 0.85);
  EXPECT_LT(normal_reflectance(2), 0.6);
  ASSERT_TRUE(named_conductor("none", &eta, &k));  // Mitsuba's perfect mirror
  EXPECT_EQ(normal_reflectance(1), 1);
  EXPECT_FALSE(named_conductor("Unobtainium", &eta, &k));
  EXPECT_NE(named_conductor_list().find("Ag"), std::string::npos);
  double ior = 0;
  ASSERT_TRUE(named_ior("BK7", &ior));
  EXPECT_FLOAT_EQ(ior, 1.5046f);
  ASSERT_TRUE(named_ior("water ice", &ior));
  EXPECT_FLOAT_EQ(ior, 1.31f);
  EXPECT_FALSE(named_ior("glass", &ior));
  EXPECT_NE(named_ior_list().find("diamond"), std::string::npos);
}
