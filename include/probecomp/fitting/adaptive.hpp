#pragma once
// Penalised surface fit refined where the data demand it (DESIGN.md §2 steps 4–5): fit the control points with
// the smoothing chosen by cross-validation (fitting/penalized.hpp), optionally correct the points' parameters by projecting
// them on the fit, estimate the measurement noise robustly from the residuals, and insert knots in the spans
// whose residuals the noise does not explain; repeat until every span is consistent with the noise, the data
// can support no more control points, or the rounds run out. Where every span is consistent but the residuals
// still show a misfit thin over the face (their spread above the local noise estimate, or neighbouring residuals
// correlated), refinement is tried, and each round tried is kept only if it predicts left-out points better; and
// the whole fit is made again from the start's knot spans halved, the one that predicts them better taken
// (AdaptiveFitOptions::dense_start_points_per_control_point).

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "probecomp/fitting/least_squares.hpp"
#include "probecomp/fitting/penalized.hpp"

namespace probecomp::fitting {

class LocalPredictionNoise;  // fitting/noise_estimate.hpp

struct AdaptiveFitOptions {
  PenalizedFitOptions fit;
  int max_rounds = 8;             // knot insertions at most
  int parameter_corrections = 2;  // projections of the points on the fit, each followed by a refit, per round
  // Residuals below this count as noise whatever the estimate (noise-free or almost noise-free data), mm. A
  // tenth of a micrometre: below what a CMM resolves.
  double noise_floor = 1e-4;
  // A span is refined when the sum of its squared residuals, over σ², exceeds the χ² quantile that noise alone
  // exceeds in any span of the surface with this probability (split evenly over the spans, so that hundreds of
  // small spans do not raise false alarms by their number).
  double false_alarm = 0.01;
  // Each point's share of its span's χ² is capped at clip² (a Huber-like bound): a lone gross error can then
  // not make a span look unexplained by itself, so refinement follows shape that several points show, never
  // one point.
  double clip = 4.0;
  // An unexplained span's penalty weight is divided by 10 each round, down to this: a million times weaker than
  // the rest of the face still holds a span that no point fixes.
  double min_span_weight = 1e-6;
  // ... and this floor where the noise estimate is at noise_floor (exact data), where every span the fit misses by
  // more than a tenth of a micrometre is unexplained (compensation::fit_faces raises it on a scanning probe's lines).
  double min_span_weight_noise_free = 1e-6;
  // How the penalty's weight varies over the face between rounds (see fit_surface): from the fit's roughness alone,
  // or from the local balance of data and penalty (restricted maximum likelihood's, for a penalty per neighbourhood
  // of spans; on scan lines and exact data the roughness rule is used whatever this says). The balance is more
  // accurate on the shape suite's grids and random points (63 faces at σ = 1.5–10 µm: std median 1.216 -> 1.057 µm,
  // 42 better by 2 % or more and 5 worse; docs/accuracy.md). Given gross errors it lets the fit follow them:
  // compensation::fit_faces, whose default it is, judges a face that may hold them on a fit with the roughness rule
  // first and uses the balance for the refits made without them. Not the default here, where no verdict on gross
  // errors follows.
  enum class SpatialPenalty { Roughness, Balance };
  SpatialPenalty spatial_penalty = SpatialPenalty::Roughness;
  // A span with fewer points is not split (its quarters would hold one or none). Four: a narrow dent in a grid of
  // points about a third of its width apart needs spans that hold only a few (measured on the free-form case: a
  // dent of σ = 1.5 mm, 0.84 mm grid: largest error 21 µm with 8, 7.9 µm with 4).
  int min_points_to_split = 4;
  // A flagged span is split in a direction only where its points lie on both sides of its middle (unless the noise
  // estimate is at noise_floor). compensation::fit_faces sets it on a scanning probe's lines: a span across which
  // the points hold one line, cut between lines, gives spans no point holds, and the fit rang there (cylinder
  // sections scanned along lines 4 mm apart across creases, σ = 4.5 µm: contacts std 18.1, 6.9 and 39.3 µm with
  // normals up to 23° off, against 1.6, 1.4 and 6.7 µm with it). Not on grids and random points, where no line
  // leaves spans empty and where it cost: a dent on a coarse grid at σ = 0.5 µm had 35 good points flagged with it.
  bool split_only_where_points_either_side = false;
  // Two: the penalty (chosen by cross-validation) holds the variance of a fit with more control points than the
  // noise can average on its own (3 000 random points, σ = 1.5 µm: largest error 46 µm with 68 points flagged
  // at 4, 3.2 µm and none flagged at 2).
  double min_points_per_control_point = 2.0;  // refinement stops before the fit has fewer
  // ... unless the noise estimate is at the floor (noise-free data): then there is no noise to average and the
  // fit may go as far as this, to follow a narrow feature (the free-form case without noise on its grid: largest
  // error 1.9 µm when stopped at 4, 0.18 µm at 2 and at 1.25). Knot lines run across the whole face, so a dent
  // among scattered points needs more control points than its own area would: 3 000 random points without
  // noise, largest error over 5 seeds 0.33–1.35 µm and none flagged at 1.25, against 8.9 µm and 2 rows of the
  // dent flagged at 2 in one seed; the steep dent's 0.54 µm against 1.6 µm.
  double min_points_per_control_point_noise_free = 1.25;
  // Where the knot lines through the flagged spans would give the fit more control points than the points support
  // (the rule above), refine the flagged spans' cells by a level of a THB basis (fitting/hierarchical.hpp)
  // instead: control points near them only, none along the rest of their lines. Grids and random points only (not
  // on a scanning probe's lines, where a cell between lines would hold no points). Measured (probecomp_shape_suite
  // --no-reference): of the suite's 30 cases and 120 unseen draws it changes 3, those whose refinement the points'
  // support or the rounds stopped: S11 7.24 -> 2.75 µm (one level; 2.03 with three, below), S26 1.469 -> 1.112 µm,
  // D906 3.61 -> 1.80 µm; the rest print the same to the last digit.
  bool local_refinement = true;
  // Cells all round a flagged one refined with it: a level-1 bicubic needs 2 × 2 cells inside the refined region,
  // so a lone cell gains almost nothing. On those three cases, one cell all round: 3.02, 1.132 and 2.05 µm; two:
  // 2.75, 1.112 and 1.80 µm; three: 2.14, 1.164 and 3.61 µm (D906's cells then need more control points than its
  // points support, and it falls back to lines).
  int local_refinement_ring = 2;
  // The finest THB level a cell may reach: a flagged span inside level l's refined region is refined to level
  // l + 1, up to this (1: one level, as before). Of the suite's cases only S11 refines past level 1: 2.747 -> 2.027 µm
  // (more rows flagged, 20 -> 37; the fitted centres' rms 3.44 -> 3.86 µm); over 8 draws of its noise, median
  // 2.080 -> 2.100 µm and worst 2.747 -> 2.468.
  int local_refinement_levels = 3;
  // Local refinement is also taken instead of knot lines where it adds fewer control points and its level-1 region
  // covers at least this share of the face's cells; above 1 (the default), never: local refinement only where
  // lines exceed the points' support. (Where the flagged spans, grown by the ring, cover most of the face, a level
  // over them adds fewer control points than lines through them, which cut long thin spans across it; where they
  // cover little, they are often a wave over the whole face seen in a few places, which lines refine where the rest
  // of it is.) Measured at 0.5 with 3 levels (probecomp_shape_suite --no-reference): S11 2.747 -> 1.026 µm, S02,
  // S17, S23 better, S15 1.080 -> 1.153; on 48 unseen draws 4 better and 3 worse (D211 1.427 -> 1.675 µm), and
  // where it acts the worst region's ±2u coverage falls by up to 12 points (D307, D401, D412): u is less honest on
  // those fits, so it is not the default. At 0, S27 and S28's worst regions fall to 63 and 67 %.
  double local_refinement_min_cover = 2.0;
  // Where the residuals showed a misfit spread thin over the face (AdaptiveFitResult::thin_misfit_seen), the fit is
  // made again from `start` with its knot spans halved until it has a control point for at most this many points
  // (or 4 096 control points), and of the two the one whose cross-validation score is lower is taken (0: never).
  // Refinement follows what the span tests see; a misfit of a fraction of σ over much of the face (a broad bulge, a
  // wave over all of it) they do not see, nor does u, which then promises what the fit does not hold (a cylinder
  // with a broad bulge, 6 000 random points at σ = 4.5 µm, one draw of its noise: 80 control points at the end,
  // worst region's ±2u coverage 34 %). From a finer start the penalty holds the variance; but a narrow feature among smooth regions is followed
  // better from the coarse start, whose lines go through it alone, so neither start is right on its own. Measured
  // (probecomp_shape_suite --no-reference, the suite and 64 unseen draws, 94 faces): 30 faces showed such a misfit;
  // std better by 2 % or more on 17 and worse on 1; the lowest ±2u coverage overall 85.1 -> 92.6 %; faces whose
  // worst region is under 88 %, 42 -> 33, the lowest of them 50.3 -> 70.5 %. Tried on every face (not only those),
  // 28 better and 3 worse, but BM_Compensate10k 183 -> 875 ms. Sixteen: fewer (24, 32) changed less.
  double dense_start_points_per_control_point = 16.0;
  // The fit's bias from what its net cannot represent, seen by a fit of the same points on a net about twice as fine
  // with the same penalty, joins `misfit` (fitting/representation_bias.hpp). Neither the χ² tests nor
  // cross-validation ask for a finer net where a few points are missed by a few σ̂ (on the paper's grid at
  // σ = 2.5 µm: a dent's rim 4.0 µm off at u = 1.0 µm, 5.9 u; now 4.5 u). On 94 faces (the shape suite and sets
  // 200–500): faces with a region whose ±2u coverage is under 88 %, 33 -> 27; the lowest overall 92.6 -> 96.0 %;
  // the std unchanged (u only). Costs a fit on the finer net at a fixed λ: BM_Compensate10k 182 -> 218 ms.
  bool representation_bias = true;
  // On noisy data, once the net is final (every span within the noise), its smoothing moved as two directional
  // weights from the λ and θ chosen (PenalizedFitOptions::directional_smoothing): one more fit of the last net.
  bool directional_smoothing = true;
};

// Fewer points than this around a point (its span and the eight around it) give no median worth the name: their
// spread is taken as the face's noise estimate.
inline constexpr int kMinLocalPoints = 9;

struct AdaptiveFitResult {
  enum class Status {
    OK,               // every span's residuals are consistent with the noise estimate
    NoiseNotReached,  // stopped (data support or rounds) with `spans_above_noise` spans still unexplained
    NotDone,          // bad input (see fit_penalized)
    NumericalError,
  };
  Status status = Status::NotDone;
  nurbs::Surface surface;
  std::vector<SurfaceParameter> params{};  // each point's foot point on the fit
  std::vector<double> residuals{};       // signed distance of each point from the fit along its normal, mm
  int control_points = 0;
  int rounds = 0;            // knot insertions made
  int knots_inserted = 0;    // in u and v together
  int refined_cells = 0;     // cells refined locally (AdaptiveFitOptions::local_refinement)
  double rms = 0.0;          // of the residuals (weighted), mm
  double max_residual = 0.0; // largest |residual| over points with weight > 0, mm
  double noise_sigma = 0.0;  // the measurement noise, mm (fitting/noise_estimate.hpp)
  int spans_above_noise = 0;
  // NoiseNotReached because a further round of refinement predicted left-out points no better (a lower
  // cross-validation score) and was undone.
  bool refinement_rejected = false;
  // The last fit's cross-validation score (PenalizedFitResult::cv_score).
  double cv_score = std::numeric_limits<double>::infinity();
  // In some round every span was consistent with the noise, yet the residuals showed a misfit spread thin over the
  // face (their spread above the local noise estimate, or neighbouring residuals correlated beyond the fit's own).
  bool thin_misfit_seen = false;
  // The fit began from the start's spans halved (AdaptiveFitOptions::dense_start_points_per_control_point).
  bool dense_start = false;
  double effective_dof = 0.0;    // tr H of the last fit (per coordinate)
  double log10_smoothing = 0.0;  // its smoothing, relative (PenalizedFitResult)
  double lambda = 0.0;           // and absolute (PenalizedFitResult::lambda)
  // Per point: the fitted point's variance over σ² (PenalizedFitResult::variance_factor); w_k times it is the
  // point's leverage h_k.
  std::vector<double> variance_factor{};
  // Per point: the estimated bias of the fit at the point, mm, never below noise_floor (see fit_surface: the
  // largest of the residuals' mean over the point's neighbourhood of spans less its variance, their significant
  // mean-square excess there, and the penalty's own bias at the point, PenalizedFitResult::smoothing_bias).
  std::vector<double> misfit{};
  // Per knot span of `surface` (u-major, as its breakpoints): the spread of the fit's standardised residuals around
  // it, mm: 1.4826 × their median |r| over the points of the span and the eight around it (weights > 0), never
  // below noise_sigma; noise_sigma where those hold fewer than kMinLocalPoints. The noise where the fit follows the
  // shape; the misfit where it cannot (a feature the data support no more control points for): what a point must
  // stand out from to be a gross error. A median: a lone gross error among its neighbours does not move it.
  // Per span, not per point: a million points would need 8 MB for what a few thousand spans hold.
  std::vector<double> span_spread{};
  // The last fit's penalty: its weight per knot span of `surface` (u-major; empty where the fit was on a THB basis)
  // and its anisotropy (PenalizedFitResult::log10_anisotropy).
  std::vector<double> span_weight{};
  double log10_anisotropy = 0.0;

