// Chi-square goodness-of-fit machinery of the sampling tests: binning directions on the sphere,
// integrating a claimed density over the bins adaptively (the integral runs on the device, see
// kernels/tests_sampling.cl), pooling sparse cells and the p-value (Boost's regularised gamma).
#pragma once
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "kernels/shared/types.h"

// Directions binned in a frame: theta from axis z in [0, theta_max] (theta_bins), phi = atan2(along y,
// along x) in [0, 2 pi) (phi_bins); bin t * phi_bins + p. The default covers the whole sphere about +z.
struct SphereBinning {
  uint32_t theta_bins = 80, phi_bins = 160;
  double theta_max = M_PI;
  glm::dvec3 x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
  uint32_t count() const { return theta_bins * phi_bins; }
  uint32_t bin_of(const glm::dvec3& d) const;  // count() beyond theta_max
  // The frame and sizes as the test kernels take them (kernels/tests_sampling.cl).
  std::vector<pc_float4> device_params() const;
  // A frame about the given axis.
  static SphereBinning about(const glm::dvec3& axis, double theta_max);
};

// Gauss-Legendre nodes and weights of the given order on [0, 1], in double precision.
void gauss_legendre01(int order, std::vector<double>& nodes, std::vector<double>& weights);

// Integrates a density over bins. integrate(bins, order) returns, per listed bin, its integral by an
// order x order Gauss-Legendre rule and whether the density was 0 at some of its nodes and not at others
// (an edge crosses the bin). Every bin starts at orders 4 and 8; a bin whose two estimates of the
// expected count (samples x integral) differ by more than tolerance x sqrt(max(count, 1)), or with an
// edge below order 64 (where two low orders can agree by chance), is redone at double the order, up to
// max_order. The result holds the highest-order values.
struct BinIntegrals {
  std::vector<double> value;
  int highest_order = 0;  // the highest order any bin needed
  size_t unconverged = 0; // bins still above the tolerance at max_order
  double worst = 0;       // largest |difference| / sqrt(max(count, 1)) of the last two orders over bins
};
struct BinValues {
  std::vector<float> integral;
  std::vector<uint8_t> edge;
};
using BinIntegrator = std::function<BinValues(const std::vector<uint32_t>& bins, int order)>;
// Unpacks the (integral, edge flag) float pairs the test kernels write.
BinValues bin_values(const std::vector<float>& pairs);
BinIntegrals integrate_bins(const BinIntegrator& integrate, uint32_t bin_count, double samples,
                            double tolerance = 0.1, int max_order = 128);

// Expected counts of `samples` samples: samples times each bin's integral, and a last cell for the mass
// the density lacks (failed or delta samples). *pdf_total gets the sum of the integrals.
std::vector<double> expected_counts(const BinIntegrals& integrals, double samples, double* pdf_total);

// Pearson's chi-square of observed against expected counts (same total). Cells expected below
// min_expected are pooled into one cell (with the smallest other cells until it reaches
// min_expected). zero_cells_hit counts observations in cells whose expected count is exactly 0; they
// are part of the pooled cell.
struct Chi2Result {
  double chi2 = 0, p_value = 1;
  int dof = 0;
  size_t cells = 0, pooled_cells = 0;
  double zero_cells_hit = 0;
  struct Cell {
    size_t index;  // into observed; SIZE_MAX for the pooled cell
    double observed, expected;
  };
  std::vector<Cell> worst;  // the cells that add most to chi2, largest first (up to 5)
  std::string describe() const;                // the statistic
  std::string describe_worst() const;          // and the worst cells, for failure messages
};
Chi2Result chi2_test(const std::vector<double>& observed, const std::vector<double>& expected,
                     double min_expected = 5);

// Per-test significance for `tests` tests at family-wise significance alpha (Sidak).
double sidak_alpha(double alpha, int tests);

// "integral I, sampled S, quadrature order <= O": a density run's line after its statistic.
std::string run_detail(double pdf_total, double sampled_fraction, int highest_order);

// The runs of one test family, each checked at the Sidak-corrected significance of a 1 % family-wise
// level; the summary gives the smallest p-value.
struct Chi2Family {
  explicit Chi2Family(size_t runs);
  // Prints the run's line (name, p, statistic, then `detail`) and expects p >= alpha.
  void expect_fit(const std::string& name, const Chi2Result& chi2, const std::string& detail);
  void print_summary() const;
  size_t runs;
  double alpha;
  double min_p = 1;
};
