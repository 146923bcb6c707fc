#pragma once
// A small linear program: minimise cᵀx subject to G x ≤ h, x free, with few variables (a datum's motions and one
// more: at most 8) and many constraints (two per point). Solved through its dual, max −hᵀλ subject to Gᵀλ = −c,
// λ ≥ 0, by the revised simplex method in two phases with Bland's rule (Chvátal, Linear Programming, 1983, ch. 2–3
// and 7): its basis is only as large as x, so each step costs one pass over the constraints. The tangent datum fits
// (ISO 5459's constrained minimax, ASME Y14.5.1's tangent plane, the largest inscribed and smallest circumscribed
// cylinders) are such programs once linearised. Private to the inspection layer.

#include <vector>

#include <Eigen/Core>

namespace probecomp::inspection {

struct LinearProgramResult {
  enum class Status { OK, Unbounded, Infeasible, NotDone };
  Status status = Status::NotDone;
  Eigen::VectorXd x;
  // The constraints whose dual variables are basic at the optimum: they hold with equality there, and where the
  // program fixes every direction of x they determine it (G_active x = h_active, square and regular).
  std::vector<int> active;
  [[nodiscard]] bool ok() const { return status == Status::OK; }
};

[[nodiscard]] LinearProgramResult minimise(const Eigen::VectorXd& c, const Eigen::MatrixXd& G, const Eigen::VectorXd& h);

}  // namespace probecomp::inspection