  [[nodiscard]] bool ok() const { return status == Status::OK; }
  // A surface was fitted (OK or NoiseNotReached): `surface`, `params` and `residuals` describe it.
  [[nodiscard]] bool fitted() const { return status == Status::OK || status == Status::NoiseNotReached; }
};

// `start` gives degrees, knots and weights, the first iterate and the regularisation's target (the nominal or
// offset surface); `params` the points' starting parameters on it (e.g. from registration). `local_noise`: the
// points' LocalPredictionNoise for these weights (LocalPredictionNoise(points, weights)) where the caller has it
// (the gross-error gate builds it); else it is built here.
[[nodiscard]] AdaptiveFitResult fit_surface(const nurbs::Surface& start, std::span<const Point3> points,
                                            std::span<const SurfaceParameter> params,
                                            std::span<const double> weights = {},
                                            const AdaptiveFitOptions& options = {},
                                            const LocalPredictionNoise* local_noise = nullptr);

// Each point's foot point on `s`, by Newton from its parameters (the point's parameter is kept where Newton
// does not converge). Parallel, deterministic.
[[nodiscard]] std::vector<SurfaceParameter> correct_parameters(const nurbs::Surface& s, std::span<const Point3> points,
                                                               std::span<const SurfaceParameter> params);

// The noise standard deviation from residuals: 1.4826 × their median absolute deviation (consistent for
// Gaussian noise, unmoved by a minority of unexplained residuals), divided by √(1 − unknowns / points) for the
// part of the noise the fit absorbs. Points with zero weight are left out.
[[nodiscard]] double robust_noise_sigma(std::span<const double> residuals, std::span<const double> weights,
                                        int unknowns_per_coordinate);

// The spread of the residuals around point k of `fit` (AdaptiveFitResult::span_spread at the point's span), mm;
// noise_sigma when the fit has none. The fit's breakpoints are found once, for all the points asked about (at 1 %
// gross errors among a million points, ten thousand of them).
class LocalSpread {
 public:
  explicit LocalSpread(const AdaptiveFitResult& fit);
  [[nodiscard]] double operator()(std::size_t k) const;

 private:
  const AdaptiveFitResult& fit_;
  std::vector<double> bu_, bv_;
};

}  // namespace probecomp::fitting
