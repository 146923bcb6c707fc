#include "probecomp/fitting/noise_estimate.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

#include "probecomp/geometry/neighbours.hpp"
#include "probecomp/geometry/statistics.hpp"

#include "nets.hpp"

namespace probecomp::fitting {

namespace {

// The neighbourhood lies along a line (a scan line) when its second principal spread is below this fraction of
// its first: a quadratic over the plane is then not determined across the line.
constexpr double kLineSpreadRatio = 0.15;
// A local fit is dropped when its normal matrix (coordinates scaled to the neighbourhood) is this ill-conditioned:
// repeated points, or too few distinct positions for the quadratic.
constexpr double kMinConditionReciprocal = 1e-8;
// A prediction error beyond this many times the first estimate, and the largest among its neighbours', marks a
// gross error (on Gaussian noise 1 point in 16 000 is beyond 4 σ; and the first estimate reads high when there
// are gross errors).
constexpr double kGrossErrorSigmas = 4.0;
// Screens for gross errors standing out alone (screen_for_gross_errors): a cluster of k errors among each other's
// neighbours is peeled in up to k passes.
constexpr int kScreenPasses = 8;

struct Prediction {
  bool ok = false;
  Eigen::Matrix<double, LocalPredictionNoise::kNeighbours, 1> weight;
  double variance_factor = 0.0;  // Σ weight², the prediction's variance over σ²
};

// The weights a_j with quadratic(k) = Σ a_j r_j for the least-squares quadratic through the neighbours' values,
// over columns `design` (one row per neighbour, the constant first).
template <int Columns>
Prediction predict_from(const Eigen::Matrix<double, LocalPredictionNoise::kNeighbours, Columns>& design) {
  Prediction out;
  const Eigen::Matrix<double, Columns, Columns> normal = design.transpose() * design;
  // Pivoted LDLᵀ: the ratio of its smallest to largest pivot tells a rank-deficient set (a scan line's points for
  // the quadratic over the plane) as well as an eigen-decomposition would, at a fraction of the cost.
  const Eigen::LDLT<Eigen::Matrix<double, Columns, Columns>> ldlt(normal);
  if (ldlt.info() != Eigen::Success) return out;
  const double largest = ldlt.vectorD().cwiseAbs().maxCoeff();
  if (!(largest > 0.0) || ldlt.vectorD().minCoeff() < kMinConditionReciprocal * largest) return out;
  Eigen::Matrix<double, Columns, 1> e0 = Eigen::Matrix<double, Columns, 1>::Zero();
  e0(0) = 1.0;
  const Eigen::Matrix<double, Columns, 1> c = ldlt.solve(e0);
  out.weight = design * c;
  out.variance_factor = out.weight.squaredNorm();
  out.ok = true;
  return out;
}

Prediction predict_centre(const Point3& centre, const std::array<Point3, LocalPredictionNoise::kNeighbours>& around) {
  constexpr int K = LocalPredictionNoise::kNeighbours;
  Eigen::Matrix<double, K, 3> d;
  for (int j = 0; j < K; ++j) d.row(j) = (around[static_cast<std::size_t>(j)] - centre).transpose();
  const double radius = d.rowwise().norm().maxCoeff();
  if (!(radius > 0.0)) return {};
  d /= radius;
  const Eigen::Vector3d mean = d.colwise().mean().transpose();
  const Eigen::Matrix3d scatter = (d.rowwise() - mean.transpose()).transpose() * (d.rowwise() - mean.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> axes;
  axes.computeDirect(scatter);  // eigenvalues ascending
  const Eigen::Vector3d first = axes.eigenvectors().col(2), second = axes.eigenvectors().col(1);
  const Eigen::Matrix<double, K, 1> s = d * first, t = d * second;
  if (axes.eigenvalues()(1) < kLineSpreadRatio * kLineSpreadRatio * axes.eigenvalues()(2)) {
    Eigen::Matrix<double, K, 3> design;
    design << Eigen::Matrix<double, K, 1>::Ones(), s, s.cwiseProduct(s);
    return predict_from<3>(design);
  }
  Eigen::Matrix<double, K, 6> design;
  design << Eigen::Matrix<double, K, 1>::Ones(), s, t, s.cwiseProduct(s), s.cwiseProduct(t), t.cwiseProduct(t);
  return predict_from<6>(design);
}

}  // namespace

LocalPredictionNoise::LocalPredictionNoise(std::span<const Point3> points, std::span<const double> weights,
                                           std::size_t max_points)
    : max_points_(max_points) {
  constexpr auto K = static_cast<std::size_t>(kNeighbours);
  auto used = [&](std::size_t k) { return weights.empty() || weights[k] > 0.0; };
  // The points taken part: the used ones, every m-th of them over max_points.
  std::vector<std::uint32_t> taken;
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (used(k)) taken.push_back(static_cast<std::uint32_t>(k));
  }
  if (taken.size() > max_points) {
    const std::size_t m = (taken.size() + max_points - 1) / max_points;
    std::size_t n = 0;
    for (std::size_t i = 0; i < taken.size(); i += m) taken[n++] = taken[i];
    taken.resize(n);
  }
  if (taken.size() <= K) return;
  std::vector<Point3> at(taken.size());
  for (std::size_t i = 0; i < taken.size(); ++i) at[i] = points[taken[i]];
  const std::vector<std::uint32_t> near = geometry::nearest_others(at, kNeighbours);

