#include "cross_validation.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>

#include "probecomp/fitting/spans.hpp"

namespace probecomp::fitting::detail {

using nurbs::Surface;

CvRows cv_rows(const RowMaker& maker, std::span<const Point3> points, std::span<const SurfaceParameter> params,
               std::span<const double> weights, const std::vector<double>& fold_u,
               const std::vector<double>& fold_v) {
  const Surface& s = maker.s;
  const Ordering& order = maker.order;
  const int p = s.p(), q = s.q();
  const std::size_t n_points = points.size();
  const std::size_t stride = cv_stride(n_points);
  std::vector<std::size_t> chosen;
  for (std::size_t k = 0; k < n_points; k += stride) {
    if (weights.empty() || weights[k] != 0.0) chosen.push_back(k);
  }
  // Each row's place in span order, stably: a counting sort on its span's first control point (RowMaker's key, as
  // rational_basis finds the spans), then every row made in parallel at its place.
  std::vector<int> key(chosen.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chosen.size(), 4096), [&](const auto& range) {
    for (std::size_t r = range.begin(); r != range.end(); ++r) {
      const SurfaceParameter& t = params[chosen[r]];
      key[r] = order.index(s.U().find_span(t.u) - p, s.V().find_span(t.v) - q);
    }
  });
  // With folds: each span's rows also by the fold cell they lie in (its spans cut by fold_u and fold_v), so that
  // the groups left out together are the pieces of the spans those lines cut.
  std::vector<std::uint32_t> cell;
  std::vector<std::size_t> to(chosen.size());
  if (!fold_u.empty() && !fold_v.empty()) {
    const std::size_t nfv = fold_v.size() - 1;
    cell.resize(chosen.size());
    for (std::size_t r = 0; r < chosen.size(); ++r) {
      const SurfaceParameter& t = params[chosen[r]];
      cell[r] = static_cast<std::uint32_t>(static_cast<std::size_t>(span_of(fold_u, t.u)) * nfv +
                                           static_cast<std::size_t>(span_of(fold_v, t.v)));
    }
    std::vector<std::size_t> order_of(chosen.size());
    std::iota(order_of.begin(), order_of.end(), std::size_t{0});
    std::stable_sort(order_of.begin(), order_of.end(), [&](std::size_t x, std::size_t y) {
      return key[x] != key[y] ? key[x] < key[y] : cell[x] < cell[y];
    });
    for (std::size_t at = 0; at < order_of.size(); ++at) to[order_of[at]] = at;
  } else {
    std::vector<std::size_t> place(static_cast<std::size_t>(order.nu) * static_cast<std::size_t>(order.nv) + 1, 0);
    for (const int k : key) ++place[static_cast<std::size_t>(k) + 1];
    std::partial_sum(place.begin(), place.end(), place.begin());
    for (std::size_t r = 0; r < chosen.size(); ++r) to[r] = place[static_cast<std::size_t>(key[r])]++;
  }
  const auto m = static_cast<std::size_t>(maker.m);
  CvRows rows;
  rows.m = static_cast<int>(m);
  rows.idx.resize(chosen.size() * m);
  rows.R.resize(chosen.size() * m);
  rows.key.resize(chosen.size());
  rows.len.resize(chosen.size());
  rows.y.resize(chosen.size());
  rows.w.resize(chosen.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chosen.size(), 1024), [&](const auto& range) {
    RationalBasis rb;
    for (std::size_t r = range.begin(); r != range.end(); ++r) {
      const std::size_t k = chosen[r], at = to[r];
      rows.y[at] = points[k] - maker(params[k], rb, &rows.R[at * m], &rows.idx[at * m], rows.key[at], rows.len[at]);
      rows.w[at] = weights.empty() ? 1.0 : weights[k];
    }
  });
  std::vector<std::uint32_t> cell_at;
  if (!cell.empty()) {
    cell_at.resize(chosen.size());
    for (std::size_t r = 0; r < chosen.size(); ++r) cell_at[to[r]] = cell[r];
  }
  for (std::size_t r = 0; r < chosen.size(); ++r) {
    if (r == 0 || rows.key[r] != rows.key[r - 1] || (!cell_at.empty() && cell_at[r] != cell_at[r - 1])) {
      rows.span_starts.push_back(r);
    }
  }
  rows.span_starts.push_back(chosen.size());
  if (stride == 1) {
    rows.row_of_point.assign(n_points, CvRows::kNoRow);
    for (std::size_t r = 0; r < chosen.size(); ++r) rows.row_of_point[chosen[r]] = static_cast<std::uint32_t>(to[r]);
  }
  return rows;
}

