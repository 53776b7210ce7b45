#include "runtime/film.h"

#include <algorithm>

Film film_from_accumulators(uint32_t width, uint32_t height, std::vector<pc_float4> acc) {
  size_t pixels = size_t(width) * height;
  Film f;
  f.width = width;
  f.height = height;
  f.mean.resize(3 * pixels);
  f.variance.resize(3 * pixels);
  f.even_mean.resize(3 * pixels);
  f.odd_mean.resize(3 * pixels);
  for (size_t p = 0; p < pixels; ++p) {
    const pc_float4 &even = acc[3 * p], &odd = acc[3 * p + 1], &sq = acc[3 * p + 2];
    double n = double(even.w) + odd.w;
    f.spp = uint32_t(n);
    const float e[3] = {even.x, even.y, even.z}, o[3] = {odd.x, odd.y, odd.z}, s[3] = {sq.x, sq.y, sq.z};
    for (int c = 0; c < 3; ++c) {
      double sum = double(e[c]) + o[c];
      double mean = n > 0 ? sum / n : 0;
      f.mean[3 * p + c] = float(mean);
      f.even_mean[3 * p + c] = even.w > 0 ? e[c] / even.w : 0.0f;
      f.odd_mean[3 * p + c] = odd.w > 0 ? o[c] / odd.w : 0.0f;
      double sample_variance = n > 1 ? std::max(0.0, (s[c] - sum * mean) / (n - 1)) : 0.0;
      f.variance[3 * p + c] = float(n > 0 ? sample_variance / n : 0.0);
    }
  }
  f.accumulators = std::move(acc);
  return f;
}

double estimated_rel_mse(const Film& film) {
  size_t n = film.mean.size();
  if (n == 0 || film.spp < 2) return 0;
  // With n_e even and n_o odd samples, Var(even - odd) = s^2 (1/n_e + 1/n_o) and Var(mean) = s^2 / n.
  double n_even = (film.spp + 1) / 2, n_odd = film.spp / 2;
  double scale = 1.0 / (film.spp * (1.0 / n_even + 1.0 / n_odd));
  double sum = 0;
  for (size_t i = 0; i < n; ++i) {
    double d = double(film.even_mean[i]) - film.odd_mean[i];
    double m = film.mean[i];
    sum += d * d * scale / (m * m + 0.01);
  }
  return sum / n;
}
