#include "runtime/image_compare.h"

#include <cmath>
#include <string>

#include "runtime/errors.h"

namespace {

std::string size_text(const Image& image) { return std::to_string(image.width) + "x" + std::to_string(image.height); }

}  // namespace

ImageErrors compare_images(const Image& reference, const Image& test, const Image* mask, double z_threshold) {
  if (reference.width != test.width || reference.height != test.height)
    throw UsageError("image sizes differ: " + size_text(reference) + " vs " + size_text(test));
  if (mask && (mask->width != reference.width || mask->height != reference.height))
    throw UsageError("mask size differs: " + size_text(*mask) + " vs " + size_text(reference));
  size_t n = size_t(reference.width) * reference.height;
  bool z_test = !test.variance.empty();
  if (z_test && test.variance.size() != n * 3)
    throw UsageError("the test image's variance has " + std::to_string(test.variance.size()) + " values, expected " +
                     std::to_string(n * 3));

  ImageErrors e;
  e.has_z_test = z_test;
  e.z_threshold = z_threshold;
  // Sums in double: a float sum over millions of pixels would lose the small errors we measure.
  double sum_sq = 0, sum_rel = 0, sum_abs = 0, sum_d[3] = {}, sum_r[3] = {}, sum_t[3] = {};
  size_t bad_reference = 0, bad_test = 0, bad_variance = 0, z_failures = 0;
  for (size_t p = 0; p < n; ++p) {
    if (mask && !(mask->rgb[3 * p] > 0)) continue;
    ++e.pixels;
    bool fails = false;
    for (int c = 0; c < 3; ++c) {
      double r = reference.rgb[3 * p + c], t = test.rgb[3 * p + c];
      bool ok = std::isfinite(r) && std::isfinite(t);
      bad_reference += !std::isfinite(r);
      bad_test += !std::isfinite(t);
      if (!ok) continue;  // the error below is thrown after counting them all
      double d = t - r;
      sum_sq += d * d;
      sum_rel += d * d / (r * r + 0.01);
      sum_abs += std::abs(d);
      sum_d[c] += d;
      sum_r[c] += r;
      sum_t[c] += t;
      if (z_test) {
        double var = test.variance[3 * p + c];
        if (!std::isfinite(var) || var < 0) {
          ++bad_variance;
          continue;
        }
        // With zero variance the estimate claims to be exact, so any difference is a failure.
        fails |= var == 0 ? d != 0 : std::abs(d) > z_threshold * std::sqrt(var);
      }
    }
    z_failures += fails;
  }
  if (bad_reference + bad_test + bad_variance > 0)
    throw UsageError(std::to_string(bad_reference) + " non-finite values in the reference image, " +
                     std::to_string(bad_test) + " in the test image, " + std::to_string(bad_variance) +
                     " non-finite or negative variance values");
  if (e.pixels == 0) throw UsageError(mask ? "the mask selects no pixels" : "the images have no pixels");

  double count = 3.0 * e.pixels;
  e.rmse = std::sqrt(sum_sq / count);
  e.rel_mse = sum_rel / count;
  e.mae = sum_abs / count;
  for (int c = 0; c < 3; ++c) {
    e.bias[c] = sum_d[c] / e.pixels;
    e.mean_reference[c] = sum_r[c] / e.pixels;
    e.mean_test[c] = sum_t[c] / e.pixels;
  }
  e.z_fail_fraction = z_test ? double(z_failures) / e.pixels : 0;
  return e;
}
