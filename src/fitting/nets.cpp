#include "nets.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

#include "probecomp/fitting/spans.hpp"

#include "penalty.hpp"

namespace probecomp::fitting::detail {

AlongNormal along_normal(const nurbs::Surface& s, std::span<const Point3> points,
                         std::span<const SurfaceParameter> params, std::span<const Vector3> smoothing_bias) {
  AlongNormal out{std::vector<double>(points.size()), std::vector<double>(points.size(), 0.0)};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024), [&](const auto& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const nurbs::SurfaceD1 d = nurbs::derivatives_d1(s, params[k].u, params[k].v);
      const Vector3 e = points[k] - d.S;
      const nurbs::UnitNormal n = nurbs::unit_normal(s, params[k].u, params[k].v, d.Su, d.Sv);
      // Where the surface has no normal, the whole gap is the residual (sign from nothing: positive), and the
      // whole bias its size.
      const bool degenerate = n.status == nurbs::UnitNormal::Status::Degenerate;
      out.residual[k] = degenerate ? e.norm() : e.dot(n.n);
      if (!smoothing_bias.empty()) {
        out.bias[k] = degenerate ? smoothing_bias[k].norm() : std::abs(smoothing_bias[k].dot(n.n));
      }
    }
  });
  return out;
}

nurbs::Surface uniformly_refined(nurbs::Surface s, double control_points, double cap) {
  const MeanSpeeds speed = mean_speeds(s);
  const nurbs::Domain d = s.domain();
  while (static_cast<double>(s.num_u()) * s.num_v() < control_points) {
    const std::vector<double> bu = s.U().breakpoints(), bv = s.V().breakpoints();
    const double span_u = speed.u * (d.u1 - d.u0) / static_cast<double>(bu.size() - 1);
    const double span_v = speed.v * (d.v1 - d.v0) / static_cast<double>(bv.size() - 1);
    const bool along_u = span_u >= span_v;
    // Halving a direction's spans adds one control point for each span.
    const double next = along_u ? static_cast<double>(s.num_u() + static_cast<int>(bu.size()) - 1) * s.num_v()
                                : static_cast<double>(s.num_v() + static_cast<int>(bv.size()) - 1) * s.num_u();
    if (next > cap) break;
    s = along_u ? nurbs::refine_knots_u(s, flagged_span_midpoints(bu, std::vector<char>(bu.size() - 1, 1)))
                : nurbs::refine_knots_v(s, flagged_span_midpoints(bv, std::vector<char>(bv.size() - 1, 1)));
  }
  return s;
}

nurbs::Surface on_net_of(const nurbs::Surface& start, const nurbs::Surface& fitted) {
  // Knots equal to the start's are the same doubles (insertion copies them); the tolerance only guards rounding in
  // a knot vector's storage.
  constexpr double kSameKnot = 1e-12;
  auto missing = [&](std::span<const double> have, std::span<const double> want) {
    std::vector<double> x;
    std::size_t i = 0;
    for (const double k : want) {
      while (i < have.size() && have[i] < k - kSameKnot) ++i;
      if (i < have.size() && std::abs(have[i] - k) <= kSameKnot) {
        ++i;
        continue;
      }
      x.push_back(k);
    }
    return x;
  };
  nurbs::Surface s = start;
  const std::vector<double> xu = missing(start.U().knots(), fitted.U().knots());
  const std::vector<double> xv = missing(start.V().knots(), fitted.V().knots());
  if (!xu.empty()) s = nurbs::refine_knots_u(s, xu);
  if (!xv.empty()) s = nurbs::refine_knots_v(s, xv);
  return s;
}

}  // namespace probecomp::fitting::detail
