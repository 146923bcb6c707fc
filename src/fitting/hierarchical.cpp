#include "probecomp/fitting/hierarchical.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <tuple>

#include "probecomp/nurbs/knot_insertion.hpp"

#include "hierarchical_rows.hpp"
#include "rational_basis.hpp"

namespace probecomp::fitting {

namespace {

using nurbs::KnotVector;
using nurbs::Surface;

// Coefficients of a B-spline below this are rounding (they lie in [0, 1]; a truncated one's exact zeros come out
// of a least-squares solve and a subtraction as a few units of 1e-16).
constexpr double kZeroCoefficient = 1e-13;

// The knot insertion matrix of U → U ∪ X: column i holds B-spline i of U in the refined basis (A5.4 on a unit
// coefficient vector; the refinement is linear in the coefficients).
Eigen::MatrixXd insertion_matrix(const KnotVector& U, const std::vector<double>& X, KnotVector* refined = nullptr) {
  const int n = U.num_basis();
  Eigen::MatrixXd A;
  for (int i = 0; i < n; ++i) {
    std::vector<HomogeneousPoint> Pw(static_cast<std::size_t>(n), HomogeneousPoint(0.0, 0.0, 0.0, 1.0));
    Pw[static_cast<std::size_t>(i)].x() = 1.0;
    auto [Uf, Qw] = X.empty() ? std::pair{U, Pw} : nurbs::refine_knots_homogeneous(U, Pw, X);
    if (i == 0) {
      A.setZero(static_cast<Eigen::Index>(Qw.size()), n);
      if (refined) *refined = Uf;
    }
    for (std::size_t r = 0; r < Qw.size(); ++r) A(static_cast<Eigen::Index>(r), i) = Qw[r].x();
  }
  return A;
}

// The level-0 spans [first, last] that the interval [a, b] overlaps with positive length.
std::pair<int, int> spans_under(const std::vector<double>& breaks, double a, double b) {
  const int n = static_cast<int>(breaks.size()) - 1;
  int first = n, last = -1;
  for (int s = 0; s < n; ++s) {
    if (breaks[static_cast<std::size_t>(s)] < b && breaks[static_cast<std::size_t>(s) + 1] > a) {
      first = std::min(first, s);
      last = std::max(last, s);
    }
  }
  return {first, last};
}

// Support [u_i, u_{i+p+1}] of every B-spline of U, as level-0 span ranges.
std::vector<std::pair<int, int>> supports(const KnotVector& U, const std::vector<double>& breaks) {
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < U.num_basis(); ++i) out.push_back(spans_under(breaks, U[i], U[i + U.degree() + 1]));
  return out;
}

// The rows [first, last] of column `col` of M that are not zero (first > last: none).
std::pair<Eigen::Index, Eigen::Index> nonzero_rows(const Eigen::MatrixXd& M, Eigen::Index col) {
  Eigen::Index first = 0, last = M.rows() - 1;
  while (first < M.rows() && M(first, col) == 0.0) ++first;
  while (last >= first && M(last, col) == 0.0) --last;
  return {first, last};
}

struct Function {
  int level, i, j;
  double major, minor;  // Greville point at its own level, the band's outer direction first
  double weight;        // ŵ: the weight function's coefficient at this level
  std::vector<std::pair<int, double>> out;  // (control point J of the output surface, B-spline coefficient)
};

}  // namespace

