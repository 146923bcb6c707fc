#pragma once
// Knot-span helpers shared by the refining fitters (offset_surface, fit_surface) and the simulator's refinement.

#include <algorithm>
#include <cstddef>
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

// The span index of t among the breakpoints (the last span holds the domain's end).
[[nodiscard]] inline int span_of(const std::vector<double>& breaks, double t) {
  const auto it = std::upper_bound(breaks.begin(), breaks.end(), t);
  const int s = static_cast<int>(it - breaks.begin()) - 1;
  return std::clamp(s, 0, static_cast<int>(breaks.size()) - 2);
}

// The span, a · (V spans) + b, of parameter (u, v) on the grid of spans between the breakpoints bu, bv (u-major,
// as every per-span vector of the fitters is).
[[nodiscard]] inline std::size_t span_at(const std::vector<double>& bu, const std::vector<double>& bv, double u,
                                         double v) {
  return static_cast<std::size_t>(span_of(bu, u)) * (bv.size() - 1) + static_cast<std::size_t>(span_of(bv, v));
}

// The breakpoints with every span halved `times` times (the knot spans of a THB basis's level `times`).
[[nodiscard]] inline std::vector<double> halved(std::vector<double> breaks, int times) {
  for (int l = 0; l < times; ++l) {
    std::vector<double> mid;
    for (std::size_t a = 0; a + 1 < breaks.size(); ++a) mid.push_back(0.5 * (breaks[a] + breaks[a + 1]));
    breaks.insert(breaks.end(), mid.begin(), mid.end());
    std::sort(breaks.begin(), breaks.end());
  }
  return breaks;
}

// The union of two sets of breakpoints, sorted, each value once: the spans of two nets cut by each other's lines
// (each span of the union lies in one span of either; see PenalizedFitOptions::cv_fold_u).
[[nodiscard]] inline std::vector<double> merged_breakpoints(std::vector<double> a, const std::vector<double>& b) {
  a.insert(a.end(), b.begin(), b.end());
  std::sort(a.begin(), a.end());
  a.erase(std::unique(a.begin(), a.end()), a.end());
  return a;
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

// Calls f(s2) for span (a, b) of an nsu × nsv grid of spans (u-major) and each of its (up to) eight neighbours:
// the neighbourhood the span tests, the bias estimate, the local spread and the penalty weights pool over.
template <typename F>
void for_each_around(std::size_t a, std::size_t b, std::size_t nsu, std::size_t nsv, F&& f) {
  for (std::size_t a2 = a > 0 ? a - 1 : 0; a2 <= std::min(a + 1, nsu - 1); ++a2) {
    for (std::size_t b2 = b > 0 ? b - 1 : 0; b2 <= std::min(b + 1, nsv - 1); ++b2) f(a2 * nsv + b2);
  }
}

}  // namespace probecomp::fitting
