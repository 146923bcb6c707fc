#include "probecomp/compensation/outliers.hpp"

#include <algorithm>
#include <cmath>

namespace probecomp::compensation {

double outlier_bound(const fitting::AdaptiveFitResult& fit, double weight, std::size_t k, const OutlierTest& test,
                     Spread spread) {
  const double v = fit.variance_factor.empty() ? 0.0 : fit.variance_factor[k];
  // In the fit: Var(r_k) = σ²(1 − h_k); left out: Var(r_k) = σ²(1 + v_k). The leverage is kept below 0.95 so that
  // a point the fit interpolates still has a bound of a fifth of its noise, not zero.
  const double factor = weight > 0.0 ? std::sqrt(std::max(1.0 - weight * v, 0.05)) : std::sqrt(1.0 + v);
  const double sigma = spread == Spread::Local ? std::max(fitting::local_spread(fit, k), fit.noise_sigma) : fit.noise_sigma;
  return std::max(test.sigmas * sigma * factor, test.min_residual);
}

std::vector<char> outliers_against_fit(const fitting::AdaptiveFitResult& fit, std::span<const double> weights,
                                       const OutlierTest& test, Spread spread) {
  std::vector<char> out(fit.residuals.size(), 0);
  for (std::size_t k = 0; k < out.size(); ++k) {
    const double w = weights.empty() ? 1.0 : weights[k];
    // The local spread only ever raises the bound: looked up only for the few points beyond the face's.
    out[k] = std::abs(fit.residuals[k]) > outlier_bound(fit, w, k, test, Spread::Face) &&
             (spread == Spread::Face || std::abs(fit.residuals[k]) > outlier_bound(fit, w, k, test, Spread::Local));
  }
  return out;
}

}  // namespace probecomp::compensation
