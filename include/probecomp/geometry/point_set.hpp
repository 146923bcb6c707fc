#pragma once
// Whole-set views of a point cloud for cheap checks and starting guesses: a spread subset, and the principal axes
// with the spread along each. Non-finite points are left out of both.

#include <cstddef>
#include <span>
#include <vector>

#include "probecomp/geometry/types.hpp"

namespace probecomp::geometry {

// About k of the points, spread over the input in its order (every (n/k)-th, the finite ones among them).
[[nodiscard]] std::vector<Point3> spread_subset(std::span<const Point3> points, std::size_t k);
// The same, as the points' indices (for data that travel with the points).
[[nodiscard]] std::vector<std::size_t> spread_subset_indices(std::span<const Point3> points, std::size_t k);

struct PrincipalAxes {
  std::size_t count = 0;                 // finite points
  Point3 centroid = Point3::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // unit columns, by ascending spread
  Eigen::Vector3d spread = Eigen::Vector3d::Zero();     // RMS distance of the points along each axis, mm
};

// From the points' covariance (its eigenvectors and the square roots of its eigenvalues). count 0: no finite point.
[[nodiscard]] PrincipalAxes principal_axes(std::span<const Point3> points);

}  // namespace probecomp::geometry
