#pragma once
// A fit judged by refitting without groups of its points (held_out.cpp): what it predicts where it saw nothing,
// which the fit's own cross-validation, leaving out a knot span's points at a time, does not test between scan
// lines millimetres apart.

#include <span>
#include <vector>

#include "probecomp/fitting/adaptive.hpp"

namespace probecomp::fitting {

// Each group of points (groups[k] in 0 … group_count − 1; negative: in every refit) left out in turn, and the points
// refitted on the fit's own net with its own λ, θ and penalty weights: each left-out point's squared distance from
// the refit made without it, at its parameters (fit.params), mm²; NaN for a point in no group or of weight 0. Empty
// where the fit cannot be remade so (not fitted, fitted on a THB basis) or a refit fails. `start` is the surface the
// fit began from (its penalty's target), `options` the fit's (λ and θ are taken from `fit`).
[[nodiscard]] std::vector<double> held_out_errors(const AdaptiveFitResult& fit, const nurbs::Surface& start,
                                                  std::span<const Point3> points, std::span<const double> weights,
                                                  std::span<const int> groups, int group_count,
                                                  const PenalizedFitOptions& options);

}  // namespace probecomp::fitting