namespace {

// The leave-one-out terms of rows [first, last), in order (see leave_one_out); M is the row length m when fixed at
// compile time (Eigen::Dynamic otherwise), so that a bicubic row's products stay in vector registers, as in
// block_quadratic_form (timings in docs/performance.md).
template <int M>
double leave_one_out_terms(const CvRows& rows, std::size_t first, std::size_t last, const std::vector<double>& D,
                           std::span<const double> Z, int b) {
  const int m = rows.m;
  const std::size_t mm = static_cast<std::size_t>(m);
  Eigen::Matrix<double, M, M> block(m, m);  // Z over the span's unknowns (gather_block)
  Eigen::Matrix<double, M, 3> d(m, 3);      // D there
  int span = -1;
  double sum = 0.0;
  for (std::size_t r = first; r < last; ++r) {
    const int* idx = &rows.idx[r * mm];
    if (rows.key[r] != span) {
      span = rows.key[r];
      gather_block(Z, b, idx, m, block.data());
      for (int a = 0; a < m; ++a) {
        const std::size_t I = static_cast<std::size_t>(idx[a]);
        d.row(a) << D[3 * I], D[3 * I + 1], D[3 * I + 2];
      }
    }
    const Eigen::Map<const Eigen::Matrix<double, M, 1>> R(&rows.R[r * mm], m);
    const Vector3 fitted = d.transpose() * R;  // the displacement's value at the point: S − S⁰
    const double v = block_quadratic_form(block.data(), R.data(), m);  // its leverage over its weight
    const double one_minus_h = std::max(1.0 - rows.w[r] * v, 1e-6);
    sum += rows.w[r] * (fitted - rows.y[r]).squaredNorm() / (one_minus_h * one_minus_h);
  }
  return sum;
}

}  // namespace

// Leave-one-out cross-validation (Allen's PRESS): Σ w_k |r_k|² / (1 − h_k)², r_k the point's residual and h_k its
// leverage. Unlike GCV, which replaces each h_k by their mean, it sees a point that alone holds a control point
// (h_k near 1): with scattered points on a fine basis that is where an almost unpenalised fit swings between
// the points, and GCV, blind to it, would choose such a fit for exact data.
double leave_one_out(const CvRows& rows, const std::vector<double>& D, std::span<const double> Z, int b) {
  const std::size_t n_rows = rows.y.size();
  // Fixed blocks summed in order: the same sum for any thread count; small enough that 10 000 rows share out over two
  // cores (10 blocks, not 3).
  constexpr std::size_t kBlock = 1024;
  const std::size_t blocks = (n_rows + kBlock - 1) / kBlock;
  std::vector<double> part(blocks, 0.0);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t blk) {
    const std::size_t first = blk * kBlock, last = std::min(n_rows, (blk + 1) * kBlock);
    part[blk] = rows.m == 16 ? leave_one_out_terms<16>(rows, first, last, D, Z, b)  // bicubic: the pipeline's fits
                             : leave_one_out_terms<Eigen::Dynamic>(rows, first, last, D, Z, b);
  });
  double total = 0.0;
  for (double x : part) total += x;
  return total;
}

