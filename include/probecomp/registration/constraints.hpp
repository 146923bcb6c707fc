#pragma once
// Which rigid motions the data fix. Point-to-plane alignment sees a motion only through the normal
// displacements it causes, n_i · (ω × (x_i − c) + v); motions that move no point along its normal (sliding
// on a plane, turning a cylinder about its axis or sliding along it, turning a sphere) cannot be measured.
// They show up as (near-)zero eigenvalues of the 6 × 6 information matrix H = Σ w_i J_i J_iᵀ with
// J_i = ((x_i − c) × n_i / L, n_i): the twist about the points' centroid c with the rotation scaled by their
// RMS radius L, so that rotations and translations are compared in millimetres of point motion.

#include <vector>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "probecomp/geometry/types.hpp"
#include "probecomp/geometry/rigid.hpp"

namespace probecomp::registration {

// An eigenvalue of H below this fraction of the largest counts as unconstrained: the motion would be fixed
// 1000 times (√1e6) less precisely than the best-fixed one, so any noise or model error would drive it.
inline constexpr double kUnconstrainedRatio = 1e-6;

struct FreeMotion {
  enum class Kind { Translation, Rotation };
  Kind kind = Kind::Translation;
  Vector3 direction = Vector3::Zero();  // translation direction, or rotation axis direction (unit)
  Point3 through = Point3::Zero();      // a point on the rotation axis (rotations only)
};

struct Constraints {
  int fixed = 6;                  // degrees of freedom the data determine
  std::vector<FreeMotion> free;   // the others, as pure translations first, then rotations
  double smallest_ratio = 1.0;    // smallest eigenvalue of H over the largest among the fixed ones
  // Orthonormal basis (columns, in the scaled twist coordinates) of the free motions: updates are kept out of it.
  Eigen::Matrix<double, 6, Eigen::Dynamic> free_basis;
  Point3 centre = Point3::Zero();
  double length = 1.0;
  // H⁺ over the fixed motions (Σ e_k e_kᵀ / λ_k over H's eigenpairs above the free ones): the covariance of the
  // estimated scaled twist per unit residual variance (Gauss–Newton; the free motions, held, contribute none).
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();

  [[nodiscard]] bool complete() const { return fixed == 6; }
};

// The variance, per unit residual variance, of the registered model's position along the unit normal n at x (both
// in the frame H was built in, the CAD frame for register_points): J·covariance·Jᵀ with J = ((x − c) × n / L, n).
// Times the registration's residual variance, the registration's share of a deviation's variance there.
[[nodiscard]] double normal_variance(const Constraints& c, const Point3& x, const Vector3& n);

// H in the scaled twist coordinates about `centre` (RMS radius `length`); see above.
[[nodiscard]] Constraints analyse_constraints(const Eigen::Matrix<double, 6, 6>& H, const Point3& centre, double length);
// The same from H's eigen-decomposition, for a caller that solves with it too.
[[nodiscard]] Constraints analyse_constraints(const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>& eig,
                                              const Point3& centre, double length);

// Converts a scaled twist δ = (L·ω, v) about the centre into the rigid motion x ↦ c + Rot(ω)(x − c) + v.
[[nodiscard]] geometry::RigidTransform motion_about(const geometry::Twist& delta, const Point3& centre, double length);
// The inverse: the scaled twist of a rigid motion about the centre.
[[nodiscard]] geometry::Twist scaled_twist_of(const geometry::RigidTransform& motion, const Point3& centre, double length);

}  // namespace probecomp::registration
