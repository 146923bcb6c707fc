#pragma once
// Order statistics shared by registration, fitting and compensation: medians and the robust scale
// σ̂ = 1.4826 · median |r| (the normalised MAD: consistent for Gaussian noise, unmoved by up to half the
// values being gross errors). One definition, so that every stage reads "noise" the same way.

#include <span>

namespace probecomp::geometry {

// The MAD of a normal distribution is 0.6745 σ, so σ ≈ 1.4826 · MAD.
inline constexpr double kMadToSigma = 1.4826;

// The upper median (element n/2 in sorted order; for an even count the larger of the two middle values).
// May reorder `values` (large sets are left as they are, found in parallel); the value is exact. 0 for no values.
[[nodiscard]] double upper_median_in_place(std::span<double> values);

// The median (the mean of the two middle values for an even count). May reorder `values`. 0 for no values.
[[nodiscard]] double median_in_place(std::span<double> values);

// 1.4826 · upper median |r| over the residuals, but at least `min_scale`; `min_scale` when there are none.
[[nodiscard]] double robust_scale(std::span<const double> residuals, double min_scale);
// The same computed in `residuals` itself (left reordered, in absolute value): no copy of a million residuals at
// every ICP step.
[[nodiscard]] double robust_scale_in_place(std::span<double> residuals, double min_scale);

// The upper quantile z of the standard normal with P(N(0,1) > z) = alpha, 0 < alpha ≤ 0.5 (Abramowitz and Stegun
// 26.2.23, error below 4.5e-4).
[[nodiscard]] double normal_upper_quantile(double alpha);

// The χ² quantile with n degrees of freedom exceeded with probability alpha (Wilson–Hilferty: (χ²/n)^(1/3) is
// nearly normal with mean 1 − 2/(9n) and variance 2/(9n); good to a few per cent from n = 2).
[[nodiscard]] double chi2_upper_quantile(double n, double alpha);

}  // namespace probecomp::geometry
