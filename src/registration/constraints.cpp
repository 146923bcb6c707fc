#include "probecomp/registration/constraints.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace probecomp::registration {

double normal_variance(const Constraints& c, const Point3& x, const Vector3& n) {
  Eigen::Matrix<double, 6, 1> J;
  J.head<3>() = (x - c.centre).cross(n) / c.length;
  J.tail<3>() = n;
  return J.dot(c.covariance * J);
}

Constraints analyse_constraints(const Eigen::Matrix<double, 6, 6>& H, const Point3& centre, double length) {
  return analyse_constraints(Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(H), centre, length);
}

Constraints analyse_constraints(const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>& eig,
                                const Point3& centre, double length) {
  Constraints c;
  c.centre = centre;
  c.length = length;
  const Eigen::Matrix<double, 6, 1> lambda = eig.eigenvalues();  // ascending
  const double largest = lambda(5);
  int free = 0;
  while (free < 6 && !(lambda(free) > kUnconstrainedRatio * largest)) ++free;
  c.fixed = 6 - free;
  c.smallest_ratio = largest > 0.0 && free < 6 ? lambda(free) / largest : 0.0;
  c.free_basis = eig.eigenvectors().leftCols(free);
  for (int k = free; k < 6; ++k) {
    c.covariance += eig.eigenvectors().col(k) * eig.eigenvectors().col(k).transpose() / lambda(k);
  }
  if (free == 0) return c;

  // A readable basis of the same subspace: the pure translations in it (combinations whose rotation part
  // vanishes: the null space of its top three rows), then the rest, each a rotation about some axis.
  const Eigen::MatrixXd N = c.free_basis;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(N.topRows(3), Eigen::ComputeFullV);
  const Eigen::VectorXd s = svd.singularValues();
  int rotations = 0;
  for (int k = 0; k < s.size(); ++k) rotations += s(k) > 1e-6;
  const Eigen::MatrixXd V = svd.matrixV();  // free × free; the first `rotations` columns have a rotation part
  for (int k = rotations; k < free; ++k) {
    const Eigen::Matrix<double, 6, 1> e = N * V.col(k);
    c.free.push_back({FreeMotion::Kind::Translation, e.tail<3>().normalized(), Point3::Zero()});
  }
  for (int k = 0; k < rotations; ++k) {
    Eigen::Matrix<double, 6, 1> e = N * V.col(k);
    const Vector3 w = e.head<3>() / length;
    Vector3 v = e.tail<3>();
    // Remove the free translations' share of v (a screw along a free translation is the same freedom).
    for (const FreeMotion& t : c.free) {
      if (t.kind == FreeMotion::Kind::Translation) v -= t.direction.dot(v) * t.direction;
    }
    // The axis of x ↦ ω × (x − c) + v: the points whose velocity is parallel to ω.
    const Point3 through = centre + w.cross(v) / w.squaredNorm();
    c.free.push_back({FreeMotion::Kind::Rotation, w.normalized(), through});
  }
  return c;
}

geometry::RigidTransform motion_about(const geometry::Twist& delta, const Point3& centre, double length) {
  geometry::Twist xi;
  xi.head<3>() = delta.head<3>() / length;
  xi.tail<3>().setZero();
  const geometry::RigidTransform R = geometry::from_twist(xi);
  geometry::RigidTransform T = geometry::RigidTransform::Identity();
  T.linear() = R.linear();
  T.translation() = centre - R.linear() * centre + delta.tail<3>();
  return T;
}

geometry::Twist scaled_twist_of(const geometry::RigidTransform& motion, const Point3& centre, double length) {
  const geometry::Twist xi = geometry::to_twist(motion);
  geometry::Twist delta;
  delta.head<3>() = xi.head<3>() * length;
  delta.tail<3>() = motion * centre - centre;
  return delta;
}

}  // namespace probecomp::registration
