#pragma once
// The adaptive fit's tests, beyond each span's χ², of whether a refinement is tried and whether one tried is kept
// (refinement_tests.cpp). Private to fitting/.

#include <span>

#include "probecomp/fitting/noise_estimate.hpp"
#include "probecomp/fitting/penalized.hpp"

namespace probecomp::fitting::detail {

// Whether neighbouring residuals correlate beyond what the fit alone makes of pure noise: by more than
// kCorrelationStandardErrors of the larger of its null draws' spread and 1/√(K·n) above their mean (below 0, as a
// fit's residuals repel one another by about its leverage: −0.02 to −0.08 on the shape suite's final fits). Above
// 0 by as much, no draws are needed; a fit too large to keep its basis rows is measured against that alone.
[[nodiscard]] bool correlated_beyond_the_fit(const LocalPredictionNoise& local_noise, std::span<const double> residuals,
                                             const PenalizedFitResult& fit);

// Whether a fit's penalty did nothing: its trace above kSaturatedShare of its `control_points`.
[[nodiscard]] bool saturated(double edf, int control_points);

// Along scan lines, once every span's residuals are consistent with the noise, a refinement of every span is tried:
// on a coarse net a smooth misfit of a fourth of σ hides in the residuals' spread (D805, a 275 µm saddle on a
// cylinder scanned along lines, σ = 4.5 µm: spread 4.67 µm, local prediction errors 4.54 µm; 20 control points,
// contacts 1.14 µm std where the reference smoother reaches 0.51). Leave-span-out scores of different nets are not
// comparable, so the refined fit is kept when it explains significantly more than the coarse one (an F test at
// kRefinementTrialSignificance on the weighted residual sums, the degrees of freedom the fits' traces) and, unless
// the coarse fit's penalty did nothing (its trace above kSaturatedShare of its control points: the net is at the end
// of what it can follow), when it also predicts better: its residual sum falls by more than kPredictiveF σ² per degree
// of freedom added (Mallows' C_p asks for 2; at 2 a narrow dent among lines was refined over the whole face, D1006
// 0.349 -> 0.416 µm, D708 1.288 -> 1.417). Tried on saturated nets only, it left broad bulges and long waves on the
// nominal's net (D915 1.165 µm, D911 1.314, D712 0.876, against 0.808, 0.980, 0.712 tried on every net; the
// reference smoother 0.857, 0.878, 0.691).
//
// Whether a refined fit (residual sum `rss1`, trace `edf1`) is kept over the coarse one (`rss0`, `edf0`, and whether
// that was saturated), both on the same `points`.
[[nodiscard]] bool refinement_kept(double rss0, double edf0, bool saturated0, double rss1, double edf1, int points);

}  // namespace probecomp::fitting::detail
