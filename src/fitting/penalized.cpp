#include "probecomp/fitting/penalized.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "assembly.hpp"
#include "band.hpp"
#include "hierarchical_rows.hpp"
#include "penalty.hpp"
#include "rational_basis.hpp"

namespace probecomp::fitting {

namespace {

using detail::RationalBasis;
using nurbs::Surface;

// The band algebra is in band.cpp, the thin-plate penalty in penalty.cpp.
using detail::Band;
using detail::Ordering;
using detail::ThinPlateTerms;
using detail::band_inverse;
using detail::block_quadratic_form;
using detail::inside;
using detail::chunk_count;
using detail::cholesky;
using detail::gather_block;
using detail::solve;
using detail::thin_plate_energy;

// The unknown each of rb's basis functions multiplies, in idx.
void row_unknowns(const Surface& s, const Ordering& order, const RationalBasis& rb, int* idx) {
  const int p = s.p(), q = s.q();
  for (int i = 0; i <= p; ++i)
    for (int j = 0; j <= q; ++j) idx[i * (q + 1) + j] = order.index(rb.i0 + i, rb.j0 + j);
}

// The start surface's control points in Cartesian form, row i (u) major: made once per fit for every basis row,
// which would otherwise divide each of its (p+1)(q+1) homogeneous points by its weight again.
std::vector<Point3> cartesian_net(const Surface& s) {
  std::vector<Point3> net(static_cast<std::size_t>(s.num_u()) * static_cast<std::size_t>(s.num_v()));
  for (int i = 0; i < s.num_u(); ++i)
    for (int j = 0; j < s.num_v(); ++j) net[static_cast<std::size_t>(i) * s.num_v() + j] = s.control_point(i, j);
  return net;
}

// A point's basis row: the fitted functions non-zero at t, their values and unknowns. Those are the surface s's
// rational basis functions, or with a hierarchical basis (hierarchical.hpp, s its output surface) the THB
// functions reduced from them. Rows are `m` long: a THB row shorter than that is padded with zero values on its
// last unknown, which add nothing to any sum, and `len` says how many are its own. `key` names t's knot span of s
// (its first control point's index in `order`): rows with one key have the same unknowns.
struct RowMaker {
  const Surface& s;
  std::span<const Point3> net;  // cartesian_net(s)
  const Ordering& order;        // of s's control points
  const HierarchicalBasis* thb = nullptr;
  int n = 0;  // unknowns
  int m = 0;  // row length
  RowMaker(const Surface& s_, std::span<const Point3> net_, const Ordering& order_, const HierarchicalBasis* thb_)
      : s(s_), net(net_), order(order_), thb(thb_), n(thb_ ? thb_->unknowns : s_.num_u() * s_.num_v()),
        m(thb_ ? thb_->max_row : (s_.p() + 1) * (s_.q() + 1)) {}
  [[nodiscard]] int bandwidth() const {
    return std::min(thb ? thb->bandwidth : order.bandwidth(s.p(), s.q()), n - 1);
  }
  // The row at t in R, idx, key and len; returns the start surface's point S⁰(t), which every use of a row needs.
  Vector3 operator()(const SurfaceParameter& t, RationalBasis& rb, double* R, int* idx, int& key, int& len) const {
    detail::rational_basis(s, t.u, t.v, rb);
    const int p = s.p(), q = s.q();
    Vector3 S0 = Vector3::Zero();
    for (int i = 0; i <= p; ++i) {
      const Point3* row = &net[static_cast<std::size_t>(rb.i0 + i) * s.num_v() + rb.j0];
      for (int j = 0; j <= q; ++j) S0 += rb.R[i * (q + 1) + j] * row[j];
    }
    key = order.index(rb.i0, rb.j0);
    if (thb == nullptr) {
      row_unknowns(s, order, rb, idx);
      std::copy(rb.R, rb.R + m, R);
      len = m;
    } else {
      len = detail::reduce_row(*thb, rb.i0, rb.j0, rb.R, R, idx);
      std::fill(R + len, R + m, 0.0);
      std::fill(idx + len, idx + m, idx[len - 1]);
    }
    return S0;
  }
};

// Points the cross-validation score is summed over at most.
constexpr std::size_t kCvPoints = 16384;
// The cross-validation takes every stride-th point: every point below 2·kCvPoints.
std::size_t cv_stride(std::size_t n_points) { return std::max<std::size_t>(1, n_points / kCvPoints); }

// The points the leave-one-out score is summed over, each with its basis row (the nonzero R_I and their unknowns)
// and its offset from the start surface, y_k = x_k − S⁰(u_k, v_k): made once per fit, used by every trial λ.
// Above kCvPoints points, every stride-th point (in input order, so the same points for every λ): each term is
// exact for its point, so the sum over the sample estimates the whole sum without bias, at a bounded cost.
// The rows are ordered by knot span (stably: the same order for any thread count), so that each trial reads the
// band inverse once per span, not once per point.
struct CvRows {
  int m = 0;                 // basis functions per row (RowMaker::m)
  std::vector<int> idx;      // m per row
  std::vector<double> R;     // m per row
  std::vector<int> key;      // one per row: its knot span (RowMaker)
  std::vector<int> len;      // one per row: its own functions, the first len of its m
  std::vector<Vector3> y;    // one per row
  std::vector<double> w;     // one per row
  // Each point's row, kNoRow for a point of weight 0, when the rows are those of every point (a stride of 1); else
  // empty. The fit's assembly and its variance factors then take the rows made here instead of evaluating each
  // point's basis again: the same numbers.
  static constexpr std::uint32_t kNoRow = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> row_of_point;
  // Where each knot span's rows begin (rows are in span order), and the end: for leave-span-out.
  std::vector<std::size_t> span_starts;
  [[nodiscard]] bool cover_every_point() const { return !row_of_point.empty(); }
};

// The data's normal equations for the displacement: AᵀWA, AᵀWy and yᵀWy with y_k = x_k − S⁰(u_k, v_k).
struct DataTerms {
  Band AtWA;
  std::vector<double> AtWy;  // n × 3
  double yWy = 0.0;
  double weight_sum = 0.0;
  int used = 0;
};

// `rows`, when given, cover every point and give each point's basis row and offset (else each is evaluated here).
DataTerms assemble_data(const RowMaker& maker, int b, std::span<const Point3> points,
                        std::span<const SurfaceParameter> params, std::span<const double> weights, const CvRows* rows) {
  const int n = maker.n;
  const std::size_t n_points = points.size();
  const std::size_t bytes = static_cast<std::size_t>(n) * (b + 4) * sizeof(double);
  const std::size_t chunks = chunk_count(n_points, bytes);
  std::vector<DataTerms> parts(chunks);
  // Consecutive points in one knot span (a scan line crosses a span in tens of points) share their unknowns:
  // their outer products are summed in a small dense block, which is added into the band once per run of them,
  // instead of each point's products scattered into the band (a million points: about twice as fast).
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    DataTerms& t = parts[c];
    t.AtWA = Band(n, b);
    t.AtWy.assign(static_cast<std::size_t>(n) * 3, 0.0);
    RationalBasis rb;
    const int m = maker.m;
    std::vector<int> own_idx(static_cast<std::size_t>(m)), run_idx(own_idx);
    std::vector<double> own_R(static_cast<std::size_t>(m));
    std::vector<double> block(static_cast<std::size_t>(m * m));  // block[x·m + y], y ≤ x: Σ w R_x R_y over the run
    std::vector<double> block_y(static_cast<std::size_t>(m * 3)); // Σ w R_x y
    int run_span = -1;  // the run's knot span (RowMaker's key)
    auto flush = [&] {
      if (run_span < 0) return;
      for (int x = 0; x < m; ++x) {
        for (int y = 0; y <= x; ++y) {
          const int I = std::max(run_idx[x], run_idx[y]), J = std::min(run_idx[x], run_idx[y]);
          t.AtWA.at(I, J) += block[x * m + y];
        }
        for (int c3 = 0; c3 < 3; ++c3) t.AtWy[3 * static_cast<std::size_t>(run_idx[x]) + c3] += block_y[x * 3 + c3];
      }
    };
    for (std::size_t k = n_points * c / chunks; k < n_points * (c + 1) / chunks; ++k) {
      const double w = weights.empty() ? 1.0 : weights[k];
      if (w == 0.0) continue;
      const int* idx = own_idx.data();
      const double* R = own_R.data();
      Vector3 y;
      int key = 0, len = 0;
      if (rows != nullptr) {
        const std::size_t r = rows->row_of_point[k];
        idx = &rows->idx[r * static_cast<std::size_t>(m)];
        R = &rows->R[r * static_cast<std::size_t>(m)];
        y = rows->y[r];
        key = rows->key[r];
      } else {
        y = points[k] - maker(params[k], rb, own_R.data(), own_idx.data(), key, len);
      }
      if (key != run_span) {
        flush();
        run_span = key;
        std::copy(idx, idx + m, run_idx.begin());
        std::fill(block.begin(), block.end(), 0.0);
        std::fill(block_y.begin(), block_y.end(), 0.0);
      }
      for (int x = 0; x < m; ++x) {
        const double wx = w * R[x];
        for (int yy = 0; yy <= x; ++yy) block[x * m + yy] += wx * R[yy];
        for (int c3 = 0; c3 < 3; ++c3) block_y[x * 3 + c3] += wx * y[c3];
      }
      t.yWy += w * y.squaredNorm();
      t.weight_sum += w;
      ++t.used;
    }
    flush();
  });
  DataTerms& out = parts[0];
  for (std::size_t c = 1; c < chunks; ++c) {
    out.AtWA.add(parts[c].AtWA);
    for (std::size_t k = 0; k < out.AtWy.size(); ++k) out.AtWy[k] += parts[c].AtWy[k];
    out.yWy += parts[c].yWy;
    out.weight_sum += parts[c].weight_sum;
    out.used += parts[c].used;
  }
  return std::move(out);
}


