#pragma once
// The fit's bias from what its basis cannot represent (representation_bias.cpp), added to
// AdaptiveFitResult::misfit. Private to fitting/.

#include <span>

#include "probecomp/fitting/adaptive.hpp"

namespace probecomp::fitting::detail {

// `fit` (made from `start`'s shape on its own net) against a fit of the same points on a net about twice as fine,
// with the same penalty; where the two disagree beyond what the finer fit's extra variance explains, pooled over each
// span and its eight neighbours, `fit.misfit` is raised to that. Nothing on a fit on a THB basis or on exact data.
void add_representation_bias(AdaptiveFitResult& fit, const nurbs::Surface& start, std::span<const Point3> points,
                             std::span<const double> weights, const AdaptiveFitOptions& options);

}  // namespace probecomp::fitting::detail
