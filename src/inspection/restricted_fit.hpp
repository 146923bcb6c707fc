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

// Those faces of `nominal` alone, as a model to fit a datum's or a characteristic's points to.
[[nodiscard]] cad::Model faces_of(const cad::Model& nominal, const std::vector<int>& faces);

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

namespace probecomp::inspection {

// The tangent fit (ISO 5459's constrained minimax; ASME Y14.5.1): from where the least-squares fit left `points`,
// moved within `fixed` (the directions that fit found fixed), so that every point lies on the material side of the
// faces and, with the size free (a hole, a pin, a sphere), the faces offset by the least amount that keeps them
// there (the largest inscribed or smallest circumscribed feature); without it, the largest distance into the
// material is the least (a plane touching the high points, the outer plane of its minimum zone). Sequential linear
// programs (linear_program.hpp), each on the distances linearised where the last left the points.
struct TangentFit {
  bool converged = false;
  int iterations = 0;
  geometry::RigidTransform motion = geometry::RigidTransform::Identity();  // applied to the points given
  std::vector<int> used;  // the points fitted (found, not past an edge), at the end
  Eigen::MatrixXd J;      // used × 6, at the end
  Eigen::VectorXd d;      // used: signed distances from the faces at the end (from the offset faces: d − size), mm
  double size = 0.0;      // with the size free: the offset along the outward normal, mm
  // ∂(motion's scaled twist)/∂(each used point's distance), 6 × used: the few points the fit rests on have columns.
  Eigen::MatrixXd sensitivity;
};

[[nodiscard]] TangentFit fit_tangent(const cad::ModelLocator& faces, std::span<const Point3> points,
                                     const MotionBasis& fixed, const Point3& centre, double length, bool size_free);

}  // namespace probecomp::inspection
