#include "probecomp/fitting/adaptive.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "probecomp/fitting/spans.hpp"
#include "probecomp/nurbs/closest_point.hpp"
#include "probecomp/geometry/point_tree.hpp"
#include "probecomp/geometry/statistics.hpp"

namespace probecomp::fitting {

namespace {

using nurbs::Surface;

using geometry::kMadToSigma;
using geometry::median_in_place;

// Signed residual of each point along the fit's unit normal at its parameters.
std::vector<double> normal_residuals(const Surface& s, std::span<const Point3> points,
                                     std::span<const SurfaceParameter> params) {
  std::vector<double> r(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024), [&](const auto& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const nurbs::SurfaceD1 d = nurbs::derivatives_d1(s, params[k].u, params[k].v);
      const Vector3 e = points[k] - d.S;
      const nurbs::UnitNormal n = nurbs::unit_normal(s, params[k].u, params[k].v, d.Su, d.Sv);
      // Where the surface has no normal, the whole gap is the residual (sign from nothing: positive).
      r[k] = n.status == nurbs::UnitNormal::Status::Degenerate ? e.norm() : e.dot(n.n);
    }
  });
  return r;
}

// The upper quantile z with P(N(0,1) > z) = alpha (Abramowitz and Stegun 26.2.23, error below 4.5e-4).
double normal_upper_quantile(double alpha) {
  const double t = std::sqrt(-2.0 * std::log(alpha));
  return t - (2.515517 + 0.802853 * t + 0.010328 * t * t) / (1.0 + 1.432788 * t + 0.189269 * t * t + 0.001308 * t * t * t);
}

// The χ² quantile with n degrees of freedom exceeded with probability alpha (Wilson–Hilferty: (χ²/n)^(1/3) is
// nearly normal with mean 1 − 2/(9n) and variance 2/(9n); good to a few per cent from n = 2).
double chi2_upper_quantile(double n, double alpha) {
  const double h = 2.0 / (9.0 * n);
  const double c = 1.0 - h + normal_upper_quantile(alpha) * std::sqrt(h);
  return n * c * c * c;
}

// The span index of t among the breakpoints (the last span holds the domain's end).
int span_of(const std::vector<double>& breaks, double t) {
  const auto it = std::upper_bound(breaks.begin(), breaks.end(), t);
  const int s = static_cast<int>(it - breaks.begin()) - 1;
  return std::clamp(s, 0, static_cast<int>(breaks.size()) - 2);
}

}  // namespace

std::vector<std::uint32_t> nearest_neighbours(std::span<const Point3> points) {
  std::vector<std::uint32_t> out(points.size(), 0);
  if (points.size() < 2) return out;
  geometry::PointCloud cloud{std::vector<Point3>(points.begin(), points.end())};
  geometry::PointTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024), [&](const auto& range) {
    for (std::size_t pos = range.begin(); pos != range.end(); ++pos) {
      const std::size_t k = tree.vAcc[pos];  // the tree's leaf order: neighbouring queries share cached nodes
      std::uint32_t index[2];
      double dist_sq[2];  // squared (nanoflann)
      nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(2);
      knn.init(index, dist_sq);
      const double q[3] = {points[k].x(), points[k].y(), points[k].z()};
      tree.findNeighbors(knn, q, nanoflann::SearchParams());
      // The point itself is normally first; with duplicates either may come first, and a duplicate is a fine
      // neighbour (its noise is independent).
      out[k] = index[0] != k ? index[0] : index[1];
    }
  });
  return out;
}

double neighbour_noise_sigma(std::span<const double> residuals, std::span<const double> weights,
                             std::span<const std::uint32_t> neighbours) {
  std::vector<double> d;
  d.reserve(residuals.size());
  for (std::size_t k = 0; k < residuals.size(); ++k) {
    const std::size_t j = neighbours[k];
    if (j == k || (!weights.empty() && !(weights[k] > 0.0 && weights[j] > 0.0))) continue;
    d.push_back(std::abs(residuals[k] - residuals[j]));
  }
  if (d.empty()) return std::numeric_limits<double>::infinity();
  return kMadToSigma * median_in_place(d) / std::sqrt(2.0);
}

std::vector<SurfaceParameter> correct_parameters(const Surface& s, std::span<const Point3> points,
                                                 std::span<const SurfaceParameter> params) {
  std::vector<SurfaceParameter> out(params.begin(), params.end());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 512), [&](const auto& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const nurbs::ClosestPointResult r = nurbs::refine_closest_point(s, points[k], params[k].u, params[k].v);
      if (r.ok()) out[k] = {r.u, r.v};
    }
  });
  return out;
}

double robust_noise_sigma(std::span<const double> residuals, std::span<const double> weights,
                          int unknowns_per_coordinate) {
  std::vector<double> r;
  r.reserve(residuals.size());
  for (std::size_t k = 0; k < residuals.size(); ++k) {
    if (weights.empty() || weights[k] > 0.0) r.push_back(residuals[k]);
  }
  if (r.empty()) return 0.0;
  std::vector<double> work = r;
  const double centre = median_in_place(work);
  for (double& x : r) x = std::abs(x - centre);
  const double mad = median_in_place(r);
  const double absorbed = std::min(static_cast<double>(unknowns_per_coordinate) / static_cast<double>(r.size()), 0.9);
  return kMadToSigma * mad / std::sqrt(1.0 - absorbed);
}

