#include "probecomp/fitting/adaptive.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "probecomp/fitting/noise_estimate.hpp"
#include "probecomp/fitting/spans.hpp"
#include "probecomp/fitting/hierarchical.hpp"
#include "probecomp/nurbs/closest_point.hpp"
#include "probecomp/geometry/statistics.hpp"

#include "hierarchy_marks.hpp"
#include "nets.hpp"
#include "penalty.hpp"
#include "refinement_tests.hpp"
#include "representation_bias.hpp"
#include "span_weights.hpp"

namespace probecomp::fitting {

namespace {

using nurbs::Surface;

using geometry::kMadToSigma;
using geometry::median_in_place;

// The residuals' spread gives way to the local prediction errors as the noise estimate above this multiple of them
// (see fit_surface). Shape suite (--no-reference) and 48 unseen draws, against the nearest-neighbour differences
// at 1.25 before: at 1.25 here the demo's std is 0.96 µm and the suite's 1.340 µm median; at 1.35, 0.89 µm (as
// before) and 1.321 µm.
constexpr double kMisfitRatio = 1.35;

// A neighbourhood's mean-square excess counts as bias only above the χ² quantile exceeded by noise alone with
// this probability (see the bias estimate in fit_surface).
constexpr double kBiasSignificance = 0.01;

// A point whose own standardised residual is beyond this many σ (0.27 % of points on noise alone) is taken at
// its word: the fit may be off there by as much as the residual says, less the noise's share.
constexpr double kOwnResidualSigmas = 3.0;

// Half-width, in decades, of the smoothing search after a parameter correction (see fit_surface).
constexpr double kCorrectionBracket = 0.75;
// Later rounds seek λ no more than this many decades below the last round's, and, where the residuals show noise,
// up to the whole range's top. Below, the bound is what holds a fit from swinging between scan lines as λ drifts
// down round by round (see smoothest_within_one_standard_error below). Above, a bound of the same width capped the
// choice: along scan lines across a crease (shape suite D707, σ = 4.5 µm) λ sat at the bound round after round,
// from 10^-8.96 to 10^-4.96 on 330 control points, and the fit rang between the lines (contacts 7.5 µm std, normals
// up to 11° off; 0.91 µm without the bound). On exact data it stays: a steep dent's largest error rose from under
// 2 to 2.37 µm without it (Pipeline.ASteepDentWithoutNoiseKeepsEveryRow).
constexpr double kSmoothingWindow = 2.0;

// The finer start (AdaptiveFitOptions::dense_start_points_per_control_point) holds at most this many control
// points: a face of a million points would otherwise start at 62 500, band matrices of gigabytes. The shape suite's
// faces (6 000–7 000 points) start at 375–440; its largest fits end at about 3 000.
constexpr double kMaxDenseStartControlPoints = 4096.0;

// Cross-validation scores of two fits within this fraction of each other do not tell them apart (see fit_surface).
// Measured at 2 % over the shape suite's 94 faces (--no-reference): D207's worst region 43.4 -> 69.7 % with the
// balance (as at 1 %); with the roughness rule, faces with a region whose ±2u coverage is under 88 %, 27 -> 26.
constexpr double kCrossValidationTie = 0.02;

// The adaptive fit from one start (see fit_surface); `used`: the points with weight > 0; `local_noise` built over
// the points and weights.
AdaptiveFitResult refine_from(const Surface& start, std::span<const Point3> points,
                              std::span<const SurfaceParameter> params, std::span<const double> weights,
                              const AdaptiveFitOptions& options, std::size_t used,
                              const LocalPredictionNoise& local_noise);

}  // namespace

LocalSpread::LocalSpread(const AdaptiveFitResult& fit)
    : fit_(fit), bu_(fit.surface.U().breakpoints()), bv_(fit.surface.V().breakpoints()) {}

double LocalSpread::operator()(std::size_t k) const {
  const std::size_t s = span_at(bu_, bv_, fit_.params[k].u, fit_.params[k].v);
  return s < fit_.span_spread.size() ? fit_.span_spread[s] : fit_.noise_sigma;
}

std::vector<SurfaceParameter> correct_parameters(const Surface& s, std::span<const Point3> points,
                                                 std::span<const SurfaceParameter> params) {
  std::vector<SurfaceParameter> out(params.begin(), params.end());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 512), [&](const auto& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const nurbs::ClosestPointResult r = nurbs::refine_closest_point(s, points[k], params[k].u, params[k].v);
      if (r.ok()) out[k] = {r.u, r.v};
    }
  });
  return out;
}

double robust_noise_sigma(std::span<const double> residuals, std::span<const double> weights,
                          int unknowns_per_coordinate) {
  std::vector<double> r;
  r.reserve(residuals.size());
  for (std::size_t k = 0; k < residuals.size(); ++k) {
    if (weights.empty() || weights[k] > 0.0) r.push_back(residuals[k]);
  }
  if (r.empty()) return 0.0;
  std::vector<double> work = r;
  const double centre = median_in_place(work);
  for (double& x : r) x = std::abs(x - centre);
  const double mad = median_in_place(r);
  const double absorbed = std::min(static_cast<double>(unknowns_per_coordinate) / static_cast<double>(r.size()), 0.9);
  return kMadToSigma * mad / std::sqrt(1.0 - absorbed);
}

