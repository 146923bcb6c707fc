#pragma once
// Rigid motions: the small-motion (twist) parametrisation ICP solves for, and the rotation-angle convention
// of the registration reports (DESIGN.md §3, the paper's Table 1: rotations about X, Y, Z in degrees).

#include <Eigen/Geometry>

#include "probecomp/geometry/types.hpp"

namespace probecomp::geometry {

// A proper rigid motion x ↦ R·x + t (no scaling, det R = +1).
using RigidTransform = Eigen::Isometry3d;
// A twist (ω, v): rotation vector ω (radians, axis × angle) then translation v (mm).
using Twist = Eigen::Matrix<double, 6, 1>;

// exp of the twist as used by ICP updates: rotation by |ω| about the axis ω/|ω| (Rodrigues), then
// translation by v, i.e. x ↦ Rot(ω)·x + v. Exact for any size, not linearised.
[[nodiscard]] RigidTransform from_twist(const Twist& xi);
// The inverse of from_twist: ω from the rotation's angle-axis (angle in [0, π]), v = t.
[[nodiscard]] Twist to_twist(const RigidTransform& T);

// The pose parameters of the reports: T = Translation(t) · Rz(rz) · Ry(ry) · Rx(rx) (rotations about the
// fixed X, then Y, then Z axes), angles in degrees, t in mm.
struct Pose {
  double rx = 0.0, ry = 0.0, rz = 0.0;  // degrees
  Vector3 t = Vector3::Zero();          // mm
};
[[nodiscard]] RigidTransform from_pose(const Pose& pose);
// Angles in (−180°, 180°]; ry in [−90°, 90°] (away from ry = ±90°, where X and Z rotations coincide).
[[nodiscard]] Pose to_pose(const RigidTransform& T);

// The largest distance a point within `radius` of `centre` moves under T.
[[nodiscard]] double largest_motion(const RigidTransform& T, const Point3& centre, double radius);

}  // namespace probecomp::geometry