AdaptiveFitResult fit_surface(const Surface& start, std::span<const Point3> points,
                              std::span<const SurfaceParameter> params, std::span<const double> weights,
                              const AdaptiveFitOptions& options, std::span<const std::uint32_t> given_neighbours) {
  AdaptiveFitResult result{.status = AdaptiveFitResult::Status::NotDone, .surface = start};
  std::vector<SurfaceParameter> t(params.begin(), params.end());
  std::size_t used = 0;
  for (std::size_t k = 0; k < points.size(); ++k) used += weights.empty() || (k < weights.size() && weights[k] > 0.0);
  Surface current = start;
  std::vector<std::uint32_t> computed;
  if (given_neighbours.size() != points.size()) computed = nearest_neighbours(points);
  const std::span<const std::uint32_t> neighbours = computed.empty() ? given_neighbours : std::span<const std::uint32_t>(computed);

  for (int round = 0;; ++round) {
    FitResult fit = fit_control_points(current, points, t, weights, options.fit);
    for (int c = 0; c < options.parameter_corrections && fit.ok(); ++c) {
      t = correct_parameters(fit.surface, points, t);
      fit = fit_control_points(fit.surface, points, t, weights, options.fit);
    }
    if (!fit.ok()) {
      result.status = fit.status == FitResult::Status::NotDone ? AdaptiveFitResult::Status::NotDone
                                                               : AdaptiveFitResult::Status::NumericalError;
      return result;
    }
    current = fit.surface;
    const int unknowns = current.num_u() * current.num_v();

    result.surface = current;
    result.params = t;
    result.residuals = normal_residuals(current, points, t);
    result.control_points = unknowns;
    // The spread of the residuals overstates the noise while the fit still misses a shape that covers much of
    // the face (a broad deformation): then the differences between neighbours, which that misfit barely
    // changes, tell the noise. On noise alone the two agree; the smaller is taken.
    {
      const double spread = robust_noise_sigma(result.residuals, weights, unknowns);
      // The fit makes neighbouring residuals alike in proportion to what it absorbs, so their differences
      // understate σ as the spread does: the same correction (measured: 10 % low without it on the dent test).
      const double absorbed = std::min(static_cast<double>(unknowns) / static_cast<double>(std::max<std::size_t>(used, 1)), 0.9);
      const double local = neighbour_noise_sigma(result.residuals, weights, neighbours) / std::sqrt(1.0 - absorbed);
      result.noise_sigma = std::min(spread, local);
    }
    double sum = 0.0, weight_sum = 0.0;
    result.max_residual = 0.0;
    for (std::size_t k = 0; k < points.size(); ++k) {
      const double w = weights.empty() ? 1.0 : weights[k];
      sum += w * result.residuals[k] * result.residuals[k];
      weight_sum += w;
      if (w > 0.0) result.max_residual = std::max(result.max_residual, std::abs(result.residuals[k]));
    }
    result.rms = std::sqrt(sum / weight_sum);

    // Which spans' residuals the noise does not explain.
    const double sigma = std::max(result.noise_sigma, options.noise_floor);
    const std::vector<double> bu = current.U().breakpoints();
    const std::vector<double> bv = current.V().breakpoints();
    const std::size_t nsu = bu.size() - 1, nsv = bv.size() - 1;
    std::vector<double> chi2(nsu * nsv, 0.0);
    std::vector<int> count(nsu * nsv, 0);
    // Each point's span in parallel; the sums in point order (the same whatever the thread count).
    std::vector<std::size_t> span(points.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096), [&](const auto& range) {
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        span[k] = static_cast<std::size_t>(span_of(bu, t[k].u)) * nsv + static_cast<std::size_t>(span_of(bv, t[k].v));
      }
    });
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (!weights.empty() && !(weights[k] > 0.0)) continue;
      const std::size_t s = span[k];
      chi2[s] += (result.residuals[k] / sigma) * (result.residuals[k] / sigma);
      ++count[s];
    }
    const double kept = 1.0 - std::min(static_cast<double>(unknowns) / static_cast<double>(std::max<std::size_t>(used, 1)), 0.9);
    std::vector<char> flag_u(nsu, 0), flag_v(nsv, 0);
    result.spans_above_noise = 0;
    const double alpha = options.false_alarm / static_cast<double>(nsu * nsv);
    for (std::size_t a = 0; a < nsu; ++a) {
      for (std::size_t b = 0; b < nsv; ++b) {
        const std::size_t s = a * nsv + b;
        if (count[s] == 0 || chi2[s] <= chi2_upper_quantile(count[s] * kept, alpha)) continue;
        ++result.spans_above_noise;
        if (count[s] >= options.min_points_to_split) {
          flag_u[a] = 1;
          flag_v[b] = 1;
        }
      }
    }
    if (result.spans_above_noise == 0) {
      result.status = AdaptiveFitResult::Status::OK;
      return result;
    }
    const std::vector<double> xu = flagged_span_midpoints(bu, flag_u);
    const std::vector<double> xv = flagged_span_midpoints(bv, flag_v);
    const double after = static_cast<double>(current.num_u() + static_cast<int>(xu.size())) *
                         static_cast<double>(current.num_v() + static_cast<int>(xv.size()));
    if (round == options.max_rounds || (xu.empty() && xv.empty()) ||
        after * (result.noise_sigma <= options.noise_floor ? options.min_points_per_control_point_noise_free
                                                           : options.min_points_per_control_point) >
            static_cast<double>(used)) {
      result.status = AdaptiveFitResult::Status::NoiseNotReached;
      return result;
    }
    if (!xu.empty()) current = nurbs::refine_knots_u(current, xu);
    if (!xv.empty()) current = nurbs::refine_knots_v(current, xv);
    result.knots_inserted += static_cast<int>(xu.size() + xv.size());
    result.rounds = round + 1;
  }
}

}  // namespace probecomp::fitting
