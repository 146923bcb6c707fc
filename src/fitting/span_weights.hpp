#pragma once
// The spatially adaptive penalty's weight per knot span (span_weights.cpp), set between the adaptive fit's rounds
// from the last fit (fit_surface). Each rule's weights are in [floor, 1], 1 the face's full penalty, u-major
// (a·nsv + b). Private to fitting/.

#include <cstddef>
#include <span>
#include <vector>

namespace probecomp::fitting::detail {

// From the local balance of data and penalty: each span's weight ∝ its neighbourhood's share of the fit's degrees
// of freedom (the sum of its points' leverages, `leverage_sum` per span) over the fitted displacement's energy there
// (`span_energy`, PenalizedFitResult), relative to the geometric mean over the face and capped at 1. A span whose
// neighbourhood holds no point or no energy gets 1; one holding fewer than `min_points` points itself (`count`)
// keeps at least its `current` weight.
[[nodiscard]] std::vector<double> balanced_span_weights(std::span<const double> span_energy,
                                                        std::span<const double> leverage_sum, std::span<const int> count,
                                                        std::span<const double> current, int min_points,
                                                        std::size_t nsu, std::size_t nsv, double floor);

// From the fit's roughness alone (its energy over the span's area, the breakpoints bu, bv giving the area up to a
// constant): (mean roughness / the span's)², capped at 1.
[[nodiscard]] std::vector<double> roughness_span_weights(std::span<const double> span_energy,
                                                         const std::vector<double>& bu, const std::vector<double>& bv,
                                                         double floor);

}  // namespace probecomp::fitting::detail
