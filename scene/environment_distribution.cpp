#include "scene/environment_distribution.h"

#include <algorithm>
#include <cmath>

#include "scene/texture_load.h"

namespace {

// In double: an emission of 1e-45 in blue alone still has a (tiny) positive luminance.
double luminance(const glm::vec3& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

// A cdf as floats, its last entry exactly 1; an all-zero function gets a uniform cdf.
void write_cdf(const double* f, uint32_t n, double sum, float* cdf) {
  double running = 0;
  cdf[0] = 0;
  for (uint32_t i = 0; i < n; ++i) {
    running += sum > 0 ? f[i] / sum : 1.0 / n;
    cdf[i + 1] = i + 1 == n ? 1.0f : float(running);
  }
}

}  // namespace

double build_env_distribution(const TextureImage& map, std::vector<float>& dist, uint32_t mapping) {
  const uint32_t w = map.width, h = map.height;
  const bool equal_area = mapping != PC_ENV_LAT_LONG;
  std::vector<double> lum(size_t(w) * h);
  double integral = 0;
  for (uint32_t r = 0; r < h; ++r)
    for (uint32_t c = 0; c < w; ++c) {
      lum[size_t(r) * w + c] = luminance(texel_linear(map, size_t(r) * w + c));
      // Solid angle of the texel: 4 pi / (w h) on an equal-area map; (2 pi / w) (cos theta_top -
      // cos theta_bottom) on a lat-long one.
      if (equal_area)
        integral += lum[size_t(r) * w + c] * (4 * M_PI / (double(w) * h));
      else
        integral += lum[size_t(r) * w + c] * (2 * M_PI / w) * (std::cos(M_PI * r / h) - std::cos(M_PI * (r + 1) / h));
    }
  // Texel (r, c) under the map's wrapping, at most one texel beyond an edge. Lat-long: columns repeat, rows
  // clamp at the poles. Equal-area (kernels/environment.cl, env_octahedral_texel): beyond an edge, the
  // texel mirrored across the edge's middle.
  auto at = [&](int64_t r, int64_t c) {
    if (equal_area) {
      if (c < 0 || c >= w) {
        c = c < 0 ? -1 - c : 2 * int64_t(w) - 1 - c;
        r = h - 1 - r;
      }
      if (r < 0 || r >= h) {
        r = r < 0 ? -1 - r : 2 * int64_t(h) - 1 - r;
        c = w - 1 - c;
      }
    } else {
      r = std::clamp<int64_t>(r, 0, h - 1);
      c = ((c % w) + w) % w;
    }
    return lum[size_t(r) * w + size_t(c)];
  };
  // In the cell of texel (r, c) the lookup blends it with its 8 neighbours, one quadrant of the cell at a
  // time; a bilinear function is largest at a corner of its rectangle, so the cell's largest value is at
  // one of 9 points: the texel's centre, the middles of the cell's edges (half the texel, half the
  // neighbour) and its corners (a quarter of each of four texels). A nearest-texel lookup is the texel.
  std::vector<double> row_sum(h, 0.0), func(size_t(w) * h);
  double total = 0;
  for (uint32_t r = 0; r < h; ++r) {
    double sin_theta = equal_area ? 1.0 : std::sin(M_PI * (r + 0.5) / h);
    for (uint32_t c = 0; c < w; ++c) {
      double centre = at(r, c), largest = centre;
      if (mapping != PC_ENV_EQUAL_AREA_NEAREST) {
        for (int dr : {-1, 1}) largest = std::max(largest, 0.5 * (centre + at(int64_t(r) + dr, c)));
        for (int dc : {-1, 1}) largest = std::max(largest, 0.5 * (centre + at(r, int64_t(c) + dc)));
        for (int dr : {-1, 1})
          for (int dc : {-1, 1})
            largest = std::max(largest, 0.25 * (centre + at(int64_t(r) + dr, c) + at(r, int64_t(c) + dc) +
                                                at(int64_t(r) + dr, int64_t(c) + dc)));
      }
      func[size_t(r) * w + c] = largest * sin_theta;
      row_sum[r] += largest * sin_theta;
    }
    total += row_sum[r];
  }
  dist.assign(h + 1 + size_t(h) * (w + 1), 0.0f);
  write_cdf(row_sum.data(), h, total, dist.data());
  for (uint32_t r = 0; r < h; ++r) write_cdf(&func[size_t(r) * w], w, row_sum[r], &dist[h + 1 + size_t(r) * (w + 1)]);
  return integral;
}