// One trial λ: the factor, the displacement, the residual sum of squares and tr H.
struct Trial {
  bool ok = false;
  double log10_smoothing = 0.0, lambda = 0.0;
  double log10_anisotropy = 0.0;
  double rss = 0.0, trace = 0.0, cv_score = std::numeric_limits<double>::infinity();
  std::vector<double> Z;  // the band of the inverse (for tr H, the leverages and the variance factors)
  Band L;                 // the Cholesky factor of AᵀWA + λG + εI (for the smoothing bias)
  std::vector<double> D;  // n × 3
};

}  // namespace

// The fit at its λ: the factor of AᵀWA + λG + εI and each point's basis row and weight (PenalizedFitResult::linear).
struct LinearFit {
  Band L;
  CvRows rows;  // covering every point (CvRows::cover_every_point)
};

namespace {

// Passes of the smoothing-bias estimate (see fit_penalized). On exact data from a surface in the fit's space, where
// a fixed λ's whole error is its bias, the estimate misses 20, 21 and 44 % of it (rms) at relative λ 1e-3, 1e-2
// and 1e-1 after two passes, 8, 12 and 29 % after four, 1, 9 and 18 % after eight (FitPenalized.
// TheSmoothingBiasItReportsIsTheErrorOfAFitToExactData). On the shape suite, 8 draws of the noise each, the lowest
// region's ±2u coverage averaged over the draws rose from 84.5 to 88.2 % (S07), 87.8 to 91.3 % (S09) and 89.1 to
// 93.9 % (S11) from two passes to eight; sixteen added under a point more, and the overall coverage of the
// quietest cases crept past 99 %.
constexpr int kSmoothingBiasPasses = 8;

// The largest memory the λ scan's trials may hold at once to run side by side (each its factor and band inverse:
// 2 n (b + 1) doubles; a 10 000-point face's 9 trials, 1.2 MB; a million points' finest fits, hundreds).
constexpr std::size_t kParallelScanBytes = std::size_t{16} << 20;

CvRows cv_rows(const RowMaker& maker, std::span<const Point3> points, std::span<const SurfaceParameter> params,
               std::span<const double> weights) {
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
  std::vector<std::size_t> place(static_cast<std::size_t>(order.nu) * static_cast<std::size_t>(order.nv) + 1, 0);
  for (const int k : key) ++place[static_cast<std::size_t>(k) + 1];
  std::partial_sum(place.begin(), place.end(), place.begin());
  std::vector<std::size_t> to(chosen.size());
  for (std::size_t r = 0; r < chosen.size(); ++r) to[r] = place[static_cast<std::size_t>(key[r])]++;
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
  for (std::size_t r = 0; r < chosen.size(); ++r) {
    if (r == 0 || rows.key[r] != rows.key[r - 1]) rows.span_starts.push_back(r);
  }
  rows.span_starts.push_back(chosen.size());
  if (stride == 1) {
    rows.row_of_point.assign(n_points, CvRows::kNoRow);
    for (std::size_t r = 0; r < chosen.size(); ++r) rows.row_of_point[chosen[r]] = static_cast<std::uint32_t>(to[r]);
  }
  return rows;
}

// The leave-one-out terms of rows [first, last), in order (see leave_one_out); M is the row length m when fixed at
// compile time (Eigen::Dynamic otherwise), so that a bicubic row's products stay in vector registers, as in
// block_quadratic_form (timings in docs/performance.md).
template <int M>
double leave_one_out_terms(const CvRows& rows, std::size_t first, std::size_t last, const std::vector<double>& D,
                           const std::vector<double>& Z, int b) {
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

// Leave-one-out cross-validation (Allen's PRESS): Σ w_k |r_k|² / (1 − h_k)², r_k the point's residual and h_k its
// leverage. Unlike GCV, which replaces each h_k by their mean, it sees a point that alone holds a control point
// (h_k near 1): with scattered points on a fine basis that is where an almost unpenalised fit swings between
// the points, and GCV, blind to it, would choose such a fit for exact data.
double leave_one_out(const CvRows& rows, const std::vector<double>& D, const std::vector<double>& Z, int b) {
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

// The leave-span-out terms of the spans [first, last) of `starts` (each span's rows are rows starts[s] to
// starts[s + 1], the rows being in span order), in order. Leaving the rows B of a span out of a fit with λ fixed
// changes their residuals r_B to (I − H_BB)⁻¹ r_B, H_BB = R_B Z R_Bᵀ W_B (Z over the span's m unknowns): by Woodbury,
// r_B + R_B (Z⁻¹ − R_Bᵀ W_B R_B)⁻¹ R_Bᵀ W_B r_B, an m × m solve per span whatever its number of points: the deletion
// identity of a linear smoother, with the block of the hat matrix in place of one point's h_k (blocked
// cross-validation: Arlot and Celisse, "A survey of cross-validation procedures for model selection", 2010).
template <int M>
double leave_span_out_terms(const CvRows& rows, const std::vector<std::size_t>& starts, std::size_t first,
                            std::size_t last, const std::vector<double>& D, const std::vector<double>& Z, int b) {
  const std::size_t mm = static_cast<std::size_t>(rows.m);
  using Square = Eigen::Matrix<double, M, M>;
  double sum = 0.0;
  for (std::size_t s = first; s < last; ++s) {
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
  }
  return sum;
}

// Leave-span-out cross-validation: Σ w_k |r_k^(−span)|², each point's residual from the fit made without every point
// of its knot span. Leave-one-out judges λ by how well a point is predicted from its nearest neighbours, which on a
// scanning probe's lines are on its own line: it then chooses almost no smoothing, and across the lines, where
// nothing but the smoothing holds the fit, the fit swings (shape suite, lines 4 mm apart, σ = 3 µm: contacts up to
// 0.29 mm off). A span's points left out together must be predicted from other lines, as the fit between the lines
// is.
double leave_span_out(const CvRows& rows, const std::vector<double>& D, const std::vector<double>& Z, int b) {
  const std::vector<std::size_t>& starts = rows.span_starts;
  const std::size_t spans = starts.size() - 1;
  // Fixed groups of spans summed in order: the same sum for any thread count.
  constexpr std::size_t kSpansPerGroup = 32;
  const std::size_t groups = (spans + kSpansPerGroup - 1) / kSpansPerGroup;
  std::vector<double> part(groups, 0.0);
  tbb::parallel_for(std::size_t{0}, groups, [&](std::size_t grp) {
    const std::size_t first = grp * kSpansPerGroup, last = std::min(spans, (grp + 1) * kSpansPerGroup);
    part[grp] = rows.m == 16 ? leave_span_out_terms<16>(rows, starts, first, last, D, Z, b)
                             : leave_span_out_terms<Eigen::Dynamic>(rows, starts, first, last, D, Z, b);
  });
  double total = 0.0;
  for (double x : part) total += x;
  return total;
}

Trial evaluate(const DataTerms& data, const Band& G, double scale_ratio, double ridge, double log10_smoothing,
               const CvRows& rows, CrossValidation cv) {
  Trial t;
  t.log10_smoothing = log10_smoothing;
  t.lambda = std::pow(10.0, log10_smoothing) * scale_ratio;
  Band N = data.AtWA;
  N.add(G, t.lambda);
  for (int I = 0; I < N.n; ++I) N.at(I, I) += ridge;
  if (!cholesky(N)) return t;
  t.D = data.AtWy;
  solve(N, t.D);
  // RSS = yᵀWy − 2 Dᵀ AᵀWy + Dᵀ AᵀWA D, per coordinate (y is the small displacement from the start, so the
  // difference loses nothing that matters).
  double quad = 0.0, cross = 0.0;
  const int n = N.n, b = N.b;
  for (int I = 0; I < n; ++I) {
    for (int c = 0; c < 3; ++c) cross += t.D[3 * I + c] * data.AtWy[3 * I + c];
    for (int J = std::max(0, I - b); J <= I; ++J) {
      const double a = data.AtWA.at(I, J);
      if (a == 0.0) continue;
      double dot = 0.0;
      for (int c = 0; c < 3; ++c) dot += t.D[3 * I + c] * t.D[3 * J + c];
      quad += (J == I ? 1.0 : 2.0) * a * dot;
    }
  }
  t.rss = std::max(data.yWy - 2.0 * cross + quad, 0.0);
  std::vector<double> Z = band_inverse(N);
  double trace = 0.0;
  for (int I = 0; I < n; ++I) {
    for (int J = std::max(0, I - b); J <= I; ++J) {
      const double a = data.AtWA.at(I, J);
      if (a == 0.0) continue;
      trace += (J == I ? 1.0 : 2.0) * a * Z[static_cast<std::size_t>(J) * (b + 1) + (I - J)];
    }
  }
  t.trace = trace;
  t.cv_score = (cv == CrossValidation::LeaveSpanOut ? leave_span_out(rows, t.D, Z, b) : leave_one_out(rows, t.D, Z, b)) /
               data.weight_sum;
  t.ok = std::isfinite(t.rss) && std::isfinite(trace);
  t.Z = std::move(Z);
  t.L = std::move(N);
  return t;
}

// The fit in the tensor space of `start`, or with `thb` in that hierarchical basis (its output surface `start`).
PenalizedFitResult fit_on(const Surface& start, const HierarchicalBasis* thb, std::span<const Point3> points,
                          std::span<const SurfaceParameter> params, std::span<const double> weights,
                          const PenalizedFitOptions& options, std::span<const double> span_weights) {
  PenalizedFitResult result{.status = PenalizedFitResult::Status::NotDone, .surface = start};
  const std::size_t n_points = points.size();
  if (n_points == 0 || params.size() != n_points || (!weights.empty() && weights.size() != n_points)) return result;
  const nurbs::Domain dom = start.domain();
  for (std::size_t k = 0; k < n_points; ++k) {
    const double w = weights.empty() ? 1.0 : weights[k];
    if (!points[k].allFinite() || !inside(dom, params[k]) || !(w >= 0.0) || !std::isfinite(w)) return result;
  }
  const int nu = start.num_u(), nv = start.num_v();
  const Ordering order(nu, nv);
  const std::vector<Point3> net = cartesian_net(start);
  const RowMaker maker(start, net, order, thb);
  const int n = maker.n;
  const int b = maker.bandwidth();
  // The penalty's spans are the tensor surface's (with a hierarchical basis, its output surface's): each THB function
  // is one polynomial there. The fitted displacement's roughness is measured on the tensor control net.
  const int b_tensor = std::min(order.bandwidth(start.p(), start.q()), nu * nv - 1);
  auto penalty = [&] { return thin_plate_energy(start, order, b, span_weights, nullptr, nullptr, thb); };
  // The penalty's matrix is made side by side with the cross-validation's rows and the data's normal equations, each
  // still in its own fixed order (the same numbers), so that one's serial parts (the rows' counting sort, the sums of
  // the chunks) leave no core idle. Where the rows are every point's (the 10 000-point case), the normal equations
  // are summed from them after they are made, one basis evaluation a point instead of two; else each point's basis
  // row is made for them, side by side with the rows.
  DataTerms data;
  ThinPlateTerms terms;
  CvRows rows;
  if (cv_stride(n_points) == 1) {
    tbb::parallel_invoke([&] { rows = cv_rows(maker, points, params, weights); }, [&] { terms = penalty(); });
    data = assemble_data(maker, b, points, params, weights, &rows);
  } else {
    tbb::parallel_invoke([&] { data = assemble_data(maker, b, points, params, weights, nullptr); },
                         [&] { terms = penalty(); }, [&] { rows = cv_rows(maker, points, params, weights); });
  }
  if (data.used == 0 || !(data.weight_sum > 0.0)) return result;
  const double data_trace = data.AtWA.trace();
  const double ridge = options.ridge * data_trace / n;

  std::atomic<int> evaluations{0};  // trials may run side by side
  // One trial at relative smoothing t10 and anisotropy a10 (both log10). λ is relative to the trace of G(θ), so a
  // change of θ alone reshapes the penalty without changing its overall strength.
  // The scan's and most trials' penalty is at the starting anisotropy: made once, not once a trial.
  const double a0 = options.log10_anisotropy.value_or(0.0);
  const Band G_start = terms.combined(std::pow(10.0, a0));
  auto run = [&](double t10, double a10) {
    ++evaluations;
    std::optional<Band> own;
    if (a10 != a0) own = terms.combined(std::pow(10.0, a10));
    const Band& G = own ? *own : G_start;
    Trial t = evaluate(data, G, data_trace / std::max(G.trace(), 1e-300), ridge, t10, rows, options.cross_validation);
    t.log10_anisotropy = a10;
    return t;
  };
  // Golden sections of [lo, hi] for the trial `at(x)` with the smallest score (Kiefer 1953): the score is smooth
  // and has one minimum in practice once bracketed.
  auto golden = [&](double lo, double hi, int steps, auto&& at) {
    constexpr double kGolden = 0.6180339887498949;
    double x1 = hi - kGolden * (hi - lo), x2 = lo + kGolden * (hi - lo);
    Trial t1, t2;
    tbb::parallel_invoke([&] { t1 = at(x1); }, [&] { t2 = at(x2); });
    for (int step = 0; step < steps; ++step) {
      if (t1.cv_score <= t2.cv_score) {
        hi = x2;
        x2 = x1;
        t2 = std::move(t1);
        x1 = hi - kGolden * (hi - lo);
        t1 = at(x1);
      } else {
        lo = x1;
        x1 = x2;
        t1 = std::move(t2);
        x2 = lo + kGolden * (hi - lo);
        t2 = at(x2);
      }
    }
    return t1.cv_score <= t2.cv_score ? std::move(t1) : std::move(t2);
  };
  // Each trial keeps its factor and its band inverse, so the best one is used as it is, not evaluated again.
  Trial best;
  if (options.log10_smoothing) {
    best = run(*options.log10_smoothing, a0);
  } else {
    // A scan in decades, then golden sections of the best decade's two neighbours. A range no wider than two
    // scan steps (a search near a known λ) is bracketed already: golden sections of it alone.
    double lo = options.min_log10_smoothing, hi = options.max_log10_smoothing;
    if (hi - lo > 2.0 * options.scan_step) {
      std::vector<double> scan;
      for (double t10 = options.min_log10_smoothing; t10 <= options.max_log10_smoothing + 1e-9; t10 += options.scan_step) {
        scan.push_back(t10);
      }
      // The scan's trials are independent: all side by side when their factors and band inverses together are
      // small, else one at a time; compared in scan order (the same choice for any thread count).
      const std::size_t trial_bytes = 2 * sizeof(double) * static_cast<std::size_t>(n) * static_cast<std::size_t>(b + 1);
      const std::size_t at_once = trial_bytes * scan.size() <= kParallelScanBytes ? scan.size() : 1;
      for (std::size_t first = 0; first < scan.size(); first += at_once) {
        std::vector<Trial> trials(std::min(at_once, scan.size() - first));
        tbb::parallel_for(std::size_t{0}, trials.size(), [&](std::size_t k) { trials[k] = run(scan[first + k], a0); });
        for (Trial& t : trials) {
          if (t.ok && t.cv_score < best.cv_score) best = std::move(t);
        }
      }
      const double best_t = best.ok ? best.log10_smoothing : options.max_log10_smoothing;
      lo = std::max(best_t - options.scan_step, options.min_log10_smoothing);
      hi = std::min(best_t + options.scan_step, options.max_log10_smoothing);
    }
    Trial g = golden(lo, hi, options.golden_steps, [&](double x) { return run(x, a0); });
    if (g.cv_score <= best.cv_score) best = std::move(g);
    // Then the anisotropy at that smoothing, and the smoothing once more near it at the anisotropy found.
    if (options.anisotropic && !options.log10_anisotropy && best.ok) {
      const double t10 = best.log10_smoothing;
      Trial a = golden(-options.max_log10_anisotropy, options.max_log10_anisotropy, options.golden_steps,
                       [&](double x) { return run(t10, x); });
      if (a.cv_score < best.cv_score) {
        best = std::move(a);
        const double a10 = best.log10_anisotropy;
        Trial t = golden(std::max(t10 - 1.0, options.min_log10_smoothing), std::min(t10 + 1.0, options.max_log10_smoothing),
                         options.golden_steps, [&](double x) { return run(x, a10); });
        if (t.cv_score < best.cv_score) best = std::move(t);
      }
    }
  }
  if (options.log10_smoothing_offset != 0.0 && !options.log10_smoothing && best.ok) {
    const double moved = std::clamp(best.log10_smoothing + options.log10_smoothing_offset,
                                    options.min_log10_smoothing, options.max_log10_smoothing);
    Trial t = run(moved, best.log10_anisotropy);
    if (t.ok) best = std::move(t);
  }
  result.evaluations = evaluations;
  if (!best.ok) {
    result.status = PenalizedFitResult::Status::NumericalError;
    return result;
  }
  const std::vector<double>& Z = best.Z;

  // The displacement of start's control net, in `order` (a hierarchical basis's mapped through its coefficients).
  std::vector<double> expanded;
  if (thb != nullptr) {
    const std::vector<Vector3> net_d = control_net_displacement(*thb, best.D);
    expanded.resize(static_cast<std::size_t>(nu) * nv * 3);
    for (int i = 0; i < nu; ++i) {
      for (int j = 0; j < nv; ++j) {
        const auto I = static_cast<std::size_t>(order.index(i, j));
        for (int c = 0; c < 3; ++c) expanded[3 * I + static_cast<std::size_t>(c)] = net_d[static_cast<std::size_t>(i) * nv + j][c];
      }
    }
  }
  const std::vector<double>& D_net = thb != nullptr ? expanded : best.D;
  std::vector<HomogeneousPoint> Pw(start.homogeneous());
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const int I = order.index(i, j);
      const Vector3 d(D_net[3 * I], D_net[3 * I + 1], D_net[3 * I + 2]);
      if (!d.allFinite()) {
        result.status = PenalizedFitResult::Status::NumericalError;
        return result;
      }
      HomogeneousPoint& h = Pw[static_cast<std::size_t>(i) * nv + j];
      h.head<3>() += h.w() * d;
    }
  }
  result.surface = Surface(start.U(), start.V(), std::move(Pw));
  (void)thin_plate_energy(start, order, b_tensor, {}, &D_net, &result.span_roughness);
  result.log10_smoothing = best.log10_smoothing;
  result.log10_anisotropy = best.log10_anisotropy;
  result.lambda = best.lambda;
  result.effective_dof = best.trace;
  result.cv_score = best.cv_score;
  result.rss = best.rss;
  result.weight_sum = data.weight_sum;
  result.points_used = data.used;

  // The smoothing bias E[D̂] − D = −λ (AᵀWA + λG + εI)⁻¹ G D of the penalised fit (the whisker ε's own share
  // left out: far below the data's), with an estimate of D for the unknown D (a plug-in estimate, as for kernel
  // smoothers' bias). D̂ itself reads low where the penalty dominates: E[D̂] = S D with S = I − λM⁻¹G the fit's
  // shrinkage (M = AᵀWA + λG), so D = S⁻¹E[D̂]. Each pass β ← −λM⁻¹G (D̂ − β) adds one term of the Neumann series
  // S⁻¹ = Σ (λM⁻¹G)^j (its terms shrink: λM⁻¹G has eigenvalues in [0, 1)): after K passes a component the penalty
  // keeps a share s of is credited with 1 − (1 − s)^K of its bias, while the noise carried into the estimate grows
  // to at most K times the fit's own in the components the data hardly hold. One solve with the factor a pass.
  {
    std::optional<Band> own;
    if (best.log10_anisotropy != a0) own = terms.combined(std::pow(10.0, best.log10_anisotropy));
    const Band& G = own ? *own : G_start;
    auto bias_of = [&](const std::vector<double>& D) {
      std::vector<double> beta(static_cast<std::size_t>(n) * 3, 0.0);
      for (int I = 0; I < n; ++I) {
        for (int J = std::max(0, I - b); J <= I; ++J) {
          const double g = G.at(I, J);
          if (g == 0.0) continue;
          for (int c = 0; c < 3; ++c) {
            beta[3 * I + c] -= best.lambda * g * D[3 * J + c];
            if (J != I) beta[3 * J + c] -= best.lambda * g * D[3 * I + c];
          }
        }
      }
      solve(best.L, beta);
      return beta;
    };
    std::vector<double> beta = bias_of(best.D), corrected(beta.size());
    for (int pass = 1; pass < kSmoothingBiasPasses; ++pass) {
      for (std::size_t k = 0; k < beta.size(); ++k) corrected[k] = best.D[k] - beta[k];
      beta = bias_of(corrected);
    }
    // Each point's variance factor and smoothing bias, from one evaluation of its basis row.
    result.variance_factor.assign(n_points, 0.0);
    result.smoothing_bias.assign(n_points, Vector3::Zero());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_points, 1024), [&](const auto& range) {
      RationalBasis rb;
      const int m = maker.m;
      std::vector<int> own_idx(static_cast<std::size_t>(m));
      std::vector<double> own_R(static_cast<std::size_t>(m)), block(static_cast<std::size_t>(m * m));
      int run_span = -1;  // the knot span (RowMaker's key) of the basis row whose block is gathered
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        // The cross-validation's row where it made one (every point of weight > 0 below 2·kCvPoints points).
        const int* idx = own_idx.data();
        const double* R = own_R.data();
        int key = 0, len = 0;
        if (rows.cover_every_point() && rows.row_of_point[k] != CvRows::kNoRow) {
          const std::size_t r = rows.row_of_point[k];
          idx = &rows.idx[r * static_cast<std::size_t>(m)];
          R = &rows.R[r * static_cast<std::size_t>(m)];
          key = rows.key[r];
        } else {
          (void)maker(params[k], rb, own_R.data(), own_idx.data(), key, len);
        }
        if (key != run_span) {
          run_span = key;
          gather_block(Z, b, idx, m, block.data());
        }
        result.variance_factor[k] = block_quadratic_form(block.data(), R, m);
        Vector3 e = Vector3::Zero();
        for (int a = 0; a < m; ++a) {
          const std::size_t I = static_cast<std::size_t>(idx[a]);
          e += R[a] * Vector3(beta[3 * I], beta[3 * I + 1], beta[3 * I + 2]);
        }
        result.smoothing_bias[k] = e;
      }
    });
  }
  if (rows.cover_every_point()) {
    result.linear = std::make_shared<const LinearFit>(LinearFit{std::move(best.L), std::move(rows)});
  }
  result.status = PenalizedFitResult::Status::OK;
  return result;
}

}  // namespace

