#include "linear_program.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/LU>

namespace probecomp::inspection {

namespace {

// Reduced costs and pivots below these count as zero. The programs here have coefficients of order 1 (unit normals,
// lever arms over the frame's length, ±1) and right-hand sides in mm, so 1e-12 is far below a nanometre.
constexpr double kCostTolerance = 1e-12;
constexpr double kPivotTolerance = 1e-10;

// The standard form max wᵀy, A y = r, y ≥ 0 with p artificial columns after the N real ones (column N + i is
// ±e_i, the sign of r_i, so that y = |r| on them is a first basis).
struct Tableau {
  const Eigen::MatrixXd& A;  // p × N
  Eigen::VectorXd r;
  Eigen::VectorXd sign;      // of each artificial column
  std::vector<int> basis;    // p column indices
  Eigen::MatrixXd B;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu, lu_transposed;

  Tableau(const Eigen::MatrixXd& a, Eigen::VectorXd rhs) : A(a), r(std::move(rhs)) {
    const Eigen::Index p = A.rows();
    sign = r.unaryExpr([](double v) { return v < 0.0 ? -1.0 : 1.0; });
    for (Eigen::Index i = 0; i < p; ++i) basis.push_back(static_cast<int>(A.cols() + i));
  }
  [[nodiscard]] Eigen::Index real() const { return A.cols(); }
  [[nodiscard]] Eigen::VectorXd column(Eigen::Index j) const {
    if (j < real()) return A.col(j);
    Eigen::VectorXd e = Eigen::VectorXd::Zero(A.rows());
    e(j - real()) = sign(j - real());
    return e;
  }
  // v · column(j), without building the column: pricing takes it for every column each iteration (7 200 touches of a
  // tangent plane: the copies and the basis search were most of a characteristic's time). The same sum, so the same
  // bits: a real column's dot over its view, an artificial one's single term.
  [[nodiscard]] double dot_column(const Eigen::VectorXd& v, Eigen::Index j) const {
    if (j < real()) return v.dot(A.col(j));
    return v(j - real()) * sign(j - real());
  }
  void factor() {
    B.resize(A.rows(), A.rows());
    for (Eigen::Index i = 0; i < A.rows(); ++i) B.col(i) = column(basis[static_cast<std::size_t>(i)]);
    lu.compute(B);
    lu_transposed.compute(B.transpose());
  }

