// Spectra as linear sRGB by Mitsuba 3's conventions (scene/spectrum.h).
#include "scene/spectrum.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <glm/common.hpp>

#include "scene/spectral_tables.h"

namespace {

using namespace spectral_tables;

// A table of kCieSamples entries evaluated at `nm`, linear between its wavelengths, 0 outside them
// (Mitsuba's cie1931_xyz and cie_d65).
double table_at(const float* table, double nm) {
  if (!(nm >= kCieMin && nm <= kCieMax)) return 0;
  double t = (nm - kCieMin) * ((kCieSamples - 1) / (kCieMax - kCieMin));
  int i0 = std::clamp(int(t), 0, kCieSamples - 2);
  double w1 = t - i0;
  return (1 - w1) * table[i0] + w1 * table[i0 + 1];
}

glm::dvec3 xyz_to_srgb(glm::dvec3 xyz) {
  // Mitsuba's matrix (ITU-R BT.709 primaries, D65 white), as floats.
  return {3.240479f * xyz.x - 1.537150f * xyz.y - 0.498535f * xyz.z,
          -0.969256f * xyz.x + 1.875991f * xyz.y + 0.041556f * xyz.z,
          0.055648f * xyz.x - 0.204043f * xyz.y + 1.057311f * xyz.z};
}

// Mitsuba's spectrum_list_to_srgb: the spectrum, linear between its entries and 0 outside them, times
// the colour matching functions (and D65 for a reflectance), summed at 1000 wavelengths across
// [kCieMin, kCieMax] and normalised so that a constant 1 has luminance 1.
glm::dvec3 spectrum_to_xyz(const std::vector<double>& wavelengths, const std::vector<double>& values, bool d65) {
  constexpr int kSteps = 1000;
  glm::dvec3 xyz(0);
  size_t index = 0;
  for (int i = 0; i < kSteps; ++i) {
    double w = kCieMin + (i / double(kSteps - 1)) * (kCieMax - kCieMin);
    if (w < wavelengths.front() || w > wavelengths.back()) continue;
    double v = values.front();
    if (wavelengths.size() > 1) {
      while (index + 2 < wavelengths.size() && wavelengths[index + 1] <= w) ++index;
      double w0 = wavelengths[index], w1 = wavelengths[index + 1];
      v = ((w - w1) * values[index] + (w0 - w) * values[index + 1]) / (w0 - w1);
    }
    double weight = v * (d65 ? table_at(kD65, w) : 1.0);
    xyz += weight * glm::dvec3(table_at(kCieX, w), table_at(kCieY, w), table_at(kCieZ, w));
  }
  return xyz * ((kCieMax - kCieMin) * kCieYNormalization / kSteps);
}

glm::dvec3 clamp_into(glm::dvec3 rgb, double hi, bool* clamped) {
  glm::dvec3 c = glm::clamp(rgb, glm::dvec3(0), glm::dvec3(hi));
  if (clamped) *clamped = c != rgb;
  return c;
}

// Planck's law in W m^-2 sr^-1 nm^-1 at `nm` (the constants of Mitsuba's blackbody spectrum).
double planck(double nm, double kelvin) {
  const double c = 2.99792458e8, h = 6.62607004e-34, k = 1.38064852e-23;
  const double lambda = nm * 1e-9;
  return 2 * h * c * c / std::pow(lambda, 5) / std::expm1(h * c / (k * lambda * kelvin)) * 1e-9;
}

glm::dvec3 blackbody(double kelvin, double scale) {
  std::vector<double> wavelengths, values;
  for (double nm = kCieMin; nm <= kCieMax; nm += 1) {
    wavelengths.push_back(nm);
    values.push_back(planck(nm, kelvin) * scale);
  }
  return emission_spectrum_to_srgb(wavelengths, values);
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Mitsuba's named indices of refraction (mitsuba/render/ior.h, from Hecht, Optics: 0 to 20 degrees
// Celsius at about 589 nm).
struct NamedIor {
  const char* name;
  float ior;
};
constexpr NamedIor kIors[] = {
    {"vacuum", 1.0f}, {"helium", 1.000036f}, {"hydrogen", 1.000132f}, {"air", 1.000277f},
    {"carbon dioxide", 1.00045f}, {"water", 1.3330f}, {"acetone", 1.36f}, {"ethanol", 1.361f},
    {"carbon tetrachloride", 1.461f}, {"glycerol", 1.4729f}, {"benzene", 1.501f}, {"silicone oil", 1.52045f},
    {"bromine", 1.661f}, {"water ice", 1.31f}, {"fused quartz", 1.458f}, {"pyrex", 1.470f},
    {"acrylic glass", 1.49f}, {"polypropylene", 1.49f}, {"bk7", 1.5046f}, {"sodium chloride", 1.544f},
    {"amber", 1.55f}, {"pet", 1.5750f}, {"diamond", 2.419f}};

}  // namespace

glm::dvec3 reflectance_spectrum_to_srgb(const std::vector<double>& wavelengths, const std::vector<double>& values,
                                        bool* clamped) {
  return clamp_into(xyz_to_srgb(spectrum_to_xyz(wavelengths, values, true)), 1.0, clamped);
}

glm::dvec3 emission_spectrum_to_srgb(const std::vector<double>& wavelengths, const std::vector<double>& values,
                                     bool* clamped) {
  return clamp_into(xyz_to_srgb(spectrum_to_xyz(wavelengths, values, false)), HUGE_VAL, clamped);
}

glm::dvec3 uniform_emission_to_srgb(double v) { return v * xyz_to_srgb(glm::dvec3(1)); }

glm::dvec3 blackbody_to_srgb(double kelvin) { return blackbody(kelvin, 1.0); }

glm::dvec3 normalized_blackbody_to_srgb(double kelvin) {
  const double peak_nm = 2.8977721e-3 / kelvin * 1e9;  // Wien's displacement law
  return blackbody(kelvin, 1.0 / planck(peak_nm, kelvin));
}

glm::dvec3 d65_to_srgb() {
  std::vector<double> wavelengths, values;
  for (int i = 0; i < kCieSamples; ++i) {
    wavelengths.push_back(kCieMin + i * (kCieMax - kCieMin) / (kCieSamples - 1));
    values.push_back(kD65[i]);
  }
  return emission_spectrum_to_srgb(wavelengths, values);
}

bool named_conductor(const std::string& name, glm::dvec3* eta, glm::dvec3* k) {
  if (name == "none") {  // Mitsuba's default: a perfect mirror
    *eta = glm::dvec3(0);
    *k = glm::dvec3(1);
    return true;
  }
  for (const NamedConductor& c : kConductors) {
    if (name == c.name) {
      *eta = glm::dvec3(c.eta[0], c.eta[1], c.eta[2]);
      *k = glm::dvec3(c.k[0], c.k[1], c.k[2]);
      return true;
    }
  }
  return false;
}

std::string named_conductor_list() {
  std::string list = "none";
  for (const NamedConductor& c : kConductors) list += std::string(", ") + c.name;
  return list;
}

bool named_ior(const std::string& name, double* ior) {
  const std::string key = lower(name);
  for (const NamedIor& n : kIors) {
    if (key == n.name) {
      *ior = n.ior;
      return true;
    }
  }
  return false;
}

std::string named_ior_list() {
  std::string list;
  for (const NamedIor& n : kIors) list += (list.empty() ? "" : ", ") + std::string(n.name);
  return list;
}
