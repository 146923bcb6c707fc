#include "probecomp/geometry/point_set.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>

namespace probecomp::geometry {

std::vector<std::size_t> spread_subset_indices(std::span<const Point3> points, std::size_t k) {
  std::vector<std::size_t> out;
  const std::size_t step = std::max<std::size_t>(1, points.size() / std::max<std::size_t>(k, 1));
  for (std::size_t i = 0; i < points.size(); i += step) {
    if (points[i].allFinite()) out.push_back(i);
  }
  return out;
}

std::vector<Point3> spread_subset(std::span<const Point3> points, std::size_t k) {
  std::vector<Point3> out;
  for (std::size_t i : spread_subset_indices(points, k)) out.push_back(points[i]);
  return out;
}

PrincipalAxes principal_axes(std::span<const Point3> points) {
  PrincipalAxes a;
  for (const Point3& p : points) {
    if (!p.allFinite()) continue;
    a.centroid += p;
    ++a.count;
  }
  if (a.count == 0) return a;
  a.centroid /= static_cast<double>(a.count);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Point3& p : points) {
    if (p.allFinite()) covariance += (p - a.centroid) * (p - a.centroid).transpose();
  }
  covariance /= static_cast<double>(a.count);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(covariance);  // eigenvalues ascending
  a.axes = eig.eigenvectors();
  a.spread = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return a;
}

}  // namespace probecomp::geometry
