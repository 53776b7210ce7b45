// Spectra of Mitsuba and pbrt scene files as linear sRGB, by the conventions of Mitsuba 3's RGB variants
// (mitsuba/core/properties.cpp, spectrum.cpp), so that an imported scene looks as it does there:
// a reflectance is weighted by the D65 illuminant and clamped to [0, 1]; an emission (or an index of
// refraction) is integrated unweighted, negatives clamped to 0. The CIE 1931 tables and the named metals
// are generated from Mitsuba's own (scripts/make-spectral-tables, scene/spectral_tables.h).
#pragma once
#include <string>
#include <vector>

#include <glm/vec3.hpp>

// Wavelengths in nm, strictly increasing, at least one; values as many. Between two entries the
// spectrum is linear; outside them 0 (as Mitsuba integrates). *clamped (optional) is set when the result
// had to be clamped into range.
glm::dvec3 reflectance_spectrum_to_srgb(const std::vector<double>& wavelengths, const std::vector<double>& values,
                                        bool* clamped = nullptr);
glm::dvec3 emission_spectrum_to_srgb(const std::vector<double>& wavelengths, const std::vector<double>& values,
                                     bool* clamped = nullptr);
// A constant emission spectrum of value v (Mitsuba 3: v times xyz_to_srgb(1, 1, 1), a slightly purple
// colour, because sRGB's white is D65, not the equal-energy spectrum); a constant reflectance is v itself.
glm::dvec3 uniform_emission_to_srgb(double v);
// Planck's law at `kelvin` in W m^-2 sr^-1 nm^-1 (Mitsuba's blackbody units), as an emission.
glm::dvec3 blackbody_to_srgb(double kelvin);
// pbrt-v4's blackbody: the same spectrum normalised to 1 at its peak wavelength.
glm::dvec3 normalized_blackbody_to_srgb(double kelvin);
// The standard illuminant D65 (its table, normalised as Mitsuba's), as an emission: white.
glm::dvec3 d65_to_srgb();

// Mitsuba's named conductors ("Au", "Ag", "Cu", "Al", "Cr", ..., "none"): complex index eta + i k in
// linear sRGB, as Mitsuba's RGB variants compute them. False for an unknown name.
bool named_conductor(const std::string& name, glm::dvec3* eta, glm::dvec3* k);
// The names, for messages ("expected one of ...").
std::string named_conductor_list();
// Mitsuba's named indices of refraction ("bk7", "water", "air", ...; case-insensitive). False if unknown.
bool named_ior(const std::string& name, double* ior);
std::string named_ior_list();