PenalizedFitResult fit_penalized(const Surface& start, std::span<const Point3> points,
                                 std::span<const SurfaceParameter> params, std::span<const double> weights,
                                 const PenalizedFitOptions& options, std::span<const double> span_weights) {
  return fit_on(start, nullptr, points, params, weights, options, span_weights);
}

PenalizedFitResult fit_penalized(const HierarchicalBasis& basis, std::span<const Point3> points,
                                 std::span<const SurfaceParameter> params, std::span<const double> weights,
                                 const PenalizedFitOptions& options, std::span<const double> span_weights) {
  return fit_on(basis.surface, &basis, points, params, weights, options, span_weights);
}

std::vector<double> null_statistics(const PenalizedFitResult& fit, int probes,
                                    const std::function<double(std::span<const double>)>& statistic) {
  if (!fit.linear || probes <= 0) return {};
  const LinearFit& f = *fit.linear;
  // Three draws a solve, one per coordinate (the fit treats each alike), drawn in point order from a fixed seed.
  constexpr std::uint64_t kNullSeed = 20261129;
  std::mt19937_64 rng(kNullSeed);
  std::normal_distribution<double> normal;
  const std::size_t n_points = f.rows.row_of_point.size();
  const auto m = static_cast<std::size_t>(f.rows.m);
  std::vector<double> noise(3 * n_points, 0.0), rhs(static_cast<std::size_t>(f.L.n) * 3), residual(n_points);
  std::vector<double> out;
  for (int first = 0; first < probes; first += 3) {
    std::fill(rhs.begin(), rhs.end(), 0.0);
    for (std::size_t k = 0; k < n_points; ++k) {
      // A point without a row has weight 0: no noise, and no part in the fit.
      const std::uint32_t r = f.rows.row_of_point[k];
      if (r == CvRows::kNoRow) continue;
      const double w = f.rows.w[r];
      for (std::size_t c = 0; c < 3; ++c) noise[3 * k + c] = normal(rng) / std::sqrt(w);
      for (std::size_t a = 0; a < m; ++a) {
        const double wR = w * f.rows.R[r * m + a];
        const auto I = static_cast<std::size_t>(f.rows.idx[r * m + a]);
        for (std::size_t c = 0; c < 3; ++c) rhs[3 * I + c] += wR * noise[3 * k + c];
      }
    }
    solve(f.L, rhs);
    for (std::size_t c = 0; c < 3 && first + static_cast<int>(c) < probes; ++c) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_points, 4096), [&](const auto& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          const std::uint32_t r = f.rows.row_of_point[k];
          double fitted = 0.0;
          for (std::size_t a = 0; r != CvRows::kNoRow && a < m; ++a) {
            fitted += f.rows.R[r * m + a] * rhs[3 * static_cast<std::size_t>(f.rows.idx[r * m + a]) + c];
          }
          residual[k] = noise[3 * k + c] - fitted;
        }
      });
      out.push_back(statistic(residual));
    }
  }
  return out;
}

}  // namespace probecomp::fitting
