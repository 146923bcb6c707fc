#include "probecomp/compensation/outliers.hpp"

#include <algorithm>
#include <cmath>

namespace probecomp::compensation {

namespace {

// Point k's residual's standard deviation over σ under noise alone. In the fit: Var(r_k) = σ²(1 − h_k); left out:
// Var(r_k) = σ²(1 + v_k). The leverage is kept below 0.95 so that a point the fit interpolates still has a bound of
// a fifth of its noise, not zero.
double residual_factor(const fitting::AdaptiveFitResult& fit, double weight, std::size_t k) {
  const double v = fit.variance_factor.empty() ? 0.0 : fit.variance_factor[k];
  return weight > 0.0 ? std::sqrt(std::max(1.0 - weight * v, 0.05)) : std::sqrt(1.0 + v);
}

double bound(double sigma, double factor, const OutlierTest& test) {
  return std::max(test.sigmas * sigma * factor, test.min_residual);
}

}  // namespace

double outlier_bound(const fitting::AdaptiveFitResult& fit, double weight, std::size_t k, const OutlierTest& test,
                     Spread spread) {
  // The local spread is never below the face's noise (AdaptiveFitResult::span_spread).
  const double sigma = spread == Spread::Local ? fitting::LocalSpread(fit)(k) : fit.noise_sigma;
  return bound(sigma, residual_factor(fit, weight, k), test);
}

std::vector<char> outliers_against_fit(const fitting::AdaptiveFitResult& fit, std::span<const double> weights,
                                       const OutlierTest& test, Spread spread) {
  std::vector<char> out(fit.residuals.size(), 0);
  const fitting::LocalSpread local_spread(fit);
  for (std::size_t k = 0; k < out.size(); ++k) {
    const double r = std::abs(fit.residuals[k]);
    const double factor = residual_factor(fit, weights.empty() ? 1.0 : weights[k], k);
    // The local spread only ever raises the bound: looked up only for the few points beyond the face's.
    out[k] = r > bound(fit.noise_sigma, factor, test) &&
             (spread == Spread::Face || r > bound(local_spread(k), factor, test));
  }
  return out;
}

}  // namespace probecomp::compensation