namespace {

// The leave-span-out terms of the spans [first, last) of `starts` (each span's rows are rows starts[s] to
// starts[s + 1], the rows being in span order), in order. Leaving the rows B of a span out of a fit with λ fixed
// changes their residuals r_B to (I − H_BB)⁻¹ r_B, H_BB = R_B Z R_Bᵀ W_B (Z over the span's m unknowns): by Woodbury,
// r_B + R_B (Z⁻¹ − R_Bᵀ W_B R_B)⁻¹ R_Bᵀ W_B r_B, an m × m solve per span whatever its number of points: the deletion
// identity of a linear smoother, with the block of the hat matrix in place of one point's h_k (blocked
// cross-validation: Arlot and Celisse, "A survey of cross-validation procedures for model selection", 2010).
template <int M>
double leave_span_out_terms(const CvRows& rows, const std::vector<std::size_t>& starts, std::size_t first,
                            std::size_t last, const std::vector<double>& D, std::span<const double> Z, int b,
                            double* span_terms) {
  const std::size_t mm = static_cast<std::size_t>(rows.m);
  using Square = Eigen::Matrix<double, M, M>;
  double sum = 0.0;
  for (std::size_t s = first; s < last; ++s) {
    const double before = sum;
    const std::size_t a = starts[s], e = starts[s + 1];
    // A THB row's own functions only: its padding repeats an unknown, which would make the block singular.
    const int m = rows.len[a];
    Square block(m, m), gram(m, m);
    Eigen::Matrix<double, M, 3> d(m, 3), g(m, 3);
    const int* idx = &rows.idx[a * mm];
    gather_block(Z, b, idx, m, block.data());
    for (int k = 0; k < m; ++k) {
      const std::size_t I = static_cast<std::size_t>(idx[k]);
      d.row(k) << D[3 * I], D[3 * I + 1], D[3 * I + 2];
    }
    gram.setZero();
    g.setZero();
    for (std::size_t i = a; i < e; ++i) {
      const Eigen::Map<const Eigen::Matrix<double, M, 1>> R(&rows.R[i * mm], m);
      const Eigen::RowVector3d r = (d.transpose() * R - rows.y[i]).transpose();
      gram.noalias() += rows.w[i] * R * R.transpose();
      g.noalias() += rows.w[i] * R * r;
    }
    // Z is the inverse of the whole normal matrix; its block's inverse exceeds RᵀWR of the span's own rows by the
    // penalty's and the other points' hold on these unknowns: positive definite.
    const Eigen::LDLT<Square> z(block);
    const Square K = z.solve(Square::Identity(m, m)) - gram;
    const Eigen::Matrix<double, M, 3> Kg = K.ldlt().solve(g);
    for (std::size_t i = a; i < e; ++i) {
      const Eigen::Map<const Eigen::Matrix<double, M, 1>> R(&rows.R[i * mm], m);
      const Eigen::RowVector3d r = (d.transpose() * R - rows.y[i]).transpose() + R.transpose() * Kg;
      sum += rows.w[i] * r.squaredNorm();
    }
    if (span_terms != nullptr) span_terms[s] = sum - before;
  }
  return sum;
}

}  // namespace

// Leave-span-out cross-validation: Σ w_k |r_k^(−span)|², each point's residual from the fit made without every point
// of its knot span. Leave-one-out judges λ by how well a point is predicted from its nearest neighbours, which on a
// scanning probe's lines are on its own line: it then chooses almost no smoothing, and across the lines, where
// nothing but the smoothing holds the fit, the fit swings (shape suite, lines 4 mm apart, σ = 3 µm: contacts up to
// 0.29 mm off). A span's points left out together must be predicted from other lines, as the fit between the lines
// is.
double leave_span_out(const CvRows& rows, const std::vector<double>& D, std::span<const double> Z, int b,
                      std::vector<double>* span_terms) {
  const std::vector<std::size_t>& starts = rows.span_starts;
  const std::size_t spans = starts.size() - 1;
  if (span_terms != nullptr) span_terms->assign(spans, 0.0);
  double* terms = span_terms != nullptr ? span_terms->data() : nullptr;
  // Fixed groups of spans summed in order: the same sum for any thread count.
  constexpr std::size_t kSpansPerGroup = 32;
  const std::size_t groups = (spans + kSpansPerGroup - 1) / kSpansPerGroup;
  std::vector<double> part(groups, 0.0);
  tbb::parallel_for(std::size_t{0}, groups, [&](std::size_t grp) {
    const std::size_t first = grp * kSpansPerGroup, last = std::min(spans, (grp + 1) * kSpansPerGroup);
    part[grp] = rows.m == 16 ? leave_span_out_terms<16>(rows, starts, first, last, D, Z, b, terms)
                             : leave_span_out_terms<Eigen::Dynamic>(rows, starts, first, last, D, Z, b, terms);
  });
  double total = 0.0;
  for (double x : part) total += x;
  return total;
}

}  // namespace probecomp::fitting::detail