HierarchicalBasis hierarchical_basis(const Surface& start, std::span<const std::uint8_t> refine, int ring) {
  const int p = start.p(), q = start.q();
  const std::vector<double> bu = start.U().breakpoints(), bv = start.V().breakpoints();
  const int nsu = static_cast<int>(bu.size()) - 1, nsv = static_cast<int>(bv.size()) - 1;
  if (refine.size() != static_cast<std::size_t>(nsu) * static_cast<std::size_t>(nsv)) {
    throw std::invalid_argument("hierarchical_basis: one flag per knot span of the start surface expected");
  }
  // Ω¹: the marked cells grown by the ring (eight neighbours a step).
  std::vector<std::uint8_t> omega(refine.size(), 0);
  for (int a = 0; a < nsu; ++a) {
    for (int b = 0; b < nsv; ++b) {
      if (!refine[static_cast<std::size_t>(a) * nsv + b]) continue;
      for (int x = std::max(0, a - ring); x <= std::min(nsu - 1, a + ring); ++x)
        for (int y = std::max(0, b - ring); y <= std::min(nsv - 1, b + ring); ++y) omega[static_cast<std::size_t>(x) * nsv + y] = 1;
    }
  }
  auto in_omega = [&](std::pair<int, int> su, std::pair<int, int> sv) {
    for (int a = su.first; a <= su.second; ++a)
      for (int b = sv.first; b <= sv.second; ++b)
        if (!omega[static_cast<std::size_t>(a) * nsv + b]) return false;
    return true;
  };
  // Level 1 halves every span; the output knots take a span's midpoint where its column (row) meets Ω¹.
  std::vector<double> mid_u, mid_v, out_u, out_v;
  auto halve = [&](const std::vector<double>& breaks, bool along_u, std::vector<double>& mid, std::vector<double>& out) {
    const int n = static_cast<int>(breaks.size()) - 1, across = along_u ? nsv : nsu;
    for (int a = 0; a < n; ++a) {
      const double m = 0.5 * (breaks[static_cast<std::size_t>(a)] + breaks[static_cast<std::size_t>(a) + 1]);
      mid.push_back(m);
      bool any = false;
      for (int b = 0; b < across; ++b) any = any || omega[static_cast<std::size_t>(along_u ? a * nsv + b : b * nsv + a)];
      if (any) out.push_back(m);
    }
  };
  halve(bu, true, mid_u, out_u);
  halve(bv, false, mid_v, out_v);
  HierarchicalBasis basis{.surface = out_u.empty() ? start : nurbs::refine_knots_v(nurbs::refine_knots_u(start, out_u), out_v)};
  const Surface& S = basis.surface;
  KnotVector U1, V1;
  const Eigen::MatrixXd A01u = insertion_matrix(start.U(), mid_u, &U1), A01v = insertion_matrix(start.V(), mid_v, &V1);
  const Eigen::MatrixXd A0ou = insertion_matrix(start.U(), out_u), A0ov = insertion_matrix(start.V(), out_v);
  // Level-1 B-splines in the output basis: solve A_out→1 c = e_k (consistent where the B-spline's knots are all
  // output knots, which holds for every one whose support lies in Ω¹: the only ones used).
  auto level1_in_out = [&](const KnotVector& Uout, const KnotVector& Ul1) {
    std::vector<double> extra;
    for (double x : Ul1.breakpoints())
      if (Uout.multiplicity(x) == 0) extra.push_back(x);
    const Eigen::MatrixXd A = insertion_matrix(Uout, extra);
    Eigen::MatrixXd C = A.colPivHouseholderQr().solve(Eigen::MatrixXd::Identity(A.rows(), A.rows()));
    C = C.unaryExpr([](double x) { return std::abs(x) < kZeroCoefficient ? 0.0 : x; });
    return std::pair{C, A};
  };
  const auto [C1u, Aou1] = level1_in_out(S.U(), U1);
  const auto [C1v, Aov1] = level1_in_out(S.V(), V1);
  const auto sup0u = supports(start.U(), bu), sup0v = supports(start.V(), bv);
  const auto sup1u = supports(U1, bu), sup1v = supports(V1, bv);
  const int n0u = start.num_u(), n0v = start.num_v(), n1u = U1.num_basis(), n1v = V1.num_basis();
  const int nou = S.num_u(), nov = S.num_v();
  const bool v_inner = n0v <= n0u;  // as detail::Ordering: the shorter direction inner
  std::vector<std::uint8_t> active1(static_cast<std::size_t>(n1u) * n1v, 0);
  std::vector<Function> functions;
  Surface level1 = out_u.empty() ? start : nurbs::refine_knots_v(nurbs::refine_knots_u(start, mid_u), mid_v);
  if (!out_u.empty()) {
    for (int k = 0; k < n1u; ++k) {
      for (int l = 0; l < n1v; ++l) {
        if (!in_omega(sup1u[static_cast<std::size_t>(k)], sup1v[static_cast<std::size_t>(l)])) continue;
        active1[static_cast<std::size_t>(k) * n1v + l] = 1;
        // Its knots are all output knots: the solve above is exact for it.
        const Eigen::VectorXd ek = Aou1 * C1u.col(k) - Eigen::VectorXd::Unit(n1u, k);
        const Eigen::VectorXd el = Aov1 * C1v.col(l) - Eigen::VectorXd::Unit(n1v, l);
        if (ek.lpNorm<Eigen::Infinity>() > 1e-9 || el.lpNorm<Eigen::Infinity>() > 1e-9) {
          throw std::logic_error("hierarchical_basis: a level-1 B-spline inside Ω¹ is not in the output space");
        }
        Function f{1, k, l, U1.greville(k), V1.greville(l), level1.weight(k, l), {}};
        const auto [iu0, iu1] = nonzero_rows(C1u, k);
        const auto [jv0, jv1] = nonzero_rows(C1v, l);
        for (Eigen::Index I = iu0; I <= iu1; ++I) {
          if (C1u(I, k) == 0.0) continue;
          for (Eigen::Index J = jv0; J <= jv1; ++J)
            if (C1v(J, l) != 0.0) f.out.emplace_back(static_cast<int>(I) * nov + static_cast<int>(J), C1u(I, k) * C1v(J, l));
        }
        functions.push_back(std::move(f));
      }
    }
  }
  basis.refined_unknowns = static_cast<int>(functions.size());
  // Level 0: a B-spline whose support lies in Ω¹ is replaced; the others are truncated.
  Eigen::MatrixXd window;
  for (int i = 0; i < n0u; ++i) {
    for (int j = 0; j < n0v; ++j) {
      if (!out_u.empty() && in_omega(sup0u[static_cast<std::size_t>(i)], sup0v[static_cast<std::size_t>(j)])) continue;
      Function f{0, i, j, start.U().greville(i), start.V().greville(j), start.weight(i, j), {}};
      // The B-spline in the output basis, over the output rows and columns its support covers (its level-1
      // children lie inside that support).
      const auto [iu0, iu1] = nonzero_rows(A0ou, i);
      const auto [jv0, jv1] = nonzero_rows(A0ov, j);
      const Eigen::Index ru = iu1 - iu0 + 1, rv = jv1 - jv0 + 1;
      window = A0ou.col(i).segment(iu0, ru) * A0ov.col(j).segment(jv0, rv).transpose();
      for (int k = 0; k < n1u && !out_u.empty(); ++k) {
        if (A01u(k, i) == 0.0) continue;
        for (int l = 0; l < n1v; ++l) {
          if (A01v(l, j) == 0.0 || !active1[static_cast<std::size_t>(k) * n1v + l]) continue;
          window -= (A01u(k, i) * A01v(l, j)) * (C1u.col(k).segment(iu0, ru) * C1v.col(l).segment(jv0, rv).transpose());
        }
      }
      for (Eigen::Index I = 0; I < ru; ++I)
        for (Eigen::Index J = 0; J < rv; ++J)
          if (std::abs(window(I, J)) > kZeroCoefficient) {
            f.out.emplace_back(static_cast<int>(iu0 + I) * nov + static_cast<int>(jv0 + J), window(I, J));
          }
      if (!f.out.empty()) functions.push_back(std::move(f));
    }
  }
  for (Function& f : functions) {
    if (!v_inner) std::swap(f.major, f.minor);
  }
  std::sort(functions.begin(), functions.end(), [](const Function& a, const Function& b) {
    return std::tie(a.major, a.minor, a.level, a.i, a.j) < std::tie(b.major, b.minor, b.level, b.i, b.j);
  });
  basis.unknowns = static_cast<int>(functions.size());
  // Per output control point J: T_Jτ = ŵ_τ c_Jτ / w'_J, so that R_τ = ŵ_τ T_τ / W = Σ_J T_Jτ R^out_J.
  const std::size_t n_out = static_cast<std::size_t>(nou) * nov;
  basis.first.assign(n_out + 1, 0);
  for (const Function& f : functions)
    for (const auto& [J, c] : f.out) ++basis.first[static_cast<std::size_t>(J) + 1];
  std::partial_sum(basis.first.begin(), basis.first.end(), basis.first.begin());
  basis.unknown.resize(static_cast<std::size_t>(basis.first.back()));
  basis.coefficient.resize(basis.unknown.size());
  std::vector<int> fill(basis.first.begin(), basis.first.end() - 1);
  for (int tau = 0; tau < basis.unknowns; ++tau) {
    const Function& f = functions[static_cast<std::size_t>(tau)];
    for (const auto& [J, c] : f.out) {
      const auto at = static_cast<std::size_t>(fill[static_cast<std::size_t>(J)]++);
      basis.unknown[at] = tau;
      basis.coefficient[at] = f.weight * c / S.weight(J / nov, J % nov);
    }
  }
  // Per output span: the union of its (p+1)(q+1) control points' THB functions.
  basis.cell_first.assign(n_out + 1, 0);
  std::vector<std::vector<int>> cells(n_out);
  const std::vector<double> ou = S.U().breakpoints(), ov = S.V().breakpoints();
  for (std::size_t a = 0; a + 1 < ou.size(); ++a) {
    const int su = S.U().find_span(0.5 * (ou[a] + ou[a + 1]));
    for (std::size_t b = 0; b + 1 < ov.size(); ++b) {
      const int sv = S.V().find_span(0.5 * (ov[b] + ov[b + 1]));
      std::vector<int>& ids = cells[static_cast<std::size_t>((su - p) * nov + sv - q)];
      for (int x = su - p; x <= su; ++x)
        for (int y = sv - q; y <= sv; ++y) {
          const auto J = static_cast<std::size_t>(x * nov + y);
          for (int e = basis.first[J]; e < basis.first[J + 1]; ++e) ids.push_back(basis.unknown[static_cast<std::size_t>(e)]);
        }
      std::sort(ids.begin(), ids.end());
      ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
      basis.bandwidth = std::max(basis.bandwidth, ids.back() - ids.front());
      basis.max_row = std::max(basis.max_row, static_cast<int>(ids.size()));
    }
  }
  for (std::size_t c = 0; c < n_out; ++c) basis.cell_first[c + 1] = basis.cell_first[c] + static_cast<int>(cells[c].size());
  for (const auto& ids : cells) basis.cell_unknowns.insert(basis.cell_unknowns.end(), ids.begin(), ids.end());
  return basis;
}