  // Maximises Σ cost(j)·y_j over the columns `may_enter` allows; false if unbounded.
  template <class Cost, class MayEnter>
  bool optimise(const Cost& cost, const MayEnter& may_enter, int& iterations) {
    const Eigen::Index p = A.rows();
    for (;; ++iterations) {
      factor();
      const Eigen::VectorXd y = lu.solve(r);
      Eigen::VectorXd wB(p);
      for (Eigen::Index i = 0; i < p; ++i) wB(i) = cost(basis[static_cast<std::size_t>(i)]);
      const Eigen::VectorXd pi = lu_transposed.solve(wB);
      // Bland: the first column that improves enters...
      std::vector<char> basic(static_cast<std::size_t>(real() + p), 0);
      for (int b : basis) basic[static_cast<std::size_t>(b)] = 1;
      Eigen::Index entering = -1;
      for (Eigen::Index j = 0; j < real() + p && entering < 0; ++j) {
        if (!may_enter(j) || basic[static_cast<std::size_t>(j)]) continue;
        if (cost(j) - dot_column(pi, j) > kCostTolerance) entering = j;
      }
      if (entering < 0) return true;
      const Eigen::VectorXd d = lu.solve(column(entering));
      // ... and of the rows that limit it most, the one whose basic column comes first leaves.
      Eigen::Index leaving = -1;
      double best = std::numeric_limits<double>::infinity();
      for (Eigen::Index i = 0; i < p; ++i) {
        if (d(i) <= kPivotTolerance) continue;
        const double ratio = std::max(0.0, y(i)) / d(i);
        if (ratio < best - 1e-15 ||
            (ratio <= best + 1e-15 && leaving >= 0 && basis[static_cast<std::size_t>(i)] < basis[static_cast<std::size_t>(leaving)])) {
          best = ratio;
          leaving = i;
        }
      }
      if (leaving < 0) return false;
      basis[static_cast<std::size_t>(leaving)] = static_cast<int>(entering);
      if (iterations > 100000) return false;
    }
  }
};

}  // namespace

LinearProgramResult minimise(const Eigen::VectorXd& c, const Eigen::MatrixXd& G, const Eigen::VectorXd& h) {
  LinearProgramResult out;
  const Eigen::MatrixXd A = G.transpose();  // the dual's equality constraints, one per variable of x
  const Eigen::Index p = A.rows(), N = A.cols();
  // The dual's right-hand side −c is mostly zeros, so its vertices are highly degenerate and the simplex can stall
  // or, in floating point, cycle despite Bland's rule. A tiny perturbation, different in each row, separates them
  // (Charnes 1952); it moves the primal objective by εᵀx, far below anything measured here.
  Eigen::VectorXd rhs = -c;
  for (Eigen::Index j = 0; j < p; ++j) rhs(j) += 1e-9 * std::sqrt(2.0 + static_cast<double>(j));
  Tableau t(A, rhs);
  int iterations = 0;
  // Phase 1: drive the artificial columns out (maximise −Σ artificials).
  const auto phase1_cost = [&](Eigen::Index j) { return j < N ? 0.0 : -1.0; };
  (void)t.optimise(phase1_cost, [](Eigen::Index) { return true; }, iterations);
  t.factor();
  const Eigen::VectorXd y = t.lu.solve(t.r);
  double artificial = 0.0;
  for (Eigen::Index i = 0; i < p; ++i) {
    if (t.basis[static_cast<std::size_t>(i)] >= N) artificial += std::abs(y(i));
  }
  if (artificial > 1e-9 * (1.0 + t.r.cwiseAbs().maxCoeff())) {
    // No dual solution: the primal is unbounded below (some direction of x is limited by no constraint).
    out.status = LinearProgramResult::Status::Unbounded;
    return out;
  }
  // An artificial column still basic (at 0) is pivoted out where a real column can take its row; where none can,
  // its row is redundant (a direction of x no constraint involves) and it stays, at 0, for good.
  for (Eigen::Index i = 0; i < p; ++i) {
    if (t.basis[static_cast<std::size_t>(i)] < N) continue;
    t.factor();
    const Eigen::MatrixXd rows = t.lu.inverse().row(i) * A;
    for (Eigen::Index j = 0; j < N; ++j) {
      if (std::abs(rows(0, j)) > kPivotTolerance && std::find(t.basis.begin(), t.basis.end(), static_cast<int>(j)) == t.basis.end()) {
        t.basis[static_cast<std::size_t>(i)] = static_cast<int>(j);
        break;
      }
    }
  }
  // Phase 2: maximise −hᵀλ; artificial columns never enter again.
  const auto cost = [&](Eigen::Index j) { return j < N ? -h(j) : 0.0; };
  const bool bounded = t.optimise(cost, [&](Eigen::Index j) { return j < N; }, iterations);
  if (!bounded) {
    out.status = LinearProgramResult::Status::Infeasible;  // the dual unbounded: no x meets every constraint
    return out;
  }
  t.factor();
  Eigen::VectorXd wB(p);
  for (Eigen::Index i = 0; i < p; ++i) wB(i) = cost(t.basis[static_cast<std::size_t>(i)]);
  out.x = -t.lu_transposed.solve(wB);
  for (int j : t.basis) {
    if (j < N) out.active.push_back(j);
  }
  out.status = LinearProgramResult::Status::OK;
  return out;
}

}  // namespace probecomp::inspection
