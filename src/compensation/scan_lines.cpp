#include "scan_lines.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "probecomp/geometry/point_tree.hpp"
#include "probecomp/geometry/statistics.hpp"

namespace probecomp::compensation::detail {

namespace {

// Neighbours that tell a point on a line (and its direction) and whose residuals' mean estimates the bias there:
// ±0.9 mm along a line sampled every 0.15 mm, short of the millimetres over which the bias varies. Measured on
// D500's eight draws, ±2u coverage of the contacts 84.9 % with the fit's u alone; with the bias estimate 92.4 % at
// 12 neighbours, 88.5 % at 24, 85.0 % at 48 (longer windows average the bias away).
constexpr int kNearLine = 12;
// That estimate is unbiased in its square but noisy point by point (σ/√12 = 1.3 µm at σ = 4.5 µm, against a bias of
// 1–1.5 µm rms), and ±2u missed where the bias was large and its estimate happened to be small: u takes the bias's
// local level instead, the root mean square of the estimates over a point's kBiasLevelNeighbours nearest (±4.7 mm
// along a line sampled every 0.15 mm). Over six noise draws, the lowest region's ±2u coverage (averaged over the
// draws): D212 74.4 -> 87.8 %, D500 87.3 -> 89.8 % (at 96 neighbours 90.2 and 89.2 %, at 48 86.8 and 90.1 %), with
// the same u's rms (1.44 and 1.84 µm).
constexpr int kBiasLevelNeighbours = 64;
// Line points sampled for the spacing's median.
constexpr std::size_t kSpacingSamples = 2000;

// Whether offset d from a point lies along its line (direction t, unit): within 60° of it (|cos| ≥ 1/2). The
// spacing is measured to points that do not; the unseen turn's window takes those that do.
bool lies_along(const Vector3& d, const Vector3& t) { return std::abs(d.dot(t)) >= 0.5 * d.norm(); }

}  // namespace

ScanLineDoubts scan_line_doubts(const nurbs::Surface& fit, const nurbs::Surface& start, std::span<const Point3> centres,
                                std::span<const fitting::SurfaceParameter> params, std::span<const double> residuals,
                                std::span<const double> weights, double sigma, double line_variance_ratio,
                                bool exact_data) {
  const std::size_t n = centres.size();
  ScanLineDoubts out{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0), 0.0};
  std::vector<Point3> kept;
  std::vector<double> kept_residual;
  std::vector<std::uint32_t> kept_index;
  for (std::size_t k = 0; k < n; ++k) {
    if (!weights.empty() && !(weights[k] > 0.0)) continue;
    kept.push_back(centres[k]);
    kept_residual.push_back(residuals[k]);
    kept_index.push_back(static_cast<std::uint32_t>(k));
  }
  if (kept.size() < static_cast<std::size_t>(kNearLine)) return out;
  const geometry::OwnedPointTree tree(std::move(kept));
  const std::vector<Point3>& pts = tree.cloud.points;

