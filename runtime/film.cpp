#include "runtime/film.h"

#include <algorithm>
#include <cstring>

Film make_film(uint32_t width, uint32_t height, const std::string& technique, const FilmLayout& layout) {
  Film f;
  f.width = width;
  f.height = height;
  f.technique = technique;
  f.layout = layout;
  f.words.assign(layout.total_words(), 0u);
  return f;
}

void develop_radiance(Film& f) {
  size_t pixels = size_t(f.width) * f.height;
  f.mean.assign(3 * pixels, 0.0f);
  f.variance.assign(3 * pixels, 0.0f);
  f.even_mean.assign(3 * pixels, 0.0f);
  f.odd_mean.assign(3 * pixels, 0.0f);
  const uint32_t* plane = f.layer(size_t(f.layout.find("radiance")));
  for (size_t p = 0; p < pixels; ++p) {
    float acc[PC_RADIANCE_WORDS];
    std::memcpy(acc, plane + PC_RADIANCE_WORDS * p, sizeof acc);
    const float *e = acc, *o = acc + 4, *s = acc + 8;  // even sum and count, odd sum and count, squares
    double n = double(e[3]) + o[3];
    f.spp = uint32_t(n);
    for (int c = 0; c < 3; ++c) {
      double sum = double(e[c]) + o[c];
      double mean = n > 0 ? sum / n : 0;
      f.mean[3 * p + c] = float(mean);
      f.even_mean[3 * p + c] = e[3] > 0 ? e[c] / e[3] : 0.0f;
      f.odd_mean[3 * p + c] = o[3] > 0 ? o[c] / o[3] : 0.0f;
      double sample_variance = n > 1 ? std::max(0.0, (s[c] - sum * mean) / (n - 1)) : 0.0;
      f.variance[3 * p + c] = float(n > 0 ? sample_variance / n : 0.0);
    }
  }
}

void develop_aovs(Film& f) {
  f.aovs.clear();
  size_t pixels = size_t(f.width) * f.height;
  for (uint32_t a = 0; a < PC_AOV_COUNT; ++a) {
    const AovInfo& info = aov_info(a);
    int i = f.layout.find(info.name);
    if (i < 0) continue;
    Film::Aov out;
    out.aov = a;
    out.values.resize(pixels * info.words);
    const uint32_t* plane = f.layer(size_t(i));
    for (size_t k = 0; k < out.values.size(); ++k) {
      if (info.id) {
        out.values[k] = float(plane[k]);
      } else {
        float sum;
        std::memcpy(&sum, plane + k, sizeof sum);
        out.values[k] = f.spp > 0 ? float(double(sum) / f.spp) : 0.0f;
      }
    }
    f.aovs.push_back(std::move(out));
  }
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
