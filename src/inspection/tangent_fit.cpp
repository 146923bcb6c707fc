#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/QR>

#include "linear_program.hpp"
#include "probecomp/registration/constraints.hpp"
#include "restricted_fit.hpp"

namespace probecomp::inspection {

namespace {

// The linear programs' vertices move the points by less than this (mm) when the linearisation has settled.
constexpr double kSettledMotion = 1e-10;
constexpr int kMaxLinearPrograms = 30;

}  // namespace

TangentFit fit_tangent(const cad::ModelLocator& faces, std::span<const Point3> points, const MotionBasis& fixed,
                       const Point3& centre, double length, bool size_free) {
  TangentFit fit;
  std::vector<Point3> moved(points.begin(), points.end());
  const Eigen::Index f = fixed.cols(), p = f + 1;
  for (int iteration = 0; iteration < kMaxLinearPrograms; ++iteration) {
    fit.iterations = iteration + 1;
    const std::vector<cad::ModelPoint> feet = faces.closest_points(moved);
    fit.used.clear();
    for (std::size_t i = 0; i < moved.size(); ++i) {
      if (feet[i].ok() && !feet[i].on_trim_edge) fit.used.push_back(static_cast<int>(i));
    }
    const Eigen::Index n = static_cast<Eigen::Index>(fit.used.size());
    if (n == 0) return fit;
    fit.J.resize(n, 6);
    fit.d.resize(n);
    for (Eigen::Index r = 0; r < n; ++r) {
      const std::size_t i = static_cast<std::size_t>(fit.used[static_cast<std::size_t>(r)]);
      fit.J.block<1, 3>(r, 0) = ((moved[i] - centre).cross(feet[i].normal) / length).transpose();
      fit.J.block<1, 3>(r, 3) = feet[i].normal.transpose();
      fit.d(r) = feet[i].distance;
    }
    const Eigen::MatrixXd A = fit.J * fixed;  // e(m) = d + A m
    // x = (m, t). With the size free: min t subject to e − t ≤ 0 (the offset faces hold every point). Without:
    // min −t subject to e ≤ 0 and t − e ≤ 0 (every point inside the material, the deepest as shallow as can be).
    const Eigen::Index rows = size_free ? n : 2 * n;
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(rows, p);
    Eigen::VectorXd h(rows), c = Eigen::VectorXd::Zero(p);
    // ∂h/∂d of each row (the sign the row's point's distance enters with) and its point.
    Eigen::VectorXd h_sign(rows);
    std::vector<Eigen::Index> row_point(static_cast<std::size_t>(rows));
    for (Eigen::Index r = 0; r < n; ++r) {
      G.block(r, 0, 1, f) = A.row(r);
      G(r, f) = size_free ? -1.0 : 0.0;
      h(r) = -fit.d(r);
      h_sign(r) = -1.0;
      row_point[static_cast<std::size_t>(r)] = r;
      if (!size_free) {
        G.block(n + r, 0, 1, f) = -A.row(r);
        G(n + r, f) = 1.0;
        h(n + r) = fit.d(r);
        h_sign(n + r) = 1.0;
        row_point[static_cast<std::size_t>(n + r)] = r;
      }
    }
    c(f) = size_free ? 1.0 : -1.0;
    const LinearProgramResult lp = minimise(c, G, h);
    if (!lp.ok()) return fit;
    const Eigen::VectorXd m = lp.x.head(f);
    fit.size = size_free ? lp.x(f) : 0.0;
    // The optimum rests on its active rows: x = G_a⁻¹ h_a, so ∂x/∂d_i = G_a⁻¹ (∂h_a/∂d_i) (a pseudo-inverse where
    // the rows are fewer than x's directions).
    const Eigen::Index a = static_cast<Eigen::Index>(lp.active.size());
    Eigen::MatrixXd Ga(a, p);
    for (Eigen::Index k = 0; k < a; ++k) Ga.row(k) = G.row(lp.active[static_cast<std::size_t>(k)]);
    const Eigen::MatrixXd Ga_inverse = Ga.completeOrthogonalDecomposition().pseudoInverse();
    fit.sensitivity = Eigen::MatrixXd::Zero(6, n);
    for (Eigen::Index k = 0; k < a; ++k) {
      const Eigen::Index row = lp.active[static_cast<std::size_t>(k)];
      fit.sensitivity.col(row_point[static_cast<std::size_t>(row)]) +=
          fixed * (Ga_inverse.col(k).head(f) * h_sign(row));
    }
    const geometry::Twist delta = fixed * m;
    const geometry::RigidTransform step = registration::motion_about(delta, centre, length);
    double largest = 0.0;
    for (Point3& x : moved) {
      const Point3 y = step * x;
      largest = std::max(largest, (y - x).norm());
      x = y;
    }
    fit.motion = step * fit.motion;
    if (largest <= kSettledMotion) {
      // The last step moved nothing that matters: the distances above are the end's, less the offset faces' size.
      fit.d = fit.d + A * m;
      if (size_free) fit.d.array() -= fit.size;
      fit.converged = true;
      return fit;
    }
  }
  return fit;
}

}  // namespace probecomp::inspection
