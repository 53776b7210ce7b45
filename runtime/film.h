// The film as the host keeps it: the accumulators of every pixel, and the images derived from them.
#pragma once
#include <cstdint>
#include <vector>

#include "kernels/shared/types.h"

// Per pixel RGB, row 0 at the top.
struct Film {
  uint32_t width = 0, height = 0, spp = 0;
  std::vector<float> mean;      // the mean of all samples
  std::vector<float> variance;  // the estimated variance of that mean (sample variance / spp)
  std::vector<float> even_mean, odd_mean;  // means of the even- and odd-numbered samples
  // The device's accumulators, 3 per pixel: even-sample sum (w: count), odd-sample sum, sum of squares.
  std::vector<pc_float4> accumulators;
  // Light-transport integrators instead (runtime/light_transport.h): PC_SPLAT_WORDS fixed-point sums per
  // pixel, added exactly from any number of devices and units; accumulators is then empty.
  std::vector<uint64_t> splats;
  uint32_t integrator = 0;  // PC_INTEGRATOR_* (kernels/shared/light_types.h) of the film: path unless splats
};

// Derives the means and variances from accumulators (3 per pixel).
Film film_from_accumulators(uint32_t width, uint32_t height, std::vector<pc_float4> accumulators);

// The relative MSE of the film's mean, estimated from the difference of its two half images:
// mean over pixels and channels of E[(even - odd)^2] scaled to one full mean, over (mean^2 + 0.01).
double estimated_rel_mse(const Film& film);
