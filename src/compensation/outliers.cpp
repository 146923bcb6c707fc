#include "probecomp/compensation/outliers.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <cstdint>
#include <algorithm>
#include <cmath>

#include "probecomp/geometry/point_tree.hpp"
#include "probecomp/geometry/statistics.hpp"

namespace probecomp::compensation {

namespace {

using geometry::kMadToSigma;
using geometry::upper_median_in_place;
// Neighbours departing from the first local fit by more than this many times the median departure are left out
// of the second (an outlier among the neighbours must not bend the prediction).
constexpr double kRefitCut = 3.0;

// Relative ridge on the local quadratic's normal equations (of their trace): far below any determined
// coefficient's weight, enough to make a rank-deficient neighbourhood solvable.
constexpr double kRidge = 1e-10;

}  // namespace

LocalOutliers local_outliers(std::span<const Point3> points, std::span<const double> residuals,
                             std::span<const Vector3> normals, const LocalOutlierOptions& options) {
  LocalOutliers out;
  out.outlier.assign(points.size(), 0);
  const std::size_t k = static_cast<std::size_t>(options.neighbours) + 1;  // the point itself comes back too
  if (points.size() < k) return out;
  out.nearest.assign(points.size(), 0);
  geometry::PointCloud cloud{std::vector<Point3>(points.begin(), points.end())};
  geometry::PointTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();

  std::vector<double> departure(points.size(), 0.0);
  using Row = Eigen::Matrix<double, 6, 1>;
  // A least-squares quadratic from the rows flagged in `use`, by its 6 × 6 normal equations with a whisker of
  // ridge (neighbours along one scan line leave the cross terms free; the ridge keeps them at zero).
  auto quadratic = [](const std::vector<Row>& phi, const std::vector<double>& value, const std::vector<char>& use) {
    Eigen::Matrix<double, 6, 6> N = Eigen::Matrix<double, 6, 6>::Zero();
    Row g = Row::Zero();
    for (std::size_t a = 0; a < phi.size(); ++a) {
      if (!use[a]) continue;
      N.selfadjointView<Eigen::Lower>().rankUpdate(phi[a]);
      g += value[a] * phi[a];
    }
    N.diagonal().array() += kRidge * N.trace();
    return Row(N.selfadjointView<Eigen::Lower>().ldlt().solve(g));
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 512), [&](const auto& range) {
    std::vector<std::uint32_t> index(k);
    std::vector<double> dist_sq(k);  // squared (nanoflann)
    std::vector<Row> phi;
    std::vector<double> value, miss, scratch;
    std::vector<char> use;
    for (std::size_t pos = range.begin(); pos != range.end(); ++pos) {
      // In the tree's own (leaf) order: consecutive queries visit the same nodes, which stay in cache.
      const std::size_t i = tree.vAcc[pos];
      const std::size_t found = tree.knnSearch(points[i].data(), k, index.data(), dist_sq.data());
      out.nearest[i] = index[0] != i ? index[0] : index[1];
      // The chart: the plane across the model's normal at the point, scaled by the neighbourhood's radius so
      // that the quadratic's columns are of one size.
      const Vector3 n = normals[i].normalized();
      const Vector3 t1 = n.unitOrthogonal(), t2 = n.cross(t1);
      const double h = std::max(std::sqrt(dist_sq[found - 1]), 1e-12);
      phi.clear();
      value.clear();
      for (std::size_t a = 0; a < found; ++a) {
        if (index[a] == i) continue;
        const Vector3 d = (points[index[a]] - points[i]) / h;
        const double x = d.dot(t1), y = d.dot(t2);
        phi.push_back((Row() << 1.0, x, y, x * x, x * y, y * y).finished());
        value.push_back(residuals[index[a]]);
      }
      use.assign(phi.size(), 1);
      Row c = quadratic(phi, value, use);
      // Second pass without the neighbours the first fit explains worst.
      miss.resize(phi.size());
      for (std::size_t a = 0; a < phi.size(); ++a) miss[a] = std::abs(phi[a].dot(c) - value[a]);
      scratch = miss;
      const double cut = kRefitCut * upper_median_in_place(scratch);
      int kept = 0;
      for (std::size_t a = 0; a < phi.size(); ++a) {
        use[a] = miss[a] <= cut;
        kept += use[a];
      }
      if (cut > 0.0 && kept >= 6 && kept < static_cast<int>(phi.size())) c = quadratic(phi, value, use);
      departure[i] = residuals[i] - c(0);
    }
  });
  std::vector<double> size(departure.size());  // |departure|, then partly reordered by upper_median_in_place
  for (std::size_t i = 0; i < departure.size(); ++i) size[i] = std::abs(departure[i]);
  out.scale = kMadToSigma * upper_median_in_place(size);
  const double bound = std::max(options.sigmas * out.scale, options.min_departure);
  for (std::size_t i = 0; i < departure.size(); ++i) {
    out.outlier[i] = std::abs(departure[i]) > bound;
    out.count += out.outlier[i];
  }
  return out;
}

}  // namespace probecomp::compensation
