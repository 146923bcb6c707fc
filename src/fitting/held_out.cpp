#include "probecomp/fitting/held_out.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include "nets.hpp"

namespace probecomp::fitting {

std::vector<double> held_out_errors(const AdaptiveFitResult& fit, const nurbs::Surface& start,
                                    std::span<const Point3> points, std::span<const double> weights,
                                    std::span<const int> groups, int group_count, const PenalizedFitOptions& options) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (!fit.fitted() || fit.span_weight.empty() || groups.size() != points.size()) return {};
  const nurbs::Surface target = detail::on_net_of(start, fit.surface);
  PenalizedFitOptions o = options;
  o.lambda = fit.lambda;
  o.log10_anisotropy = fit.log10_anisotropy;
  std::vector<double> out(points.size(), kNaN);
  std::vector<double> w(points.size());
  for (int g = 0; g < group_count; ++g) {
    bool any = false;
    for (std::size_t k = 0; k < points.size(); ++k) {
      const double wk = weights.empty() ? 1.0 : weights[k];
      w[k] = groups[k] == g ? 0.0 : wk;
      any = any || (groups[k] == g && wk > 0.0);
    }
    if (!any) continue;
    const PenalizedFitResult without = fit_penalized(target, points, fit.params, w, o, fit.span_weight);
    if (!without.ok()) return {};
    for (std::size_t k = 0; k < points.size(); ++k) {
      const double wk = weights.empty() ? 1.0 : weights[k];
      if (groups[k] != g || !(wk > 0.0)) continue;
      out[k] = (nurbs::evaluate(without.surface, fit.params[k].u, fit.params[k].v) - points[k]).squaredNorm();
    }
  }
  return out;
}

}  // namespace probecomp::fitting
