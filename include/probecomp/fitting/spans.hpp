#pragma once
// Knot-span helpers shared by the refining fitters (offset_surface, fit_surface) and the simulator's refinement.

#include <vector>

namespace probecomp::fitting {

// The midpoints of the spans between consecutive breakpoints that are flagged (flagged[s] for span s), in
// order: the knots that halve them.
[[nodiscard]] inline std::vector<double> flagged_span_midpoints(const std::vector<double>& breaks,
                                                                const std::vector<char>& flagged) {
  std::vector<double> X;
  for (std::size_t s = 0; s + 1 < breaks.size(); ++s) {
    if (flagged[s]) X.push_back(0.5 * (breaks[s] + breaks[s + 1]));
  }
  return X;
}

// `per_span` parameters in each knot span, at its start and in equal steps, and the domain's end.
[[nodiscard]] inline std::vector<double> span_parameters(const std::vector<double>& breaks, int per_span) {
  std::vector<double> t;
  for (std::size_t s = 0; s + 1 < breaks.size(); ++s) {
    for (int m = 0; m < per_span; ++m) t.push_back(breaks[s] + (breaks[s + 1] - breaks[s]) * m / per_span);
  }
  t.push_back(breaks.back());
  return t;
}

}  // namespace probecomp::fitting
