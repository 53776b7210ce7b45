// The film as the host keeps it: every layer's words (runtime/film_layout.h), and the images developed
// from them.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/film_layout.h"

// Per pixel RGB, row 0 at the top.
struct Film {
  uint32_t width = 0, height = 0, spp = 0;
  std::string technique = "path";  // the technique (runtime/technique.h) whose layers come first
  FilmLayout layout;
  std::vector<uint32_t> words;     // every layer's plane at its offset in layout
  // Developed by the technique (Technique::develop) and develop_aovs:
  std::vector<float> mean;      // the mean of all samples
  std::vector<float> variance;  // the estimated variance of that mean (sample variance / spp)
  std::vector<float> even_mean, odd_mean;  // means of the even- and odd-numbered samples
  struct Aov {
    uint32_t aov = 0;             // PC_AOV_*
    std::vector<float> values;    // aov_info(aov).words per pixel
  };
  std::vector<Aov> aovs;          // in layout order

  // The plane of layer i.
  const uint32_t* layer(size_t i) const { return words.data() + layout.offset(i); }
};

// A cleared film of this layout.
Film make_film(uint32_t width, uint32_t height, const std::string& technique, const FilmLayout& layout);

// The path integrator's `radiance` layer (PC_RADIANCE_WORDS a pixel: even-sample sum and count, odd-sample
// sum and count, sum of squares) as means and variances; its spp from the counts.
void develop_radiance(Film& film);
// Each AOV layer as the mean over film.spp samples (ids as they are).
void develop_aovs(Film& film);

// The relative MSE of the film's mean, estimated from the difference of its two half images:
// mean over pixels and channels of E[(even - odd)^2] scaled to one full mean, over (mean^2 + 0.01).
double estimated_rel_mse(const Film& film);
