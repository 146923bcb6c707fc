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
#include "basis_rows.hpp"
#include "cross_validation.hpp"
#include "penalty.hpp"
#include "rational_basis.hpp"

namespace probecomp::fitting {

namespace {

using detail::RationalBasis;
using nurbs::Surface;

// The band algebra is in band.cpp, the thin-plate penalty in penalty.cpp, the cross-validation in
// cross_validation.cpp.
using detail::Band;
using detail::CvRows;
using detail::RowMaker;
using detail::cartesian_net;
using detail::cv_rows;
using detail::cv_stride;
using detail::leave_one_out;
using detail::leave_span_out;
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
  detail::BandValues Z;  // the band of the inverse (for tr H, the leverages and the variance factors)
  Band L;                 // the Cholesky factor of AᵀWA + λG + εI (for the smoothing bias)
  std::vector<double> D;  // n × 3
  std::vector<double> cv_terms;  // leave-span-out: each span's term of the score (unscaled), in span order
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

// The one-standard-error rule on leave-span-out scores (see fit_on): a λ within this many standard errors of the
// best score counts as as good; the largest such λ is sought up to kSmootherReach decades above the best, to about
// kSmootherReach / 2^kSmootherBisections decades.
constexpr double kStandardErrors = 1.0;
constexpr double kSmootherReach = 3.0;
constexpr int kSmootherBisections = 5;

// The directional weights' search (PenalizedFitOptions::directional_smoothing): each moved in steps of this many
// decades while the fit predicts better, at most kDirectionalReach from where the sweep found it, the two in turn
// for at most kDirectionalSweeps sweeps. A move is kept only if the noise it leaves, RSS / (n − tr H), rises by
// less than kDirectionalNoiseRise: a smoother fit that predicts left-out points better by leaving more unexplained
// is following its own net's misfit, not the data (shape suite S11, a 0.3 mm crease at σ = 1.5 µm, where the net
// ran out of rounds: 0.672 -> 2.323 µm without the guard, 0.919 with it when searched on every net).
constexpr double kDirectionalStep = 0.5;
constexpr double kDirectionalReach = 2.0;
constexpr int kDirectionalSweeps = 2;
constexpr double kDirectionalNoiseRise = 0.01;

// The anisotropy is chosen on a fixed grid of log10 θ (this step, over ±max_log10_anisotropy), then at the vertex of
// a parabola through the grid's best three, so that the choice moves continuously with the data. Golden sections
// end at one of a discrete set of points: chosen again on each net, a small change of the data (the registration
// redone without 1 % gross errors) became a different θ and a different refinement, and the other points moved
// 2.94 µm (Pipeline.GrossOutliersMoveNoOtherPoint holds them within 0.5 µm; with the grid 0.014–0.18 µm).
constexpr double kAnisotropyGridStep = 0.5;
// θ is judged by score · (1 + kAnisotropyPrior · (log10 θ)²), a smooth preference for the isotropic energy where
// the score cannot tell directions apart: on a coarse net it is flat (shape suite D400's first fit, 20 control
// points: the same to five digits from θ = 10^-2 to 10^2; golden sections ended at 10^-1.91 and the face kept it,
// 1.61 µm std; 0.95 µm with the grid and this preference). At θ = 10^±2 it costs 0.04 %; a clear direction gains
// 0.5–4 % (S24's wave band 0.5 %, D400's seventh net 3.6 %).
constexpr double kAnisotropyPrior = 1e-4;

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
    for (int J = data.AtWA.row_start(I); J <= I; ++J) {
      const double a = data.AtWA.at(I, J);
      if (a == 0.0) continue;
      double dot = 0.0;
      for (int c = 0; c < 3; ++c) dot += t.D[3 * I + c] * t.D[3 * J + c];
      quad += (J == I ? 1.0 : 2.0) * a * dot;
    }
  }
  t.rss = std::max(data.yWy - 2.0 * cross + quad, 0.0);
  detail::BandValues Z = band_inverse(N);
  double trace = 0.0;
  for (int I = 0; I < n; ++I) {
    for (int J = data.AtWA.row_start(I); J <= I; ++J) {
      const double a = data.AtWA.at(I, J);
      if (a == 0.0) continue;
      trace += (J == I ? 1.0 : 2.0) * a * Z[static_cast<std::size_t>(J) * (b + 1) + (I - J)];
    }
  }
  t.trace = trace;
  t.cv_score = (cv == CrossValidation::LeaveSpanOut ? leave_span_out(rows, t.D, Z, b, &t.cv_terms) : leave_one_out(rows, t.D, Z, b)) /
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
  // is one polynomial there. The fitted displacement's energy per span is measured on the tensor control net.
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
    tbb::parallel_invoke(
        [&] { rows = cv_rows(maker, points, params, weights, options.cv_fold_u, options.cv_fold_v); },
        [&] { terms = penalty(); });
    data = assemble_data(maker, b, points, params, weights, &rows);
  } else {
    tbb::parallel_invoke([&] { data = assemble_data(maker, b, points, params, weights, nullptr); },
                         [&] { terms = penalty(); },
                         [&] { rows = cv_rows(maker, points, params, weights, options.cv_fold_u, options.cv_fold_v); });
  }
  if (data.used == 0 || !(data.weight_sum > 0.0)) return result;
  data.AtWA.first = detail::envelope(maker);  // every trial's normal matrix and factor inherit it
  const double data_trace = data.AtWA.trace();
  const double ridge = options.ridge * data_trace / n;

  std::atomic<int> evaluations{0};  // trials may run side by side
  // One trial at relative smoothing t10 and anisotropy a10 (both log10). λ is relative to the trace of G(θ), so a
  // change of θ alone reshapes the penalty without changing its overall strength.
  // The scan's and most trials' penalty is at the starting anisotropy: made once, not once a trial.
  const double a0 = options.log10_anisotropy.value_or(0.0);
  const Band G_start = terms.combined(std::pow(10.0, a0));
  auto run_with = [&](const Band& G, double t10, double a10) {
    ++evaluations;
    Trial t = evaluate(data, G, data_trace / std::max(G.trace(), 1e-300), ridge, t10, rows, options.cross_validation);
    t.log10_anisotropy = a10;
    return t;
  };
  auto penalty_at = [&](double a10) {
    std::optional<Band> own;
    if (a10 != a0) own = terms.combined(std::pow(10.0, a10));
    return own;
  };
  auto run = [&](double t10, double a10) {
    const std::optional<Band> own = penalty_at(a10);
    return run_with(own ? *own : G_start, t10, a10);
  };
  // The trials at(x) for every x, independent: all side by side when their factors and band inverses together are
  // small, else one at a time. Each x's judged score goes to `score` (infinite where the trial failed); the trial
  // with the smallest is returned, the first of equals in the order of xs (the same choice for any thread count).
  const std::size_t trial_bytes = 2 * sizeof(double) * static_cast<std::size_t>(n) * static_cast<std::size_t>(b + 1);
  auto scan_trials = [&](const std::vector<double>& xs, auto&& at, auto&& judge, std::vector<double>& score) {
    Trial best_of;
    double best_score = std::numeric_limits<double>::infinity();
    const std::size_t at_once = trial_bytes * xs.size() <= kParallelScanBytes ? xs.size() : 1;
    for (std::size_t first = 0; first < xs.size(); first += at_once) {
      std::vector<Trial> trials(std::min(at_once, xs.size() - first));
      tbb::parallel_for(std::size_t{0}, trials.size(), [&](std::size_t k) { trials[k] = at(xs[first + k]); });
      for (std::size_t k = 0; k < trials.size(); ++k) {
        if (!trials[k].ok) continue;
        score[first + k] = judge(trials[k]);
        if (score[first + k] < best_score) {
          best_score = score[first + k];
          best_of = std::move(trials[k]);
        }
      }
    }
    return best_of;
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
  // λ at the starting anisotropy: a scan in decades, then golden sections of the best decade's two neighbours. A
  // range no wider than two scan steps (a search near a known λ) is bracketed already: golden sections of it alone.
  auto search_smoothing = [&] {
    auto at = [&](double x) { return run_with(G_start, x, a0); };
    Trial found;
    double lo = options.min_log10_smoothing, hi = options.max_log10_smoothing;
    if (hi - lo > 2.0 * options.scan_step) {
      std::vector<double> scan;
      for (double t10 = options.min_log10_smoothing; t10 <= options.max_log10_smoothing + 1e-9; t10 += options.scan_step) {
        scan.push_back(t10);
      }
      std::vector<double> score(scan.size(), std::numeric_limits<double>::infinity());
      found = scan_trials(scan, at, [](const Trial& t) { return t.cv_score; }, score);
      const double best_t = found.ok ? found.log10_smoothing : options.max_log10_smoothing;
      lo = std::max(best_t - options.scan_step, options.min_log10_smoothing);
      hi = std::min(best_t + options.scan_step, options.max_log10_smoothing);
    }
    Trial g = golden(lo, hi, options.golden_steps, at);
    if (g.cv_score <= found.cv_score) found = std::move(g);
    return found;
  };
  auto judged = [](const Trial& t) {
    return t.cv_score * (1.0 + kAnisotropyPrior * t.log10_anisotropy * t.log10_anisotropy);
  };
  // Leave-span-out's terms of trial t less those of `than`, summed, and that sum's standard error over the spans
  // (NaN where the two were not scored on the same spans: no comparison with them holds).
  struct PairedDifference {
    double total = std::numeric_limits<double>::quiet_NaN(), standard_error = std::numeric_limits<double>::quiet_NaN();
  };
  auto paired_difference = [](const Trial& t, const Trial& than) {
    PairedDifference out;
    const std::size_t J = than.cv_terms.size();
    if (!t.ok || J < 2 || t.cv_terms.size() != J) return out;
    double mean = 0.0;
    for (std::size_t j = 0; j < J; ++j) mean += t.cv_terms[j] - than.cv_terms[j];
    mean /= static_cast<double>(J);
    double var = 0.0;
    for (std::size_t j = 0; j < J; ++j) {
      const double d = t.cv_terms[j] - than.cv_terms[j] - mean;
      var += d * d;
    }
    var /= static_cast<double>(J - 1);
    out.total = static_cast<double>(J) * mean;
    out.standard_error = std::sqrt(static_cast<double>(J) * var);
    return out;
  };
  // The smoothing as two directional weights (PenalizedFitOptions::directional_smoothing), L_u = λθ and L_v = λ/θ
  // in absolute terms, each moved with the other held (coordinate search: the cross term's weight, √(L_u L_v) = λ,
  // moves with them). A move must predict better by the judged score (on leave-span-out, whose scores are flat
  // over decades on scan lines, better by one standard error of the spans' paired differences, the rule's
  // counterpart) and leave the noise estimate within kDirectionalNoiseRise.
  auto search_directional = [&](Trial from) {
    auto at = [&](double lu10, double lv10) {
      const double a10 = 0.5 * (lu10 - lv10);
      if (std::abs(a10) > options.max_log10_anisotropy + 1e-9) return Trial{};
      const std::optional<Band> own = penalty_at(a10);
      const Band& G = own ? *own : G_start;
      const double t10 = 0.5 * (lu10 + lv10) - std::log10(data_trace / std::max(G.trace(), 1e-300));
      if (t10 < options.min_log10_smoothing - 1e-9 || t10 > options.max_log10_smoothing + 1e-9) return Trial{};
      return run_with(G, t10, a10);
    };
    auto noise = [&](const Trial& t) { return t.rss / std::max(1.0, static_cast<double>(data.used) - t.trace); };
    auto better = [&](const Trial& c, const Trial& than) {
      if (!c.ok || !(judged(c) < judged(than)) || noise(c) > (1.0 + kDirectionalNoiseRise) * noise(than)) return false;
      if (options.cross_validation != CrossValidation::LeaveSpanOut) return true;
      const PairedDifference d = paired_difference(c, than);
      return d.total < -kStandardErrors * d.standard_error;
    };
    for (int sweep = 0; sweep < kDirectionalSweeps; ++sweep) {
      bool moved = false;
      for (int which = 0; which < 2; ++which) {
        const double lu = std::log10(from.lambda) + from.log10_anisotropy;
        const double lv = std::log10(from.lambda) - from.log10_anisotropy;
        auto step = [&](double d) { return which == 0 ? at(lu + d, lv) : at(lu, lv + d); };
        // Both first steps side by side; then on in the better one's direction while it predicts better.
        std::vector<double> score(2, std::numeric_limits<double>::infinity());
        Trial first = scan_trials(std::vector<double>{-kDirectionalStep, kDirectionalStep}, step, judged, score);
        if (!better(first, from)) continue;
        const double sign = score[0] <= score[1] ? -1.0 : 1.0;
        from = std::move(first);
        moved = true;
        for (double d = 2.0 * kDirectionalStep; d <= kDirectionalReach + 1e-9; d += kDirectionalStep) {
          Trial next = step(sign * d);
          if (!better(next, from)) break;
          from = std::move(next);
        }
      }
      if (!moved) break;
    }
    return from;
  };
  // θ at the smoothing of `made`, a trial at the starting anisotropy (which stands for its grid point): the grid's
  // best by the judged score, or the vertex of the parabola through the best three where that is better.
  auto search_anisotropy = [&](const Trial& made) {
    const double t10 = made.log10_smoothing;
    std::vector<double> grid;
    for (double x = -options.max_log10_anisotropy; x <= options.max_log10_anisotropy + 1e-9; x += kAnisotropyGridStep) {
      grid.push_back(x);
    }
    std::vector<double> score(grid.size(), std::numeric_limits<double>::infinity());
    Trial a = scan_trials(grid, [&](double x) { return x == a0 ? made : run(t10, x); }, judged, score);
    const auto kb = static_cast<std::size_t>(std::min_element(score.begin(), score.end()) - score.begin());
    if (a.ok && kb > 0 && kb + 1 < grid.size() && std::isfinite(score[kb - 1]) && std::isfinite(score[kb + 1])) {
      const double den = score[kb - 1] - 2.0 * score[kb] + score[kb + 1];
      if (den > 0.0) {
        // The vertex of the parabola through three equally spaced points, h (f0 − f2) / (2 (f0 − 2 f1 + f2)) from
        // the middle one.
        const double x = grid[kb] + 0.5 * kAnisotropyGridStep * (score[kb - 1] - score[kb + 1]) / den;
        Trial v = run(t10, x);
        if (v.ok && judged(v) < judged(a)) a = std::move(v);
      }
    }
    return a;
  };
  // Each trial keeps its factor and its band inverse, so the best one is used as it is, not evaluated again.
  Trial best;
  if (options.lambda) {
    best = run(std::log10(*options.lambda * std::max(G_start.trace(), 1e-300) / data_trace), a0);
  } else if (options.log10_smoothing) {
    best = run(*options.log10_smoothing, a0);
  } else {
    best = search_smoothing();
    // Then the anisotropy at that smoothing, and the smoothing once more near it at the anisotropy found.
    if (options.anisotropic && !options.log10_anisotropy && best.ok) {
      const double t10 = best.log10_smoothing;
      Trial a = search_anisotropy(best);
      if (judged(a) < judged(best) && a.log10_anisotropy != best.log10_anisotropy) {
        best = std::move(a);
        const double a10 = best.log10_anisotropy;
        const std::optional<Band> own = penalty_at(a10);
        Trial t = golden(std::max(t10 - 1.0, options.min_log10_smoothing), std::min(t10 + 1.0, options.max_log10_smoothing),
                         options.golden_steps, [&](double x) { return run_with(own ? *own : G_start, x, a10); });
        if (t.cv_score < best.cv_score) best = std::move(t);
      }
    }
    // Leave-span-out scores are flat over decades of λ on scan lines (predicting a span's piece of a line tells
    // little of what the fit does between lines), and the minimum wanders with the noise: shape suite D500 over six
    // draws of it, log10 λ from -2.4 to -5.8, the fit swinging across the lines at the smallest (contacts 21 µm std,
    // 189 µm at worst, where the fitted centres were 1.3 µm rms off). Of the λ whose score is within the noise of
    // the best's, the largest is taken: the one-standard-error rule (Breiman, Friedman, Olshen and Stone 1984;
    // Hastie, Tibshirani and Friedman 2009, §7.10), the standard error that of the paired differences of the spans'
    // terms, so that a λ is passed over only where the spans' predictions are worse consistently, not on one span.
    if (options.cross_validation == CrossValidation::LeaveSpanOut && options.smoothest_within_one_standard_error &&
        best.ok && best.cv_terms.size() > 1) {
      auto within_noise = [&](const Trial& t) {
        const PairedDifference d = paired_difference(t, best);
        return d.total <= kStandardErrors * d.standard_error;
      };
      double lo = best.log10_smoothing, hi = std::min(best.log10_smoothing + kSmootherReach, options.max_log10_smoothing);
      std::optional<Trial> smoother;
      if (hi > lo) {
        Trial top = run(hi, best.log10_anisotropy);
        if (within_noise(top)) {
          smoother = std::move(top);
        } else {
          for (int i = 0; i < kSmootherBisections; ++i) {
            const double mid = 0.5 * (lo + hi);
            Trial t = run(mid, best.log10_anisotropy);
            if (within_noise(t)) {
              lo = mid;
              smoother = std::move(t);
            } else {
              hi = mid;
            }
          }
        }
      }
      if (smoother) best = std::move(*smoother);
    }
  }
  if (options.directional_smoothing && best.ok) {
    const double lambda = best.lambda, a10 = best.log10_anisotropy;
    best = search_directional(std::move(best));
    result.directional_moved = best.lambda != lambda || best.log10_anisotropy != a10;
  }
  if (options.log10_smoothing_offset != 0.0 && !options.log10_smoothing && !options.lambda && best.ok) {
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
  const detail::BandValues& Z = best.Z;

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
  (void)thin_plate_energy(start, order, b_tensor, {}, &D_net, &result.span_energy);
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
        for (int J = best.L.row_start(I); J <= I; ++J) {
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
