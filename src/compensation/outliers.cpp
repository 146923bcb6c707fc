#include "compensation/outliers.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "nurbs/point_tree.hpp"

namespace probecomp::compensation {

namespace {

constexpr double kMadToSigma = 1.4826;
// Neighbours departing from the first local fit by more than this many times the median departure are left out
// of the second (an outlier among the neighbours must not bend the prediction).
constexpr double kRefitCut = 3.0;

double median_of(std::vector<double> x) {
  if (x.empty()) return 0.0;
  const std::size_t m = x.size() / 2;
  std::nth_element(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(m), x.end());
  return x[m];
}

}  // namespace

LocalOutliers local_outliers(std::span<const Point3> points, std::span<const double> residuals,
                             std::span<const Vector3> normals, const LocalOutlierOptions& options) {
  LocalOutliers out;
  out.outlier.assign(points.size(), 0);
  const std::size_t k = static_cast<std::size_t>(options.neighbours) + 1;  // the point itself comes back too
  if (points.size() < k) return out;
  nurbs::PointCloud cloud{std::vector<Point3>(points.begin(), points.end())};
  nurbs::PointTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();

  std::vector<double> departure(points.size(), 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 512), [&](const auto& range) {
    std::vector<std::uint32_t> index(k);
    std::vector<double> dist_sq(k);  // squared (nanoflann)
    Eigen::MatrixXd A(static_cast<Eigen::Index>(k), 6);
    Eigen::VectorXd b(static_cast<Eigen::Index>(k));
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const std::size_t found = tree.knnSearch(points[i].data(), k, index.data(), dist_sq.data());
      // The chart: the plane across the model's normal at the point, scaled by the neighbourhood's radius so
      // that the quadratic's columns are of one size.
      const Vector3 n = normals[i].normalized();
      const Vector3 t1 = n.unitOrthogonal(), t2 = n.cross(t1);
      const double h = std::max(std::sqrt(dist_sq[found - 1]), 1e-12);
      Eigen::Index rows = 0;
      for (std::size_t a = 0; a < found; ++a) {
        if (index[a] == i) continue;
        const Vector3 d = (points[index[a]] - points[i]) / h;
        const double x = d.dot(t1), y = d.dot(t2);
        A.row(rows) << 1.0, x, y, x * x, x * y, y * y;
        b(rows) = residuals[index[a]];
        ++rows;
      }
      auto predict = [&](const Eigen::MatrixXd& M, const Eigen::VectorXd& v) {
        // Minimum-norm least squares: neighbours along one scan line leave the cross terms free.
        const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(M);
        const Eigen::VectorXd c = cod.solve(v);
        return std::pair{c, c(0)};
      };
      const Eigen::MatrixXd M = A.topRows(rows);
      const Eigen::VectorXd v = b.head(rows);
      auto [c, at] = predict(M, v);
      // Second pass without the neighbours the first fit explains worst.
      const Eigen::VectorXd e = (M * c - v).cwiseAbs();
      std::vector<double> es(e.data(), e.data() + e.size());
      const double cut = kRefitCut * median_of(es);
      if (cut > 0.0) {
        Eigen::MatrixXd M2(rows, 6);
        Eigen::VectorXd v2(rows);
        Eigen::Index kept = 0;
        for (Eigen::Index r = 0; r < rows; ++r) {
          if (e(r) > cut) continue;
          M2.row(kept) = M.row(r);
          v2(kept) = v(r);
          ++kept;
        }
        if (kept >= 6) at = predict(M2.topRows(kept), v2.head(kept)).second;
      }
      departure[i] = residuals[i] - at;
    }
  });
  std::vector<double> size(departure.size());
  for (std::size_t i = 0; i < departure.size(); ++i) size[i] = std::abs(departure[i]);
  out.scale = kMadToSigma * median_of(size);
  const double bound = std::max(options.sigmas * out.scale, options.min_departure);
  for (std::size_t i = 0; i < departure.size(); ++i) {
    out.outlier[i] = std::abs(departure[i]) > bound;
    out.count += out.outlier[i];
  }
  return out;
}

}  // namespace probecomp::compensation
