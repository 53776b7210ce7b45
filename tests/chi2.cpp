#include "chi2.h"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>

#include <boost/math/special_functions/gamma.hpp>
#include <gtest/gtest.h>
#include <glm/geometric.hpp>

uint32_t SphereBinning::bin_of(const glm::dvec3& d) const {
  glm::dvec3 l(glm::dot(d, x), glm::dot(d, y), glm::dot(d, z));
  double theta = std::acos(std::clamp(l.z / glm::length(l), -1.0, 1.0));
  if (theta > theta_max) return count();
  double phi = std::atan2(l.y, l.x);
  if (phi < 0) phi += 2 * M_PI;
  uint32_t t = std::min(uint32_t(theta / theta_max * theta_bins), theta_bins - 1);
  uint32_t p = std::min(uint32_t(phi / (2 * M_PI) * phi_bins), phi_bins - 1);
  return t * phi_bins + p;
}

BinValues bin_values(const std::vector<float>& pairs) {
  BinValues v;
  for (size_t i = 0; i + 1 < pairs.size(); i += 2) {
    v.integral.push_back(pairs[i]);
    v.edge.push_back(pairs[i + 1] != 0);
  }
  return v;
}

std::vector<pc_float4> SphereBinning::device_params() const {
  auto f4 = [](const glm::dvec3& v, double w = 0) { return pc_float4{float(v.x), float(v.y), float(v.z), float(w)}; };
  return {f4(x), f4(y), f4(z), {float(theta_max), float(theta_bins), float(phi_bins), 0.0f}};
}