  // Each point's line direction (zero off lines), bias, and the distance to its farthest of those neighbours.
  std::vector<Vector3> direction(n, Vector3::Zero());
  std::vector<double> reach(n, 0.0);
  const double noise_of_mean = sigma * sigma / kNearLine;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
    std::uint32_t idx[kNearLine];
    double dist_sq[kNearLine];  // squared distances (nanoflann's L2 adaptor)
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(kNearLine);
      knn.init(idx, dist_sq);
      const double q[3] = {centres[k].x(), centres[k].y(), centres[k].z()};
      tree.tree.findNeighbors(knn, q, nanoflann::SearchParams());
      reach[k] = std::sqrt(dist_sq[kNearLine - 1]);
      Point3 mean = Point3::Zero();
      double m = 0.0;
      for (const std::uint32_t i : idx) {
        mean += pts[i];
        m += kept_residual[i];
      }
      mean /= kNearLine;
      m /= kNearLine;
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (const std::uint32_t i : idx) cov += (pts[i] - mean) * (pts[i] - mean).transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca;
      pca.computeDirect(cov);
      const Eigen::Vector3d e = pca.eigenvalues();  // ascending
      if (!(e[2] > 0.0 && e[1] < line_variance_ratio * e[2])) continue;
      direction[k] = pca.eigenvectors().col(2);
      out.bias[k] = std::sqrt(std::max(0.0, m * m - noise_of_mean));
    }
  });

  // Each point's bias: the level of the estimates around it.
  {
    std::vector<double> level(n, 0.0);
    std::vector<double> own(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) own[i] = out.bias[kept_index[i]] * out.bias[kept_index[i]];
    const std::size_t K = std::min<std::size_t>(kBiasLevelNeighbours, pts.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
      std::vector<std::uint32_t> idx(K);
      std::vector<double> dist_sq(K);  // squared distances (nanoflann's L2 adaptor)
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        if (!(direction[k].squaredNorm() > 0.0)) continue;
        nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(K);
        knn.init(idx.data(), dist_sq.data());
        const double q[3] = {centres[k].x(), centres[k].y(), centres[k].z()};
        tree.tree.findNeighbors(knn, q, nanoflann::SearchParams());
        double sum = 0.0;
        for (std::size_t j = 0; j < knn.size(); ++j) sum += own[idx[j]];
        level[k] = std::sqrt(sum / static_cast<double>(knn.size()));
      }
    });
    out.bias = std::move(level);
  }

  // The lines' spacing: from sampled points on lines, the distance to the nearest in-fit point that lies more
  // across the line than along it (its direction from the point over 60° from the line's), within a radius doubled
  // from twice the reach of the point's own neighbours (a radius search's cost is the points it finds; a k-nearest
  // one's grows as k², and lines 20 mm apart sampled every 0.05 mm would have needed k in the thousands).
  std::vector<std::size_t> sampled;
  {
    std::size_t on_lines = 0;
    for (const Vector3& t : direction) on_lines += t.squaredNorm() > 0.0;
    const std::size_t stride = std::max<std::size_t>(1, on_lines / kSpacingSamples);
    std::size_t seen = 0;
    for (std::size_t k = 0; k < n; ++k) {
      if (direction[k].squaredNorm() > 0.0 && seen++ % stride == 0) sampled.push_back(k);
    }
  }
  std::vector<double> across(sampled.size(), std::numeric_limits<double>::quiet_NaN());
  tbb::parallel_for(std::size_t{0}, sampled.size(), [&](std::size_t s) {
    const std::size_t k = sampled[s];
    std::vector<std::pair<std::uint32_t, double>> found;
    const double q[3] = {centres[k].x(), centres[k].y(), centres[k].z()};
    for (double radius = 2.0 * reach[k]; radius > 0.0; radius *= 2.0) {
      found.clear();
      tree.tree.radiusSearch(q, radius * radius, found, nanoflann::SearchParams(32, 0.0, false));  // squared radius
      double nearest = std::numeric_limits<double>::infinity();
      for (const auto& f : found) {
        const Vector3 d = pts[f.first] - centres[k];
        const double length = d.norm();
        if (length > 0.0 && !lies_along(d, direction[k])) nearest = std::min(nearest, length);
      }
      // (One within the radius is the nearest of all: any nearer one would be within it too.)
      if (std::isfinite(nearest)) {
        across[s] = nearest;
        break;
      }
      if (found.size() == pts.size()) break;
    }
  });
  std::erase_if(across, [](double d) { return !std::isfinite(d); });
  if (across.empty()) return out;
  out.line_spacing = geometry::median_in_place(across);

  // The deformation's curvature along each line, from the fit and the start at the point's parameters.
  const double half = 0.5 * out.line_spacing;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const Vector3& t = direction[k];
      if (!(t.squaredNorm() > 0.0)) continue;
      const nurbs::SurfaceD2 f = nurbs::derivatives_d2(fit, params[k].u, params[k].v);
      const nurbs::SurfaceD2 s = nurbs::derivatives_d2(start, params[k].u, params[k].v);
      const nurbs::UnitNormal nf = nurbs::unit_normal(fit, params[k].u, params[k].v, f.Su, f.Sv);
      if (nf.status == nurbs::UnitNormal::Status::Degenerate) continue;
      // The parameter direction (du, dv) along the line, per unit of arc length: least squares on [Su Sv].
      Eigen::Matrix<double, 3, 2> J;
      J << f.Su, f.Sv;
      const Eigen::Vector2d a = (J.transpose() * J).ldlt().solve(J.transpose() * t);
      const double speed = (J * a).norm();
      if (!(speed > 0.0)) continue;
      const Eigen::Vector2d d = a / speed;
      const Vector3 second = (f.Suu - s.Suu) * d[0] * d[0] + 2.0 * (f.Suv - s.Suv) * d[0] * d[1] + (f.Svv - s.Svv) * d[1] * d[1];
      out.normal_angle[k] = std::atan(std::abs(second.dot(nf.n)) * half);
    }
  });
  if (!exact_data) return out;

  // On exact data, the largest turn along the line within one spacing. Not on noisy lines: there the fit's
  // curvature along a line carries its smoothing of the noise, and the window's largest value raised u without
  // covering more (S29's crease at σ = 4.5 µm: mean u 2.28 -> 5.80 µm, worst region 86.5 % either way; S03 and S30,
  // features on noisy lines: u 1.50 -> 2.28 and 1.07 -> 2.00 µm, their worst regions unchanged).
  std::vector<double> widest(n, 0.0);
  const double window = out.line_spacing;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto& range) {
    std::vector<std::pair<std::uint32_t, double>> found;
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const Vector3& t = direction[k];
      if (!(t.squaredNorm() > 0.0)) continue;
      found.clear();
      const double q[3] = {centres[k].x(), centres[k].y(), centres[k].z()};
      tree.tree.radiusSearch(q, window * window, found, nanoflann::SearchParams(32, 0.0, false));  // squared radius
      double largest = out.normal_angle[k];
      for (const auto& f : found) {
        const Vector3 d = pts[f.first] - centres[k];
        if (lies_along(d, t)) largest = std::max(largest, out.normal_angle[kept_index[f.first]]);
      }
      widest[k] = largest;
    }
  });
  out.normal_angle = std::move(widest);
  return out;
}