AdaptiveFitResult fit_surface(const Surface& start, std::span<const Point3> points,
                              std::span<const SurfaceParameter> params, std::span<const double> weights,
                              const AdaptiveFitOptions& options, const LocalPredictionNoise* local_noise) {
  std::size_t used = 0;
  for (std::size_t k = 0; k < points.size(); ++k) used += weights.empty() || (k < weights.size() && weights[k] > 0.0);
  // (One structure for both starts below: it depends on the points and weights only.)
  std::optional<LocalPredictionNoise> own;
  if (local_noise == nullptr) local_noise = &own.emplace(points, weights);
  AdaptiveFitResult from_start = refine_from(start, points, params, weights, options, used, *local_noise);
  // See AdaptiveFitOptions::representation_bias.
  auto with_representation_bias = [&](AdaptiveFitResult r, const Surface& from) {
    if (options.representation_bias && r.fitted()) detail::add_representation_bias(r, from, points, weights, options);
    return r;
  };
  // See AdaptiveFitOptions::dense_start_points_per_control_point.
  const double k = options.dense_start_points_per_control_point;
  if (!(k > 0.0) || !from_start.fitted() || !from_start.thin_misfit_seen) {
    return with_representation_bias(std::move(from_start), start);
  }
  const Surface dense = detail::uniformly_refined(start, static_cast<double>(used) / k, kMaxDenseStartControlPoints);
  if (dense.num_u() * dense.num_v() == start.num_u() * start.num_v()) {
    return with_representation_bias(std::move(from_start), start);
  }
  AdaptiveFitResult from_dense = refine_from(dense, points, params, weights, options, used, *local_noise);
  // Two fits of the same points that cross-validation cannot tell apart (scores within kCrossValidationTie) are
  // both plausible, and which is right where they disagree is not known: the one kept is taken to be off by at
  // least |r − r_other| at each point. Where the balance (SpatialPenalty::Balance) kept the coarse knots and missed
  // part of a broad bulge that the fit from the finer start followed (D207: scores 21.28 and 21.31 µm², worst
  // region's ±2u coverage 43.4 %), u held none of it; with this, 69.7 %.
  auto take_disagreement = [](AdaptiveFitResult& kept, const AdaptiveFitResult& other) {
    if (!other.fitted() || !(other.cv_score <= kept.cv_score * (1.0 + kCrossValidationTie))) return;
    for (std::size_t j = 0; j < kept.misfit.size(); ++j) {
      kept.misfit[j] = std::max(kept.misfit[j], std::abs(kept.residuals[j] - other.residuals[j]));
    }
  };
  if (!from_dense.fitted() || !(from_dense.cv_score < from_start.cv_score)) {
    take_disagreement(from_start, from_dense);
    return with_representation_bias(std::move(from_start), start);
  }
  take_disagreement(from_dense, from_start);
  from_dense.dense_start = true;
  from_dense.thin_misfit_seen = true;
  return with_representation_bias(std::move(from_dense), dense);
}