SphereBinning SphereBinning::about(const glm::dvec3& axis, double theta_max) {
  SphereBinning b;
  b.z = glm::normalize(axis);
  glm::dvec3 other = std::abs(b.z.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  b.x = glm::normalize(glm::cross(other, b.z));
  b.y = glm::cross(b.z, b.x);
  b.theta_max = theta_max;
  return b;
}

void gauss_legendre01(int order, std::vector<double>& nodes, std::vector<double>& weights) {
  nodes.assign(order, 0);
  weights.assign(order, 0);
  for (int i = 0; i < order; ++i) {
    // Newton's method on P_order from Tricomi's initial guess.
    double x = std::cos(M_PI * (i + 0.75) / (order + 0.5)), dp = 1;
    for (int iter = 0; iter < 100; ++iter) {
      double p0 = 1, p1 = x;
      for (int k = 2; k <= order; ++k) {
        double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = order * (x * p1 - p0) / (x * x - 1);
      double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-15) break;
    }
    nodes[i] = 0.5 * (1 - x);
    weights[i] = 1.0 / ((1 - x * x) * dp * dp);  // 2 / ((1 - x^2) P'^2), halved for [0, 1]
  }
}

BinIntegrals integrate_bins(const BinIntegrator& integrate, uint32_t bin_count, double samples, double tolerance,
                            int max_order) {
  BinIntegrals r;
  r.value.assign(bin_count, 0);
  std::vector<double> ratio(bin_count, 0);  // each bin's last |difference| / sqrt(count)
  std::vector<uint32_t> todo(bin_count);
  std::iota(todo.begin(), todo.end(), 0u);
  int order = 4;
  std::vector<float> previous = integrate(todo, order).integral;
  while (!todo.empty()) {
    BinValues values = integrate(todo, 2 * order);
    const std::vector<float>& current = values.integral;
    r.highest_order = 2 * order;
    std::vector<uint32_t> again;
    std::vector<float> again_values;
    for (size_t i = 0; i < todo.size(); ++i) {
      uint32_t b = todo[i];
      r.value[b] = current[i];
      double count = samples * current[i];
      ratio[b] = samples * std::abs(double(current[i]) - previous[i]) / std::sqrt(std::max(count, 1.0));
      if (ratio[b] > tolerance || (values.edge[i] && 2 * order < 64)) {
        again.push_back(b);
        again_values.push_back(current[i]);
      }
    }
    if (2 * order >= max_order) {
      r.unconverged = again.size();
      break;
    }
    todo = again;
    previous = again_values;
    order *= 2;
  }
  r.worst = *std::max_element(ratio.begin(), ratio.end());
  return r;
}

Chi2Result chi2_test(const std::vector<double>& observed, const std::vector<double>& expected, double min_expected) {
  Chi2Result r;
  std::vector<size_t> order(expected.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  double pool_o = 0, pool_e = 0;
  size_t k = 0;
  auto pool = [&] {
    if (expected[order[k]] == 0) r.zero_cells_hit += observed[order[k]];
    pool_o += observed[order[k]];
    pool_e += expected[order[k]];
    ++r.pooled_cells;
    ++k;
  };
  while (k < order.size() && expected[order[k]] < min_expected) pool();
  while (r.pooled_cells > 0 && pool_e < min_expected && k < order.size()) pool();  // too small alone
  std::vector<std::pair<double, Chi2Result::Cell>> terms;
  auto add = [&](size_t index, double o, double e) {
    double term = e > 0 ? (o - e) * (o - e) / e : o > 0 ? INFINITY : 0;
    r.chi2 += term;
    terms.push_back({term, {index, o, e}});
    ++r.cells;
  };
  if (r.pooled_cells > 0) add(SIZE_MAX, pool_o, pool_e);
  for (; k < order.size(); ++k) add(order[k], observed[order[k]], expected[order[k]]);
  std::partial_sort(terms.begin(), terms.begin() + std::min<size_t>(5, terms.size()), terms.end(),
                    [](const auto& a, const auto& b) { return a.first > b.first; });
  for (size_t i = 0; i < std::min<size_t>(5, terms.size()); ++i) r.worst.push_back(terms[i].second);
  r.dof = int(r.cells) - 1;
  r.p_value = r.dof > 0 && std::isfinite(r.chi2) ? boost::math::gamma_q(0.5 * r.dof, 0.5 * r.chi2) : 0.0;
  return r;
}

std::string Chi2Result::describe() const {
  std::ostringstream s;
  s << "chi2 " << chi2 << ", dof " << dof << ", p " << p_value << " (" << cells << " cells, " << pooled_cells
    << " pooled, " << zero_cells_hit << " samples in zero-density cells)";
  return s.str();
}

std::string Chi2Result::describe_worst() const {
  std::ostringstream s;
  s << describe() << "; worst cells:";
  for (const Cell& c : worst) {
    s << " [";
    if (c.index == SIZE_MAX) s << "pooled"; else s << c.index;
    s << ": observed " << c.observed << ", expected " << c.expected << "]";
  }
  return s.str();
}

double sidak_alpha(double alpha, int tests) { return 1 - std::pow(1 - alpha, 1.0 / tests); }

Chi2Family::Chi2Family(size_t runs) : runs(runs), alpha(sidak_alpha(0.01, int(runs))) {}

void Chi2Family::expect_fit(const std::string& name, const Chi2Result& chi2, const std::string& detail) {
  min_p = std::min(min_p, chi2.p_value);
  std::printf("  %-44s p %.4f  %s; %s\n", name.c_str(), chi2.p_value, chi2.describe().c_str(), detail.c_str());
  EXPECT_GE(chi2.p_value, alpha) << name << ": " << chi2.describe_worst();
}

std::string run_detail(double pdf_total, double sampled_fraction, int highest_order) {
  char buf[120];
  std::snprintf(buf, sizeof buf, "integral %.6f, sampled %.6f, quadrature order <= %d", pdf_total, sampled_fraction,
                highest_order);
  return buf;
}

void Chi2Family::print_summary() const {
  std::printf("  %zu runs, min p %.4f, per-run significance %.2e\n", runs, min_p, alpha);
}

std::vector<double> expected_counts(const BinIntegrals& integrals, double samples, double* pdf_total) {
  std::vector<double> expected;
  *pdf_total = 0;
  for (double v : integrals.value) {
    expected.push_back(samples * v);
    *pdf_total += v;
  }
  expected.push_back(samples * std::max(0.0, 1.0 - *pdf_total));
  return expected;
}
