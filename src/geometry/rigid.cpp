#include "probecomp/geometry/rigid.hpp"

#include <cmath>
#include <numbers>

namespace probecomp::geometry {

RigidTransform from_twist(const Twist& xi) {
  const Vector3 w = xi.head<3>();
  const double angle = w.norm();
  RigidTransform T = RigidTransform::Identity();
  // Below this angle (radians) the axis is meaningless but the rotation is I + [ω]× to within rounding:
  // the next Rodrigues term, |ω|²/2, is under 1e-32.
  if (angle > 1e-16) T.linear() = Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
  T.translation() = xi.tail<3>();
  return T;
}

Twist to_twist(const RigidTransform& T) {
  const Eigen::AngleAxisd aa(T.rotation());
  Twist xi;
  xi.head<3>() = aa.angle() * aa.axis();
  xi.tail<3>() = T.translation();
  return xi;
}

RigidTransform from_pose(const Pose& pose) {
  RigidTransform T = RigidTransform::Identity();
  T.linear() = (Eigen::AngleAxisd(pose.rz * kDegree, Vector3::UnitZ()) *
                Eigen::AngleAxisd(pose.ry * kDegree, Vector3::UnitY()) *
                Eigen::AngleAxisd(pose.rx * kDegree, Vector3::UnitX()))
                   .toRotationMatrix();
  T.translation() = pose.t;
  return T;
}

Pose to_pose(const RigidTransform& T) {
  // R = Rz·Ry·Rx: R(2,0) = −sin ry, R(2,1) = cos ry sin rx, R(2,2) = cos ry cos rx, R(1,0) = sin rz cos ry,
  // R(0,0) = cos rz cos ry.
  const Eigen::Matrix3d R = T.rotation();
  Pose p;
  p.ry = std::atan2(-R(2, 0), std::hypot(R(2, 1), R(2, 2))) / kDegree;
  p.rx = std::atan2(R(2, 1), R(2, 2)) / kDegree;
  p.rz = std::atan2(R(1, 0), R(0, 0)) / kDegree;
  p.t = T.translation();
  return p;
}

double largest_motion(const RigidTransform& T, const Point3& centre, double radius) {
  // x = centre + e with |e| ≤ radius: T·x − x = (T·centre − centre) + (R − I)·e, and |(R − I)·e| ≤
  // 2 sin(θ/2)·|e|.
  const double angle = Eigen::AngleAxisd(T.rotation()).angle();
  return (T * centre - centre).norm() + 2.0 * std::sin(0.5 * angle) * radius;
}

}  // namespace probecomp::geometry
