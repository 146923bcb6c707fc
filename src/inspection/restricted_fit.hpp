#pragma once
// Least-squares fit of points to a model's faces by rigid motions restricted to a subspace (Gauss–Newton on the
// point-to-surface distances): the step every datum of a reference frame takes, and the best fit of a
// characteristic's points in the motions its datums leave free. Private to the inspection layer.

#include <span>
#include <vector>

#include <Eigen/Core>

#include "probecomp/cad/locator.hpp"
#include "probecomp/geometry/rigid.hpp"

namespace probecomp::inspection {

using MotionBasis = Eigen::Matrix<double, 6, Eigen::Dynamic>;

struct RestrictedFit {
  bool converged = false;
  int iterations = 0;
  geometry::RigidTransform motion = geometry::RigidTransform::Identity();  // applied to the points
  std::vector<cad::ModelPoint> feet;  // of the moved points, one each (a point off its faces' edge is on_trim_edge)
  std::vector<int> used;              // the points fitted: found, not past an edge
  Eigen::MatrixXd J;                  // used × 6: ∂distance/∂(scaled twist) at the end
  Eigen::VectorXd d;                  // used: signed distances at the end, mm
  double size = 0.0;                  // with the size free: the mean distance taken out, mm
  // H = AᵀA over the basis (A = J·basis, centred with the size free): its eigenvectors split into the directions
  // the points fix (columns of `fixed`, eigenvalues `lambda`) and those they do not (`free`), in basis coordinates.
  Eigen::MatrixXd A;
  Eigen::MatrixXd fixed, free;
  Eigen::VectorXd lambda;
};

// Moves `points` within the motions spanned by `basis` (orthonormal columns, scaled twists about centre/length) to
// minimise Σ (distanceᵢ − size)², size being 0 unless `size_free`. Directions whose eigenvalue of H is below
// registration::kUnconstrainedRatio of the largest are not moved.
[[nodiscard]] RestrictedFit fit_in_motions(const cad::ModelLocator& faces, std::span<const Point3> points,
                                           const MotionBasis& basis, const Point3& centre, double length,
                                           bool size_free);

}  // namespace probecomp::inspection