HierarchicalRow hierarchical_row(const HierarchicalBasis& basis, double u, double v) {
  detail::RationalBasis rb;
  detail::rational_basis(basis.surface, u, v, rb);
  HierarchicalRow row;
  row.unknown.resize(static_cast<std::size_t>(basis.max_row));
  row.value.resize(row.unknown.size());
  const int m = detail::reduce_row(basis, rb.i0, rb.j0, rb.R, row.value.data(), row.unknown.data());
  row.unknown.resize(static_cast<std::size_t>(m));
  row.value.resize(static_cast<std::size_t>(m));
  return row;
}

std::vector<Vector3> control_net_displacement(const HierarchicalBasis& basis, std::span<const double> D) {
  std::vector<Vector3> out(basis.first.size() - 1, Vector3::Zero());
  for (std::size_t J = 0; J < out.size(); ++J) {
    for (int e = basis.first[J]; e < basis.first[J + 1]; ++e) {
      const auto tau = static_cast<std::size_t>(basis.unknown[static_cast<std::size_t>(e)]);
      out[J] += basis.coefficient[static_cast<std::size_t>(e)] * Vector3(D[3 * tau], D[3 * tau + 1], D[3 * tau + 2]);
    }
  }
  return out;
}

nurbs::Surface to_nurbs(const HierarchicalBasis& basis, std::span<const double> D) {
  std::vector<HomogeneousPoint> Pw(basis.surface.homogeneous());
  const std::vector<Vector3> d = control_net_displacement(basis, D);
  for (std::size_t J = 0; J < Pw.size(); ++J) Pw[J].head<3>() += Pw[J].w() * d[J];
  return Surface(basis.surface.U(), basis.surface.V(), std::move(Pw));
}

}  // namespace probecomp::fitting
