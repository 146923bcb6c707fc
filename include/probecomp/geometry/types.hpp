#pragma once
// Plain geometric value types shared by the kernel. Lengths are millimetres.

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <limits>
#include <numbers>

namespace probecomp {

using Point3 = Eigen::Vector3d;
using Vector3 = Eigen::Vector3d;
// A control point in homogeneous form (w·x, w·y, w·z, w): NURBS are B-splines in this space.
using HomogeneousPoint = Eigen::Vector4d;

// One degree in radians: angles are given in degrees (poses, arcs, the shapes' directions), computed in radians.
inline constexpr double kDegree = std::numbers::pi / 180.0;

struct BoundingBox {
  Point3 min = Point3::Constant(std::numeric_limits<double>::infinity());
  Point3 max = Point3::Constant(-std::numeric_limits<double>::infinity());

  void extend(const Point3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  [[nodiscard]] bool contains(const Point3& p, double tolerance = 0.0) const {
    return (p.array() >= min.array() - tolerance).all() && (p.array() <= max.array() + tolerance).all();
  }
  [[nodiscard]] double diagonal() const { return (max - min).norm(); }
  // The squared distance from p to the box (0 inside): a lower bound on the distance to anything in it, squared.
  [[nodiscard]] double squared_distance(const Point3& p) const {
    return (min - p).cwiseMax(p - max).cwiseMax(0.0).squaredNorm();
  }
};

}  // namespace probecomp