  std::vector<Prediction> predictions(taken.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, taken.size(), 256), [&](const auto& range) {
    std::array<Point3, K> around;
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      for (std::size_t j = 0; j < K; ++j) around[j] = at[near[i * K + j]];
      predictions[i] = predict_centre(at[i], around);
    }
  });
  for (std::size_t i = 0; i < taken.size(); ++i) {
    if (!predictions[i].ok) continue;
    tested_.push_back(taken[i]);
    for (std::size_t j = 0; j < K; ++j) {
      neighbour_.push_back(taken[near[i * K + j]]);
      weight_.push_back(static_cast<float>(predictions[i].weight(static_cast<Eigen::Index>(j))));
    }
    scale_.push_back(static_cast<float>(1.0 / std::sqrt(1.0 + predictions[i].variance_factor)));
  }
}

double LocalPredictionNoise::neighbour_correlation(std::span<const double> residuals) const {
  constexpr auto K = static_cast<std::size_t>(kNeighbours);
  double cross = 0.0, own = 0.0;
  for (std::size_t i = 0; i < tested_.size(); ++i) {
    const double r = residuals[tested_[i]];
    own += r * r;
    for (std::size_t j = 0; j < K; ++j) cross += r * residuals[neighbour_[i * K + j]];
  }
  return own > 0.0 ? cross / (static_cast<double>(K) * own) : 0.0;
}

std::vector<double> LocalPredictionNoise::prediction_errors(std::span<const double> residuals) const {
  constexpr auto K = static_cast<std::size_t>(kNeighbours);
  std::vector<double> e(tested_.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tested_.size(), 1024), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      double predicted = 0.0;
      for (std::size_t j = 0; j < K; ++j) predicted += static_cast<double>(weight_[i * K + j]) * residuals[neighbour_[i * K + j]];
      e[i] = std::abs(residuals[tested_[i]] - predicted) * static_cast<double>(scale_[i]);
    }
  });
  return e;
}

std::size_t LocalPredictionNoise::standing_out(std::span<const double> residuals, double sigmas, double floor) const {
  if (tested_.empty()) return 0;
  const std::vector<double> e = prediction_errors(residuals);
  const double bound = std::max(sigmas * sigma_of(e, residuals.size()), floor);
  return static_cast<std::size_t>(std::count_if(e.begin(), e.end(), [&](double x) { return !(x <= bound); }));
}

