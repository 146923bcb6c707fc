#include "refinement_tests.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "probecomp/geometry/statistics.hpp"

namespace probecomp::fitting::detail {

namespace {

// Neighbouring residuals' correlation counts as a misfit's above this many standard errors of it on independent
// noise, 1/√(K·n) for n points of K neighbours each: three, since the pairs overlap (see fit_surface).
constexpr double kCorrelationStandardErrors = 3.0;

// Draws of pure noise run through a fit (fitting::null_statistics) to judge its residuals: their mean correlation is
// then known to about a third of its spread. Four solves with the fit's factor.
constexpr int kNullProbes = 12;

// See refinement_kept (refinement_tests.hpp).
constexpr double kSaturatedShare = 0.9;
constexpr double kRefinementTrialSignificance = 0.01;
constexpr double kPredictiveF = 3.0;

}  // namespace

bool correlated_beyond_the_fit(const LocalPredictionNoise& local_noise, std::span<const double> residuals,
                               const PenalizedFitResult& fit) {
  const double observed = local_noise.neighbour_correlation(residuals);
  const double se = 1.0 / std::sqrt(static_cast<double>(LocalPredictionNoise::kNeighbours) *
                                    static_cast<double>(std::max<std::size_t>(local_noise.tested(), 1)));
  if (observed > kCorrelationStandardErrors * se) return true;
  const std::vector<double> null = null_statistics(
      fit, kNullProbes, [&](std::span<const double> r) { return local_noise.neighbour_correlation(r); });
  if (null.size() < 2) return false;
  const double mean = std::accumulate(null.begin(), null.end(), 0.0) / static_cast<double>(null.size());
  double squares = 0.0;
  for (double x : null) squares += (x - mean) * (x - mean);
  const double sd = std::sqrt(squares / static_cast<double>(null.size() - 1));
  return observed > mean + kCorrelationStandardErrors * std::max(sd, se);
}

bool saturated(double edf, int control_points) { return edf > kSaturatedShare * control_points; }

// F = (rss0 − rss1)/(edf1 − edf0) over rss1/(points − edf1), its quantile taken as χ²/d (denominators of thousands
// of degrees of freedom).
bool refinement_kept(double rss0, double edf0, bool saturated0, double rss1, double edf1, int points) {
  const double d1 = edf1 - edf0, d2 = points - edf1;
  if (!(d1 > 0.5) || !(d2 > 0.0) || !(rss1 > 0.0)) return false;
  const double F = ((rss0 - rss1) / d1) / (rss1 / d2);
  return (saturated0 || F > kPredictiveF) && F > geometry::chi2_upper_quantile(d1, kRefinementTrialSignificance) / d1;
}

}  // namespace probecomp::fitting::detail
