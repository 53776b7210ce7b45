// Error metrics of a rendered image against a reference, for `pathcl compare` and tests.
#pragma once
#include <cstddef>

#include "runtime/image_io.h"

struct ImageErrors {
  size_t pixels = 0;  // pixels compared (the masked-in ones)
  // Means over the compared pixels and the 3 channels, d = test - reference:
  double rmse = 0;     // sqrt(mean d^2)
  double rel_mse = 0;  // mean d^2 / (reference^2 + 0.01)
  double mae = 0;      // mean |d|
  double bias[3] = {};  // per channel: mean d
  double mean_reference[3] = {}, mean_test[3] = {};
  // Per-pixel z-test against test.variance (only when the test image carries one): a pixel fails if
  // any channel has |d| / sqrt(variance) > z_threshold; with variance 0 it fails iff d != 0.
  bool has_z_test = false;
  double z_fail_fraction = 0;  // failing pixels / pixels; 0 without a z-test
  double z_threshold = 0;
};

// Compares test against reference over the pixels whose mask R value is > 0 (all pixels without a
// mask). UsageError if the sizes of the images (or of the mask) differ, if no pixel is compared, or
// if either image has non-finite values (or test.variance non-finite or negative ones) among the
// compared pixels.
ImageErrors compare_images(const Image& reference, const Image& test, const Image* mask, double z_threshold = 3.29);
