#include "nets.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "probecomp/fitting/adaptive.hpp"
#include "probecomp/fitting/spans.hpp"
#include "probecomp/geometry/statistics.hpp"

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

// Each span's neighbourhood is gathered and its median taken on its own (in parallel, the same whatever the thread
// count).
std::vector<double> span_spread(std::span<const double> standardised, std::span<const double> weights,
                                std::span<const std::uint32_t> span, std::size_t nsu, std::size_t nsv, double sigma) {
  // The points' |standardised residuals| grouped by span (a counting sort), in-fit points only; in single precision,
  // which a median of a spread needs no more than (a million points: 4 MB for the while).
  std::vector<std::size_t> start(nsu * nsv + 1, 0);
  for (std::size_t k = 0; k < span.size(); ++k) {
    if (weights.empty() || weights[k] > 0.0) ++start[span[k] + 1];
  }
  for (std::size_t s = 0; s < nsu * nsv; ++s) start[s + 1] += start[s];
  std::vector<float> grouped(start.back());
  {
    std::vector<std::size_t> next(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < span.size(); ++k) {
      if (weights.empty() || weights[k] > 0.0) grouped[next[span[k]]++] = static_cast<float>(std::abs(standardised[k]));
    }
  }
  std::vector<double> by_span(nsu * nsv, sigma);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nsu * nsv, 64), [&](const auto& range) {
    std::vector<double> around;  // in double for median_in_place
    for (std::size_t s = range.begin(); s != range.end(); ++s) {
      around.clear();
      for_each_around(s / nsv, s % nsv, nsu, nsv, [&](std::size_t s2) {
        around.insert(around.end(), grouped.begin() + static_cast<std::ptrdiff_t>(start[s2]),
                      grouped.begin() + static_cast<std::ptrdiff_t>(start[s2 + 1]));
      });
      if (around.size() >= static_cast<std::size_t>(kMinLocalPoints)) {
        by_span[s] = std::max(geometry::kMadToSigma * geometry::median_in_place(around), sigma);
      }
    }
  });
  return by_span;
}

}  // namespace probecomp::fitting::detail
