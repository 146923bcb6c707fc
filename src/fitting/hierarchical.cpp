#include "probecomp/fitting/hierarchical.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>

#include "probecomp/nurbs/knot_insertion.hpp"

#include "hierarchical_rows.hpp"
#include "hierarchy_marks.hpp"
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
  const std::vector<double> bu = start.U().breakpoints(), bv = start.V().breakpoints();
  const int nsu = static_cast<int>(bu.size()) - 1, nsv = static_cast<int>(bv.size()) - 1;
  if (refine.size() != static_cast<std::size_t>(nsu) * static_cast<std::size_t>(nsv)) {
    throw std::invalid_argument("hierarchical_basis: one flag per knot span of the start surface expected");
  }
  // Ω¹: the marked cells grown by the ring (eight neighbours a step).
  const std::vector<std::vector<std::uint8_t>> domains =
      detail::nested_domains({std::vector<std::uint8_t>(refine.begin(), refine.end())}, bu, bv, ring);
  return hierarchical_basis(start, domains);
}

HierarchicalBasis hierarchical_basis(const Surface& start, std::span<const std::vector<std::uint8_t>> domains) {
  const int p = start.p(), q = start.q();
  const int L = static_cast<int>(domains.size()) + 1;
  // Each level's breakpoints (level l + 1 halves every span of level l) and the knots it adds, its spans' midpoints.
  std::vector<std::vector<double>> bu{start.U().breakpoints()}, bv{start.V().breakpoints()}, mid_u, mid_v;
  auto midpoints = [](const std::vector<double>& breaks) {
    return flagged_span_midpoints(breaks, std::vector<char>(breaks.size() - 1, 1));
  };
  for (int l = 0; l + 1 < L; ++l) {
    mid_u.push_back(midpoints(bu.back()));
    mid_v.push_back(midpoints(bv.back()));
    bu.push_back(halved(bu.back(), 1));
    bv.push_back(halved(bv.back(), 1));
  }
  auto cells_u = [&](int l) { return static_cast<int>(bu[static_cast<std::size_t>(l)].size()) - 1; };
  auto cells_v = [&](int l) { return static_cast<int>(bv[static_cast<std::size_t>(l)].size()) - 1; };
  // Ωˡ (l ≥ 1) is flagged on the cells of level l − 1; a level-l cell (a, b) lies in the level-(l − 1) cell
  // (a / 2, b / 2).
  auto in_domain = [&](int l, int a, int b) {
    return domains[static_cast<std::size_t>(l) - 1][static_cast<std::size_t>(a / 2) * cells_v(l - 1) + b / 2] != 0;
  };
  bool any = false;
  for (int l = 1; l < L; ++l) {
    const auto& d = domains[static_cast<std::size_t>(l) - 1];
    if (d.size() != static_cast<std::size_t>(cells_u(l - 1)) * static_cast<std::size_t>(cells_v(l - 1))) {
      throw std::invalid_argument("hierarchical_basis: Ω" + std::to_string(l) + " needs one flag per cell of level " +
                                  std::to_string(l - 1));
    }
    for (int a = 0; a < cells_u(l - 1); ++a) {
      for (int b = 0; b < cells_v(l - 1); ++b) {
        if (!d[static_cast<std::size_t>(a) * cells_v(l - 1) + b]) continue;
        any = true;
        if (l >= 2 && !in_domain(l - 1, a, b)) throw std::invalid_argument("hierarchical_basis: the domains are not nested");
      }
    }
  }
  // The output knots: a level-l knot (the midpoint of a level-(l − 1) span) where that span's column (row) meets
  // Ωˡ. Every active function's knots are among them (docs/local-refinement-plan.md §4).
  std::vector<double> out_u, out_v;
  for (int l = 1; l < L && any; ++l) {
    const auto& d = domains[static_cast<std::size_t>(l) - 1];
    for (int a = 0; a < cells_u(l - 1); ++a) {
      bool meets = false;
      for (int b = 0; b < cells_v(l - 1); ++b) meets = meets || d[static_cast<std::size_t>(a) * cells_v(l - 1) + b];
      if (meets) out_u.push_back(mid_u[static_cast<std::size_t>(l) - 1][static_cast<std::size_t>(a)]);
    }
    for (int b = 0; b < cells_v(l - 1); ++b) {
      bool meets = false;
      for (int a = 0; a < cells_u(l - 1); ++a) meets = meets || d[static_cast<std::size_t>(a) * cells_v(l - 1) + b];
      if (meets) out_v.push_back(mid_v[static_cast<std::size_t>(l) - 1][static_cast<std::size_t>(b)]);
    }
  }
  std::sort(out_u.begin(), out_u.end());
  std::sort(out_v.begin(), out_v.end());
  HierarchicalBasis basis{.surface = !any ? start
                                          : nurbs::refine_knots_v(nurbs::refine_knots_u(start, out_u), out_v)};
  const Surface& S = basis.surface;
  // Each level's knots, its insertion matrix into the next level's and its surface (for the weights ŵ).
  std::vector<KnotVector> U{start.U()}, V{start.V()};
  std::vector<Eigen::MatrixXd> Au, Av;
  std::vector<Surface> level_surface{start};
  for (int l = 1; l < L && any; ++l) {
    KnotVector Ul, Vl;
    Au.push_back(insertion_matrix(U.back(), mid_u[static_cast<std::size_t>(l) - 1], &Ul));
    Av.push_back(insertion_matrix(V.back(), mid_v[static_cast<std::size_t>(l) - 1], &Vl));
    U.push_back(Ul);
    V.push_back(Vl);
    level_surface.push_back(nurbs::refine_knots_v(nurbs::refine_knots_u(level_surface.back(), mid_u[static_cast<std::size_t>(l) - 1]),
                                                  mid_v[static_cast<std::size_t>(l) - 1]));
  }
  const int top = static_cast<int>(U.size()) - 1;  // the finest level built (0 without refinement)
  // within[l][m]: whether each level-l B-spline's support lies inside Ωᵐ (m = l: it may be active; m = l + 1: it is
  // replaced by finer ones), Ωᵐ being flagged on level-(m − 1) cells, each holding 2^(l−m+1) × 2^(l−m+1) of level l.
  auto support_within = [&](int l, int m) {
    const auto su = supports(U[static_cast<std::size_t>(l)], bu[static_cast<std::size_t>(l)]);
    const auto sv = supports(V[static_cast<std::size_t>(l)], bv[static_cast<std::size_t>(l)]);
    const int shift = l - m + 1, nvl = V[static_cast<std::size_t>(l)].num_basis();
    const auto& d = domains[static_cast<std::size_t>(m) - 1];
    std::vector<std::uint8_t> in(static_cast<std::size_t>(U[static_cast<std::size_t>(l)].num_basis()) * nvl, 0);
    for (int k = 0; k < U[static_cast<std::size_t>(l)].num_basis(); ++k) {
      for (int n = 0; n < nvl; ++n) {
        bool all = true;
        for (int a = su[static_cast<std::size_t>(k)].first; a <= su[static_cast<std::size_t>(k)].second && all; ++a)
          for (int b = sv[static_cast<std::size_t>(n)].first; b <= sv[static_cast<std::size_t>(n)].second && all; ++b)
            all = d[static_cast<std::size_t>(a >> shift) * cells_v(m - 1) + static_cast<std::size_t>(b >> shift)] != 0;
        in[static_cast<std::size_t>(k) * nvl + n] = all;
      }
    }
    return in;
  };
  std::vector<std::vector<std::uint8_t>> inside(static_cast<std::size_t>(top) + 1), deeper(static_cast<std::size_t>(top) + 1);
  for (int l = 0; l <= top; ++l) {
    if (l > 0) inside[static_cast<std::size_t>(l)] = support_within(l, l);
    if (l < top) deeper[static_cast<std::size_t>(l)] = support_within(l, l + 1);
  }
  // The output B-splines in the finest level's basis, and a left inverse: a function of the output space has its
  // output coefficients C·c from its finest-level ones c, exactly (every active function and every truncation of
  // one lies in the output space).
  auto finest_in_out = [](const KnotVector& Uout, const KnotVector& Ufine) {
    std::vector<double> extra;
    for (double x : Ufine.breakpoints())
      if (Uout.multiplicity(x) == 0) extra.push_back(x);
    const Eigen::MatrixXd A = insertion_matrix(Uout, extra);
    return Eigen::MatrixXd(A.colPivHouseholderQr().solve(Eigen::MatrixXd::Identity(A.rows(), A.rows())));
  };
  const Eigen::MatrixXd Cu = finest_in_out(S.U(), U.back()), Cv = finest_in_out(S.V(), V.back());
  // The output B-splines whose support lies in [a, b] (the others have no part in a function zero outside it).
  auto out_range = [](const KnotVector& K, double a, double b) {
    int first = K.num_basis(), last = -1;
    for (int I = 0; I < K.num_basis(); ++I) {
      if (K[I] >= a - 1e-12 && K[I + K.degree() + 1] <= b + 1e-12) {
        first = std::min(first, I);
        last = std::max(last, I);
      }
    }
    return std::pair{first, last};
  };
  const int nou = S.num_u(), nov = S.num_v();
  const bool v_inner = start.num_v() <= start.num_u();  // as detail::Ordering: the shorter direction inner
  std::vector<Function> functions;
  Eigen::MatrixXd window, next;
  for (int l = 0; l <= top; ++l) {
    const KnotVector& Ul = U[static_cast<std::size_t>(l)];
    const KnotVector& Vl = V[static_cast<std::size_t>(l)];
    for (int i = 0; i < Ul.num_basis(); ++i) {
      for (int j = 0; j < Vl.num_basis(); ++j) {
        // Active: its support inside Ωˡ (all of the face at level 0) and not inside Ωˡ⁺¹.
        const std::size_t ij = static_cast<std::size_t>(i) * Vl.num_basis() + static_cast<std::size_t>(j);
        if ((l > 0 && !inside[static_cast<std::size_t>(l)][ij]) || (l < top && deeper[static_cast<std::size_t>(l)][ij])) continue;
        Function f{l, i, j, Ul.greville(i), Vl.greville(j), level_surface[static_cast<std::size_t>(l)].weight(i, j), {}};
        // Its coefficients level by level down to the finest, over the window its support covers, each level's
        // B-splines inside that level's Ωᵏ taken out (the truncation: Giannelli, Jüttler & Speleers 2012, eq. 9).
        Eigen::Index iu0 = i, iu1 = i, jv0 = j, jv1 = j;
        window = Eigen::MatrixXd::Ones(1, 1);
        for (int k = l + 1; k <= top; ++k) {
          const Eigen::MatrixXd& A = Au[static_cast<std::size_t>(k) - 1];
          const Eigen::MatrixXd& B = Av[static_cast<std::size_t>(k) - 1];
          const auto ru = std::pair{nonzero_rows(A, iu0).first, nonzero_rows(A, iu1).second};
          const auto rv = std::pair{nonzero_rows(B, jv0).first, nonzero_rows(B, jv1).second};
          next = A.block(ru.first, iu0, ru.second - ru.first + 1, iu1 - iu0 + 1) * window *
                 B.block(rv.first, jv0, rv.second - rv.first + 1, jv1 - jv0 + 1).transpose();
          window.swap(next);
          std::tie(iu0, iu1) = ru;
          std::tie(jv0, jv1) = rv;
          const int nvk = V[static_cast<std::size_t>(k)].num_basis();
          for (Eigen::Index a = 0; a < window.rows(); ++a)
            for (Eigen::Index b = 0; b < window.cols(); ++b)
              if (inside[static_cast<std::size_t>(k)][static_cast<std::size_t>(iu0 + a) * nvk + static_cast<std::size_t>(jv0 + b)]) window(a, b) = 0.0;
        }
        // In the output basis: C over the output B-splines inside the function's support.
        const KnotVector& Uf = U.back();
        const KnotVector& Vf = V.back();
        const auto [ou0, ou1] = out_range(S.U(), Uf[static_cast<int>(iu0)], Uf[static_cast<int>(iu1) + Uf.degree() + 1]);
        const auto [ov0, ov1] = out_range(S.V(), Vf[static_cast<int>(jv0)], Vf[static_cast<int>(jv1) + Vf.degree() + 1]);
        if (ou1 < ou0 || ov1 < ov0) continue;
        const Eigen::MatrixXd out = Cu.block(ou0, iu0, ou1 - ou0 + 1, window.rows()) * window *
                                    Cv.block(ov0, jv0, ov1 - ov0 + 1, window.cols()).transpose();
        for (Eigen::Index I = 0; I < out.rows(); ++I)
          for (Eigen::Index J = 0; J < out.cols(); ++J)
            if (std::abs(out(I, J)) > kZeroCoefficient) {
              f.out.emplace_back(static_cast<int>(ou0 + I) * nov + static_cast<int>(ov0 + J), out(I, J));
            }
        if (!f.out.empty()) functions.push_back(std::move(f));
      }
    }
  }
  basis.refined_unknowns = static_cast<int>(std::count_if(functions.begin(), functions.end(), [](const Function& f) { return f.level > 0; }));
  basis.levels = top + 1;
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