std::vector<char> LocalPredictionNoise::isolated_errors(std::span<const double> residuals, double sigmas,
                                                        double floor) const {
  constexpr auto K = static_cast<std::size_t>(kNeighbours);
  std::vector<char> out(residuals.size(), 0);
  if (tested_.empty()) return out;
  const std::vector<double> e = prediction_errors(residuals);
  const double bound = std::max(sigmas * sigma_of(e, residuals.size()), floor);
  // (An untested neighbour's error is taken as zero: it cannot be compared.)
  std::vector<double> at_point(residuals.size(), 0.0);
  for (std::size_t i = 0; i < tested_.size(); ++i) at_point[tested_[i]] = e[i];
  for (std::size_t i = 0; i < tested_.size(); ++i) {
    if (e[i] <= bound) continue;
    bool largest = true;
    for (std::size_t j = 0; j < K && largest; ++j) largest = e[i] >= at_point[neighbour_[i * K + j]];
    out[tested_[i]] = largest;
  }
  return out;
}

double LocalPredictionNoise::sigma(std::span<const double> residuals) const {
  if (tested_.empty()) return std::numeric_limits<double>::infinity();
  return sigma_of(prediction_errors(residuals), residuals.size());
}

double LocalPredictionNoise::sigma_of(const std::vector<double>& e, std::size_t n_points) const {
  constexpr auto K = static_cast<std::size_t>(kNeighbours);
  std::vector<double> work = e;
  const double first = geometry::kMadToSigma * geometry::median_in_place(work);
  // A gross error spoils the prediction of every point that has it among its neighbours (3 % of such points spoil
  // a third of the predictions; the median then reads 1.6 σ): the points whose error stands out beyond
  // kGrossErrorSigmas and beyond each of their neighbours' are taken for gross errors, and the predictions
  // they enter are left out.
  std::vector<char> gross(n_points, 0);
  std::vector<double> at_point(n_points, 0.0);
  for (std::size_t i = 0; i < tested_.size(); ++i) at_point[tested_[i]] = e[i];
  bool any = false;
  for (std::size_t i = 0; i < tested_.size(); ++i) {
    if (!(e[i] > kGrossErrorSigmas * first)) continue;
    bool largest = true;
    for (std::size_t j = 0; j < K && largest; ++j) largest = e[i] >= at_point[neighbour_[i * K + j]];
    if (largest) gross[tested_[i]] = 1;
    any = any || largest;
  }
  if (!any) return first;
  work.clear();
  for (std::size_t i = 0; i < tested_.size(); ++i) {
    bool clean = !gross[tested_[i]];
    for (std::size_t j = 0; j < K && clean; ++j) clean = !gross[neighbour_[i * K + j]];
    if (clean) work.push_back(e[i]);
  }
  return work.empty() ? first : geometry::kMadToSigma * geometry::median_in_place(work);
}

std::vector<char> peel_isolated_errors(const LocalPredictionNoise& local, std::span<const Point3> points,
                                       std::span<const double> residuals, double sigmas, double floor) {
  // Two gross errors among each other's neighbours spoil each other's prediction: only the larger stands out
  // alone. Screened again without the points found, until none is found (or kScreenPasses).
  std::vector<char> out(points.size(), 0);
  std::vector<double> weights(points.size(), 1.0);
  for (int pass = 0; pass < kScreenPasses; ++pass) {
    const std::vector<char> found = pass == 0 ? local.isolated_errors(residuals, sigmas, floor)
                                              : LocalPredictionNoise(points, weights, local.max_points())
                                                    .isolated_errors(residuals, sigmas, floor);
    bool more = false;
    for (std::size_t k = 0; k < found.size(); ++k) {
      if (!found[k] || out[k]) continue;
      out[k] = 1;
      weights[k] = 0.0;
      more = true;
    }
    if (!more) break;
  }
  return out;
}

GrossErrorScreen screen_for_gross_errors(const LocalPredictionNoise& local, const nurbs::Surface& s,
                                         std::span<const Point3> points, std::span<const SurfaceParameter> params,
                                         double sigmas, double floor, double peel_floor) {
  GrossErrorScreen out;
  const std::vector<double> residual = detail::along_normal(s, points, params, {}).residual;
  out.may_hold = local.tested() < points.size() || local.standing_out(residual, sigmas, floor) > 0;
  if (!out.may_hold) return out;
  out.isolated = peel_isolated_errors(local, points, residual, sigmas, std::max(floor, peel_floor));
  if (std::find(out.isolated.begin(), out.isolated.end(), 1) == out.isolated.end()) out.isolated.clear();
  return out;
}

}  // namespace probecomp::fitting