std::vector<int> scan_line_numbers(std::span<const Point3> centres, int min_lines) {
  // A step between lines is the lines' spacing, millimetres; along them a scanning probe's points are tenths of a
  // millimetre apart: any factor between the two tells them apart.
  constexpr double kLineBreakSteps = 5.0;
  constexpr std::size_t kMinLinePoints = 10;
  const std::size_t n = centres.size();
  if (n < 2 * kMinLinePoints) return {};
  std::vector<double> step(n - 1);
  for (std::size_t k = 0; k + 1 < n; ++k) step[k] = (centres[k + 1] - centres[k]).norm();
  std::vector<double> sorted = step;
  const double typical = geometry::median_in_place(sorted);
  if (!(typical > 0.0)) return {};
  std::vector<int> out(n, 0);
  std::vector<double> lengths;
  int line = 0;
  std::size_t begun = 0;
  for (std::size_t k = 0; k < n; ++k) {
    out[k] = line;
    if (k + 1 == n || step[k] > kLineBreakSteps * typical) {
      lengths.push_back(static_cast<double>(k + 1 - begun));
      begun = k + 1;
      ++line;
    }
  }
  if (line < min_lines || geometry::median_in_place(lengths) < static_cast<double>(kMinLinePoints)) return {};
  return out;
}

}  // namespace probecomp::compensation::detail