namespace {

AdaptiveFitResult refine_from(const Surface& start, std::span<const Point3> points,
                              std::span<const SurfaceParameter> params, std::span<const double> weights,
                              const AdaptiveFitOptions& options, std::size_t used,
                              const LocalPredictionNoise& local_noise) {
  AdaptiveFitResult result{.status = AdaptiveFitResult::Status::NotDone, .surface = start};
  std::vector<SurfaceParameter> t(params.begin(), params.end());
  // The knots so far on the start's exact shape: what each round's fit penalises the displacement from (never
  // the last round's fit, which would make the final surface a cascade of fits whose variance the last one's
  // hat matrix does not describe).
  Surface target = start;
  // With local refinement (AdaptiveFitOptions::local_refinement): the cells of `target` (its knot spans, and at
  // level l those halved l times) marked for a finer level of a THB basis, and that basis; none marked: the tensor
  // fit on `target`.
  const bool refine_locally = options.local_refinement && !options.split_only_where_points_either_side &&
                     options.fit.cross_validation == CrossValidation::LeaveOneOut;
  detail::LevelFlags marks;
  std::optional<HierarchicalBasis> basis;

  // The penalty's weight per knot span (a · V spans + b) of the surface fitted (target, or the basis's output
  // surface): lowered where the data show shape the fit misses, so that the flexibility added there is not
  // smoothed away by a λ that suits the rest of the face, nor spread over it (knot lines run across the whole
  // face; their new spans elsewhere keep the full penalty).
  std::vector<double> span_weight(static_cast<std::size_t>(target.U().num_spans() * target.V().num_spans()), 1.0);
  PenalizedFitOptions fit_options = options.fit;
  // Along scan lines (leave-span-out), where the data are noisy, the smoothest λ within the noise of the best score
  // (PenalizedFitOptions::smoothest_within_one_standard_error): on a score flat over decades, each round's search
  // starting from the last λ drifted round by round to where the fit swings between the lines (D500 over six draws
  // of the noise: log10 λ from −2.4 to −5.8, contacts' std 1.7–21.4 µm; with the rule −2.2 to −2.9, 1.5–2.0 µm).
  // Whether the data are noisy is told before the first fit by the points' distances from the start as their
  // neighbours predict them (LocalPredictionNoise: a local quadratic follows the deformation; S13 without noise
  // 1e-5 µm, D500 4.53 µm), and by each fit's residuals after it. (Tried and worse: the rule in the last round only,
  // from where the drift had already taken λ: D500 still 15–18 µm on three draws of six.)
  if (fit_options.cross_validation == CrossValidation::LeaveSpanOut) {
    const double before = local_noise.sigma(detail::along_normal(start, points, t, {}).residual);
    fit_options.smoothest_within_one_standard_error = std::isfinite(before) && before > options.noise_floor;
  }
  // While refinement is tried (see below): the last fit kept, and its cross-validation score.
  bool trying = false;
  bool thin_misfit_seen = false;  // AdaptiveFitResult::thin_misfit_seen
  std::optional<AdaptiveFitResult> kept;
  double kept_cv = std::numeric_limits<double>::infinity();
  double kept_rss = 0.0, kept_edf = 0.0;  // and its residual sum and trace, for scan lines' trials
  bool kept_saturated = false;            // and whether its penalty did nothing (detail::saturated)
  const bool by_f_test = fit_options.cross_validation == CrossValidation::LeaveSpanOut;
  auto undone = [&](const PenalizedFitResult& fit) {
    if (!trying) return false;
    if (!fit.ok()) return true;
    return by_f_test ? !detail::refinement_kept(kept_rss, kept_edf, kept_saturated, fit.rss, fit.effective_dof,
                                                fit.points_used)
                     : !(fit.cv_score < kept_cv);
  };
  auto restored = [&] {
    kept->thin_misfit_seen = thin_misfit_seen;
    return std::move(*kept);
  };
  auto fit_once = [&](const PenalizedFitOptions& o) {
    return basis ? fit_penalized(*basis, points, t, weights, o, span_weight)
                 : fit_penalized(target, points, t, weights, o, span_weight);
  };
  // The last net fitted once more with its smoothing moved as two directional weights (see below), and the last
  // round's result, returned where the search does not move (or that fit fails).
  bool polishing = false;
  std::optional<AdaptiveFitResult> unpolished;
  const bool polish_allowed = options.directional_smoothing && options.fit.anisotropic &&
                              !options.fit.log10_anisotropy && !options.fit.log10_smoothing && !options.fit.lambda;
  auto may_polish = [&](const AdaptiveFitResult& r) { return polish_allowed && r.noise_sigma > options.noise_floor; };
  auto start_polishing = [&](AdaptiveFitResult last) {  // `last` completed as a final result
    polishing = true;
    fit_options.log10_anisotropy = last.log10_anisotropy;
    fit_options.lambda = last.lambda;
    fit_options.directional_smoothing = true;
    unpolished = std::move(last);
    unpolished->thin_misfit_seen = thin_misfit_seen;
  };
  // The kept round's net, penalty weights and options, taken with `kept` where it explains the data and may be
  // polished: where a refinement tried is undone, that net is polished as any final net is (see below), not
  // returned unpolished (scan lines, D1102: 1.271 µm polished, 1.381 not).
  struct KeptNet {
    Surface target;
    std::optional<HierarchicalBasis> basis;
    std::vector<double> span_weight;
    PenalizedFitOptions fit_options;
  };
  std::optional<KeptNet> kept_net;
  auto polish_kept = [&] {
    if (!kept_net) return false;
    target = std::move(kept_net->target);
    basis = std::move(kept_net->basis);
    span_weight = std::move(kept_net->span_weight);
    fit_options = std::move(kept_net->fit_options);
    kept_net.reset();
    t = kept->params;
    trying = false;
    result = *kept;
    start_polishing(std::move(*kept));
    return true;
  };
  for (int round = 0;; ++round) {
    PenalizedFitResult fit = fit_once(fit_options);
    if (polishing && (!fit.ok() || !fit.directional_moved)) return std::move(*unpolished);
    // A round tried (see below) whose fit predicts left-out points no better is undone: judged before the
    // parameter corrections (the points' parameters are those the kept fit was scored with), so that a refinement
    // undone costs one fit, not three, and again after them.
    if (undone(fit)) {
      if (polish_kept()) continue;
      return restored();
    }
    for (int c = 0; c < options.parameter_corrections && fit.ok(); ++c) {
      t = correct_parameters(fit.surface, points, t);
      // The points moved along the surface by a fraction of their spacing: the smoothing is sought within
      // kCorrectionBracket decades of the last (golden sections only: 8 fits, against 17 for the full search).
      PenalizedFitOptions near = fit_options;
      near.log10_anisotropy = fit.log10_anisotropy;
      if (polishing) {
        // (At the weights the search found: λ searched again at its θ would undo half of its move.)
        near.lambda = fit.lambda;
        near.directional_smoothing = false;
      } else if (!options.fit.log10_smoothing) {
        // Around the λ cross-validation chose, not the one a study's offset moved it to (it is moved again).
        const double chosen = fit.log10_smoothing - options.fit.log10_smoothing_offset;
        near.min_log10_smoothing = std::max(fit_options.min_log10_smoothing, chosen - kCorrectionBracket);
        near.max_log10_smoothing = std::min(fit_options.max_log10_smoothing, chosen + kCorrectionBracket);
      }
      fit = fit_once(near);
    }
    if (undone(fit)) {
      if (polish_kept()) continue;
      return restored();
    }
    if (polishing && !fit.ok()) return std::move(*unpolished);
    if (!fit.ok()) {
      result.status = fit.status == PenalizedFitResult::Status::NotDone ? AdaptiveFitResult::Status::NotDone
                                                                        : AdaptiveFitResult::Status::NumericalError;
      return result;
    }
    const int unknowns = basis ? basis->unknowns : target.num_u() * target.num_v();

    result.surface = fit.surface;
    result.span_weight = basis ? std::vector<double>{} : span_weight;
    result.log10_anisotropy = fit.log10_anisotropy;
    result.lambda = fit.lambda;
    result.cv_score = fit.cv_score;
    result.params = t;
    detail::AlongNormal along = detail::along_normal(fit.surface, points, t, fit.smoothing_bias);
    fit.smoothing_bias = {};  // along the normal from here on (a million points: 24 MB freed)
    result.residuals = std::move(along.residual);
    result.control_points = unknowns;
    result.effective_dof = fit.effective_dof;
    result.log10_smoothing = fit.log10_smoothing;
    result.variance_factor = std::move(fit.variance_factor);

    const std::vector<double>& vf = result.variance_factor;
    // A residual's variance is σ²(1 − h_k) (h_k = w_k · variance factor, the point's leverage): residuals
    // divided by √(1 − h_k) all have variance σ² whatever the local flexibility of the fit.
    auto leverage = [&](std::size_t k) { return (weights.empty() ? 1.0 : weights[k]) * vf[k]; };
    std::vector<double> standardised(points.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      standardised[k] = result.residuals[k] / std::sqrt(std::max(1.0 - leverage(k), 0.05));
    }
    // The residuals' spread is the noise once the fit follows the shape; while it does not, the spread holds the
    // misfit too, and the local prediction errors (fitting/noise_estimate.hpp), which a smooth misfit does not
    // move, tell the noise. The spread is kept unless it is clearly above them, a misfit of more than 0.9 σ rms:
    // below that it is left to the span tests, measured against the spread, which then refine only where the
    // misfit stands out. (Measured against the noise itself from the first round, the refinement chased the noise:
    // 900 control points instead of 782 on the demo's panel, std 0.89 -> 0.99 µm.) The nearest neighbours'
    // differences, used before, read a wave as noise: 7.0 µm for σ = 4.5 µm under a 100 µm wave 8 mm long (S14),
    // where the local prediction reads 4.54 µm. Of the standardised residuals, the scale the span tests measure
    // against; too few points for a local quadratic: the spread.
    const double spread = robust_noise_sigma(standardised, weights, 0);
    const double local = local_noise.sigma(standardised);
    result.noise_sigma = std::isfinite(local) && spread > kMisfitRatio * local ? local : spread;
    double sum = 0.0, weight_sum = 0.0;
    result.max_residual = 0.0;
    for (std::size_t k = 0; k < points.size(); ++k) {
      const double w = weights.empty() ? 1.0 : weights[k];
      sum += w * result.residuals[k] * result.residuals[k];
      weight_sum += w;
      if (w > 0.0) result.max_residual = std::max(result.max_residual, std::abs(result.residuals[k]));
    }
    result.rms = std::sqrt(sum / weight_sum);

    // Which spans' residuals the noise does not explain.
    const double sigma = std::max(result.noise_sigma, options.noise_floor);
    const std::vector<double> bu = fit.surface.U().breakpoints();
    const std::vector<double> bv = fit.surface.V().breakpoints();
    const std::size_t nsu = bu.size() - 1, nsv = bv.size() - 1;
    std::vector<double> chi2(nsu * nsv, 0.0), sum_r(nsu * nsv, 0.0), sum_free(nsu * nsv, 0.0);
    std::vector<int> count(nsu * nsv, 0);
    // Of each span's points, how many lie below its middle in u and in v.
    std::vector<int> below_u(nsu * nsv, 0), below_v(nsu * nsv, 0);
    // Each point's span in parallel; the sums in point order (the same whatever the thread count).
    std::vector<std::uint32_t> span(points.size());  // a face has far fewer than 2^32 spans
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096), [&](const auto& range) {
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        span[k] = static_cast<std::uint32_t>(span_at(bu, bv, t[k].u, t[k].v));
      }
    });
    const double clip2 = options.clip * options.clip;
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (!weights.empty() && !(weights[k] > 0.0)) continue;
      const std::size_t s = span[k];
      const double z = standardised[k] / sigma;
      chi2[s] += std::min(z * z, clip2);
      sum_r[s] += result.residuals[k];
      sum_free[s] += std::max(1.0 - leverage(k), 0.0);
      ++count[s];
      const std::size_t a = s / nsv, b = s % nsv;
      below_u[s] += t[k].u < 0.5 * (bu[a] + bu[a + 1]);
      below_v[s] += t[k].v < 0.5 * (bv[b] + bv[b + 1]);
    }
    // A span's χ² and count pooled with its (up to) eight neighbours'.
    struct Pooled {
      double chi2 = 0.0, sum_r = 0.0, sum_free = 0.0;
      int count = 0;
    };
    auto pooled = [&](std::size_t a, std::size_t b) {
      Pooled n;
      for_each_around(a, b, nsu, nsv, [&](std::size_t s2) {
        n.chi2 += chi2[s2];
        n.sum_r += sum_r[s2];
        n.sum_free += sum_free[s2];
        n.count += count[s2];
      });
      return n;
    };
    // The fit's local bias b_k = E[r_k], estimated over each span and its eight neighbours (pooled: tens of
    // points; fewer, closer ones where refinement made the spans small), so that u is a root-mean-square error,
    // not only a standard deviation: where the fit still misses shape the noise cannot hide, and on exact data.
    // Two estimates from the residuals, the larger taken:
    //  - the residuals' mean, squared, less its own variance σ²·Σ(1 − h_k)/n²: a misfit of one sign across the
    //    neighbourhood (a broad shape smoothed a little too much), seen through noise far larger than itself;
    //  - the residuals' mean square over the noise, σ²·(mean z² − 1), when the neighbourhood's χ² is significant
    //    (at the span test's 1 %): a misfit that changes sign inside the neighbourhood (a narrow feature), which
    //    the mean cancels. Unless significant it is left out: on noise alone it would add a random share of σ².
    result.misfit.assign(points.size(), 0.0);
    {
      std::vector<double> bias(nsu * nsv, 0.0);
      for (std::size_t a = 0; a < nsu; ++a) {
        for (std::size_t b = 0; b < nsv; ++b) {
          const Pooled n = pooled(a, b);
          if (n.count == 0) {
            bias[a * nsv + b] = options.noise_floor;
            continue;
          }
          const double mean = n.sum_r / n.count;
          double b2 = std::max(0.0, mean * mean - sigma * sigma * n.sum_free / (static_cast<double>(n.count) * n.count));
          if (n.chi2 > geometry::chi2_upper_quantile(n.count, kBiasSignificance)) {
            b2 = std::max(b2, sigma * sigma * (n.chi2 / n.count - 1.0));
          }
          // Never below the noise floor: the fit does not claim the surface to better than what a CMM resolves.
          bias[a * nsv + b] = std::max(std::sqrt(b2), options.noise_floor);
        }
      }
      // And the larger of that and the penalty's own bias at the point (PenalizedFitResult::smoothing_bias, along
      // the normal): a smooth, noise-free estimate where the residuals are too noisy to show a broad misfit (the
      // free-form case's bulge, σ = 1.5 µm: the residuals' estimate reads 0.32 µm where the error over noise
      // seeds has a bias of 0.45 µm; worst 4 × 4 region's ±2u coverage 77 % without it, 91 % with it), while
      // the residuals see what the penalty's estimate cannot: a narrow feature the knots do not follow. And a
      // point's own residual where it is far beyond the noise: on exact data a feature between a few points
      // (3 000 random points without noise: worst region's coverage 86.5 % without it, 98.9 % with it).
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024), [&](const auto& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          const double r2 = result.residuals[k] * result.residuals[k];
          // (Not for a point left out: its residual is its own gross error, which the fit ignored.)
          const bool in_fit = weights.empty() || weights[k] > 0.0;
          const double own = in_fit && std::abs(standardised[k]) > kOwnResidualSigmas * sigma
                                 ? std::sqrt(std::max(0.0, r2 - sigma * sigma * std::max(1.0 - leverage(k), 0.0)))
                                 : 0.0;
          result.misfit[k] = std::max({bias[span[k]], along.bias[k], own});
        }
      });
    }
    // split: a flagged span with points enough to be split (flag_u and flag_v: the knot lines that split it).
    std::vector<char> flag_u(nsu, 0), flag_v(nsv, 0), span_flag(nsu * nsv, 0), split(nsu * nsv, 0);
    // Marks span (a, b)'s knot lines for splitting: both, or (either_side_only) each only where points lie on both
    // sides of it (AdaptiveFitOptions::split_only_where_points_either_side). Whether any was marked.
    auto mark_lines = [&](std::size_t a, std::size_t b, bool either_side_only) {
      const std::size_t s = a * nsv + b;
      const bool u = !either_side_only || std::min(below_u[s], count[s] - below_u[s]) > 0;
      const bool v = !either_side_only || std::min(below_v[s], count[s] - below_v[s]) > 0;
      if (u) flag_u[a] = 1;
      if (v) flag_v[b] = 1;
      return u || v;
    };
    result.spans_above_noise = 0;
    const double alpha = options.false_alarm / static_cast<double>(nsu * nsv);
    for (std::size_t a = 0; a < nsu; ++a) {
      for (std::size_t b = 0; b < nsv; ++b) {
        const std::size_t s = a * nsv + b;
        // Standardised residuals have unit variance each; the count is the χ²'s degrees of freedom. (Clipping
        // lowers the sum on noise alone, so the test stays on the safe side.) A span is tested alone and with
        // its eight neighbours pooled: a feature about as wide as the point spacing leaves a misfit of two or
        // three σ on the few points of each span it crosses, which no span's own test can tell from noise but
        // the neighbourhood's forty points do. The pooled test flags the spans of the neighbourhood whose own
        // residuals carry the excess (mean square above σ²).
        if (count[s] == 0) continue;
        bool unexplained = chi2[s] > geometry::chi2_upper_quantile(count[s], alpha);
        if (!unexplained && chi2[s] > count[s]) {
          const Pooled n = pooled(a, b);
          unexplained = n.chi2 > geometry::chi2_upper_quantile(n.count, alpha);
        }
        if (!unexplained) continue;
        ++result.spans_above_noise;
        span_flag[s] = 1;
        if (count[s] >= options.min_points_to_split) {
          split[s] = 1;
          // (See AdaptiveFitOptions::split_only_where_points_either_side; not on exact data, which the penalty's
          // floor holds between the lines, and whose creases between lines need the split: shape suite S29, its
          // worst region's ±2u coverage 94.6 % with it, 66.4 % without.)
          const bool any = !options.split_only_where_points_either_side || result.noise_sigma <= options.noise_floor;
          (void)mark_lines(a, b, !any);
        }
      }
    }
    auto complete = [&](AdaptiveFitResult& r, AdaptiveFitResult::Status status) {
      r.status = status;
      r.span_spread = detail::span_spread(standardised, weights, span, nsu, nsv, r.noise_sigma);
    };
    auto finish = [&](AdaptiveFitResult::Status status) {
      complete(result, status);
      result.thin_misfit_seen = thin_misfit_seen;
      return std::move(result);
    };
    // Every span is consistent with the noise estimate; but a misfit spread thin over the face (a wave over all
    // of it, a broad bulge) inflates the spread it is measured against, and the local prediction errors read a few
    // per cent high on a flexible fit's residuals (neighbouring residuals are correlated), so no test on σ tells
    // it from the noise. What tells is whether more control points predict left-out points better: the spans
    // whose residuals and neighbourhood exceed σ on average are refined on trial, and that round (and every
    // later one) is kept only if its cross-validation score is lower. Tried only where the residuals show such a
    // misfit: their spread exceeds those prediction errors despite their reading high, or neighbouring residuals
    // are correlated beyond chance (a fit's residuals repel on noise alone: −0.02 to −0.08 on the shape suite's
    // final fits; D308, a 15 µm wave in a window, +0.015 over 7 000 points), so that a face showing none pays
    // nothing for it (a trial undone on the benchmark's 10 000 points took 0.17 -> 0.57 s). Not on scan lines:
    // leave-span-out scores of different knot spans are not comparable.
    bool trial = false;
    if (result.spans_above_noise == 0 && round < options.max_rounds && result.noise_sigma > options.noise_floor &&
        options.fit.cross_validation == CrossValidation::LeaveOneOut &&
        ((std::isfinite(local) && spread > local) ||
         detail::correlated_beyond_the_fit(local_noise, result.residuals, fit))) {
      thin_misfit_seen = true;
      for (std::size_t a = 0; a < nsu; ++a) {
        for (std::size_t b = 0; b < nsv; ++b) {
          const std::size_t s = a * nsv + b;
          if (count[s] < options.min_points_to_split || !(chi2[s] > count[s])) continue;
          const Pooled n = pooled(a, b);
          if (!(n.chi2 > n.count)) continue;
          span_flag[s] = split[s] = 1;
          (void)mark_lines(a, b, false);
          trial = true;
        }
      }
    }
    if (result.spans_above_noise == 0 && round < options.max_rounds && result.noise_sigma > options.noise_floor &&
        by_f_test) {
      for (std::size_t a = 0; a < nsu; ++a) {
        for (std::size_t b = 0; b < nsv; ++b) {
          const std::size_t s = a * nsv + b;
          // (Split only where points lie either side of the knot line, as the span tests' refinement does here.)
          if (count[s] < options.min_points_to_split || !mark_lines(a, b, true)) continue;
          span_flag[s] = split[s] = 1;
          trial = true;
        }
      }
    }
    const auto status_now = result.spans_above_noise == 0 ? AdaptiveFitResult::Status::OK
                                                           : AdaptiveFitResult::Status::NoiseNotReached;
    if (polishing) return finish(status_now);
    if (result.spans_above_noise == 0 && !trial) {
      // The net is final and explains the data: its smoothing is moved as two directional weights from the λ and
      // θ chosen, one fit more (PenalizedFitOptions::directional_smoothing). θ is sought at one λ, then λ at that
      // θ, which stops short where a feature lies along a parameter direction (shape suite D910, a wave in a band
      // on a cylinder, random points: 0.973 -> 0.643 µm; D1114, a crease at 83°: 1.018 -> 0.784; D1002, a wave in
      // a band on a panel: 0.910 -> 0.722). Not on a net that did not reach the noise: its smoothing is then traded
      // against its misfit, and moving it changes which readings are outliers (S11, a crease the net does not
      // follow: 0.672 -> 0.926 µm); nor while a refinement is on trial, whose score is compared with the kept
      // round's; nor where θ or λ were given.
      if (!trying && may_polish(result)) {
        AdaptiveFitResult last = result;
        complete(last, AdaptiveFitResult::Status::OK);
        start_polishing(std::move(last));
        continue;
      }
      return finish(AdaptiveFitResult::Status::OK);
    }
    if (round == options.max_rounds) return finish(AdaptiveFitResult::Status::NoiseNotReached);
    if (trying || trial) {
      kept = result;
      complete(*kept, status_now);
      if (kept->status == AdaptiveFitResult::Status::OK && may_polish(*kept)) {
        kept_net = KeptNet{target, basis, span_weight, fit_options};
      } else {
        kept_net.reset();
      }
      kept->refinement_rejected = status_now != AdaptiveFitResult::Status::OK;
      kept_cv = fit.cv_score;
      kept_rss = fit.rss;
      kept_edf = fit.effective_dof;
      kept_saturated = detail::saturated(fit.effective_dof, unknowns);
      trying = true;
    }
    // The penalty's weight over the face follows the fit's own roughness (detail::roughness_span_weights, a pilot
    // estimate as in spatially adaptive smoothing splines), lowered where the fit is rougher than on average and
    // only going down from round to round; or, with AdaptiveFitOptions::SpatialPenalty::Balance, the local balance of
    // data and penalty that restricted maximum likelihood asks of each of several penalties
    // (detail::balanced_span_weights), set afresh each round, so that the penalty goes down where the fitted shape
    // holds much energy for the freedom the data give it and cross-validation still sets the overall λ. Not on scan
    // lines nor exact data, whose spans between lines or points only the penalty holds: the balance, read from
    // leverages, has nothing to read there and lowered it until the fit rang (D706, lines 4 mm apart at σ = 4.5 µm:
    // std 1.41 -> 6.0 µm; S29 without noise: 2.35 -> 51 µm). Nor in a span with fewer points than it takes to split
    // it: read from the leverages of two or three points it lowered the penalty at a dent a coarse grid barely
    // resolves until the fit swung through the hole a flagged point left (the paper's case on a 60 × 30 grid,
    // σ = 4.5 µm, 1 % of the points moved 0.1–5 mm: the others moved 37.5 µm from where they are without those
    // points, against 0.05 µm). Then the unexplained spans' penalty goes down a decade (to a floor: the energy
    // still holds what no point fixes).
    bool lowered = false;
    const double floor =
        result.noise_sigma <= options.noise_floor ? options.min_span_weight_noise_free : options.min_span_weight;
    const bool balance = options.spatial_penalty == AdaptiveFitOptions::SpatialPenalty::Balance &&
                         result.noise_sigma > options.noise_floor &&
                         options.fit.cross_validation == CrossValidation::LeaveOneOut;
    if (balance) {
      std::vector<double> leverage_sum(nsu * nsv, 0.0);
      for (std::size_t k = 0; k < points.size(); ++k) {
        if (weights.empty() || weights[k] > 0.0) leverage_sum[span[k]] += leverage(k);
      }
      const std::vector<double> w = detail::balanced_span_weights(
          fit.span_energy, leverage_sum, count, span_weight, options.min_points_to_split, nsu, nsv, floor);
      for (std::size_t s = 0; s < nsu * nsv; ++s) {
        if (w[s] < 0.5 * span_weight[s] || w[s] > 2.0 * span_weight[s]) lowered = true;
        span_weight[s] = w[s];
      }
    } else {
      // (A span lowered further in a round whose noise estimate was above the floor comes back up to it.)
      for (double& w : span_weight) {
        if (w < floor) {
          w = floor;
          lowered = true;
        }
      }
      const std::vector<double> w = detail::roughness_span_weights(fit.span_energy, bu, bv, floor);
      for (std::size_t s = 0; s < nsu * nsv; ++s) {
        if (w[s] < 0.5 * span_weight[s]) {
          span_weight[s] = w[s];
          lowered = true;
        }
      }
    }
    for (std::size_t s = 0; s < nsu * nsv; ++s) {
      if (!span_flag[s] || span_weight[s] <= floor) continue;
      span_weight[s] = std::max(span_weight[s] * 0.1, floor);
      lowered = true;
    }
    const double per_control_point = result.noise_sigma <= options.noise_floor
                                         ? options.min_points_per_control_point_noise_free
                                         : options.min_points_per_control_point;
    std::vector<double> xu, xv;
    bool refined = false;
    if (!refine_locally) {
      xu = flagged_span_midpoints(bu, flag_u);
      xv = flagged_span_midpoints(bv, flag_v);
      const double after = static_cast<double>(target.num_u() + static_cast<int>(xu.size())) *
                           static_cast<double>(target.num_v() + static_cast<int>(xv.size()));
      if (after * per_control_point > static_cast<double>(used)) {
        xu.clear();
        xv.clear();
      }
      if (!xu.empty()) target = nurbs::refine_knots_u(target, xu);
      if (!xv.empty()) target = nurbs::refine_knots_v(target, xv);
      refined = !xu.empty() || !xv.empty();
    } else {
      // As above, knot lines through every flagged span; but where the points would not support the control points
      // they add, the flagged spans' cells are refined by a level of a THB basis instead, which adds control points
      // near them only (a cell at the deepest level allowed is split by lines alone). Not on a round tried for a
      // thin misfit (see above): undone as a whole when its score is no lower, it would take the penalty's
      // lowering with it.
      const std::vector<double> tbu = target.U().breakpoints(), tbv = target.V().breakpoints();
      const std::size_t tsu = tbu.size() - 1, tsv = tbv.size() - 1;
      // A flagged span is marked for one level finer than the finest whose domain holds it, up to the deepest level
      // allowed (AdaptiveFitOptions::local_refinement_levels).
      struct Candidate {
        std::vector<char> lu, lv;
        const detail::LevelFlags* from;
      };
      struct Built {
        std::vector<double> cu, cv;
        Surface next;
        detail::LevelFlags marks;
        std::optional<HierarchicalBasis> basis;
        int count = 0;
      };
      // The refined domains as marked now: the same for every subset of the flagged spans tried below.
      const detail::LevelFlags domains_now = detail::nested_domains(marks, tbu, tbv, options.local_refinement_ring);
      auto build = [&](const std::vector<char>& to_split) {
        detail::LevelFlags grown = marks;
        std::vector<char> line_u(tsu, 0), line_v(tsv, 0);
        for (std::size_t s = 0; s < nsu * nsv; ++s) {
          if (!to_split[s]) continue;
          const std::size_t a = s / nsv, b = s % nsv;
          const double u = 0.5 * (bu[a] + bu[a + 1]), v = 0.5 * (bv[b] + bv[b + 1]);
          line_u[static_cast<std::size_t>(span_of(tbu, u))] = line_v[static_cast<std::size_t>(span_of(tbv, v))] = 1;
          const int depth = detail::depth_at(domains_now, tbu, tbv, u, v);
          if (!trial) detail::mark_at(grown, std::min(depth, options.local_refinement_levels - 1), tbu, tbv, u, v);
        }
        // Two candidates, each of knot lines and marks: lines through every flagged span with the marks as they
        // were, and the new marks alone. The first the points support is taken, except that the second replaces
        // the first where it adds fewer control points and its refined region covers at least
        // local_refinement_min_cover of the face (see AdaptiveFitOptions).
        const Candidate candidates[] = {{line_u, line_v, &marks},
                                        {std::vector<char>(tsu, 0), std::vector<char>(tsv, 0), &grown}};
        std::optional<Built> chosen;
        for (const Candidate& c : candidates) {
          if (chosen && options.local_refinement_min_cover > 1.0) break;  // the second could not replace the first
          const std::vector<double> cu = flagged_span_midpoints(tbu, c.lu);
          const std::vector<double> cv = flagged_span_midpoints(tbv, c.lv);
          if (cu.empty() && cv.empty() && *c.from == marks) continue;
          Surface next = cu.empty() ? target : nurbs::refine_knots_u(target, cu);
          if (!cv.empty()) next = nurbs::refine_knots_v(next, cv);
          // The marks on next's cells: a cell cut by a line leaves its mark on both halves.
          detail::LevelFlags next_marks =
              detail::carried(*c.from, tbu, tbv, next.U().breakpoints(), next.V().breakpoints());
          const detail::LevelFlags domains =
              detail::nested_domains(next_marks, next.U().breakpoints(), next.V().breakpoints(), options.local_refinement_ring);
          std::optional<HierarchicalBasis> candidate;
          if (!domains.empty()) candidate = hierarchical_basis(next, domains);
          const int count_after = candidate ? candidate->unknowns : next.num_u() * next.num_v();
          if (static_cast<double>(count_after) * per_control_point > static_cast<double>(used)) continue;
          const double cover = domains.empty() ? 0.0
                                               : static_cast<double>(std::count(domains[0].begin(), domains[0].end(), 1)) /
                                                     static_cast<double>(domains[0].size());
          if (!chosen || (count_after < chosen->count && cover >= options.local_refinement_min_cover)) {
            chosen = Built{cu, cv, std::move(next), std::move(next_marks), std::move(candidate), count_after};
          }
        }
        return chosen;
      };
      std::optional<Built> chosen = build(split);
      // Where the points support neither for every flagged span, the half of them whose residuals exceed the noise
      // most, and half of that, until one is supported: all or nothing, a face with a sharp crease among a broad
      // misfit stopped refining with hundreds of spans flagged (shape suite S11, a 0.3 mm crease over 1 mm at
      // σ = 1.5 µm, with θ chosen each round: stuck at 1 692 control points for 37 rounds, contacts 7.9 µm std;
      // refined where the residuals are largest, 3 354 control points and 0.75 µm).
      if (!chosen) {
        std::vector<std::pair<double, std::size_t>> excess;  // (χ² over its count, span), largest first
        for (std::size_t s = 0; s < nsu * nsv; ++s) {
          if (split[s]) excess.emplace_back(chi2[s] - count[s], s);
        }
        std::stable_sort(excess.begin(), excess.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
        while (!chosen && excess.size() > 1) {
          excess.resize(excess.size() / 2);
          std::vector<char> part(nsu * nsv, 0);
          for (const auto& e : excess) part[e.second] = 1;
          chosen = build(part);
        }
      }
      if (chosen) {
        xu = chosen->cu;
        xv = chosen->cv;
        target = std::move(chosen->next);
        marks = std::move(chosen->marks);
        basis.reset();
        if (chosen->basis && chosen->basis->refined_unknowns > 0) basis = std::move(chosen->basis);
        refined = true;
      }
      result.refined_cells = 0;
      for (const auto& m : marks) result.refined_cells += static_cast<int>(std::count(m.begin(), m.end(), 1));
    }
    if (!refined && !lowered) return finish(status_now);
    // Each new span of the surface fitted next inherits the weight of the span it was cut from.
    if (refined) {
      const Surface& next = basis ? basis->surface : target;
      const std::vector<double> nbu = next.U().breakpoints();
      const std::vector<double> nbv = next.V().breakpoints();
      std::vector<double> w((nbu.size() - 1) * (nbv.size() - 1));
      for (std::size_t a = 0; a + 1 < nbu.size(); ++a) {
        const std::size_t oa = static_cast<std::size_t>(span_of(bu, 0.5 * (nbu[a] + nbu[a + 1])));
        for (std::size_t b = 0; b + 1 < nbv.size(); ++b) {
          const std::size_t ob = static_cast<std::size_t>(span_of(bv, 0.5 * (nbv[b] + nbv[b + 1])));
          w[a * (nbv.size() - 1) + b] = span_weight[oa * nsv + ob];
        }
      }
      span_weight = std::move(w);
    }
    // Later rounds change the fit locally: the smoothing is sought from kSmoothingWindow below the last one. The
    // anisotropy, the face's deformation's (a wave's or a crease's direction), is chosen again on each net, afresh
    // (see fit_penalized): a coarse first net cannot show it, and its score may not depend on it at all (shape
    // suite D400, 20 control points: the same to five digits from θ = 10^-2 to 10^2; the θ taken there, 10^-1.91,
    // kept for seven rounds, std 1.61 µm; chosen on each net, 0.95 µm; over the suite's 94 faces the std median
    // 1.053 -> 0.996 µm).
    // On exact data the first net's θ is kept: between the points only the penalty holds the fit, and the finest
    // nets' scores drift to θ that let it ripple there (S17, a crease on a cylinder, 5 200 control points for
    // 7 020 points: the last net took 10^-1.91 and its contacts were 4.5 µm off, 0.8 µm at the first net's θ).
    // Nor on a round tried for a thin misfit (and those after it), whose score is compared with the kept round's:
    // θ chosen again would lower it for no added control point.
    if (!options.fit.log10_anisotropy && (!(result.noise_sigma > options.noise_floor) || trying)) {
      fit_options.log10_anisotropy = fit.log10_anisotropy;
    }
    // (See smoothest_within_one_standard_error above: kept while the residuals show noise.)
    fit_options.smoothest_within_one_standard_error =
        fit_options.smoothest_within_one_standard_error && result.noise_sigma > options.noise_floor;
    if (!options.fit.log10_smoothing) {
      const double last = fit.log10_smoothing;
      fit_options.min_log10_smoothing = std::max(options.fit.min_log10_smoothing, last - kSmoothingWindow);
      fit_options.max_log10_smoothing = result.noise_sigma > options.noise_floor
                                            ? options.fit.max_log10_smoothing
                                            : std::min(options.fit.max_log10_smoothing, last + kSmoothingWindow);
    }
    result.knots_inserted += static_cast<int>(xu.size() + xv.size());
    result.rounds = round + 1;
  }
}

}  // namespace

}  // namespace probecomp::fitting
