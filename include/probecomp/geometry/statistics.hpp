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

}  // namespace probecomp::geometry
