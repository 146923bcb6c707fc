#pragma once
// Penalised least-squares fit of a NURBS surface's control points, the smoothing chosen from the data
// (DESIGN.md §2 step 4, and issue 19). Degrees, knots and weights are those of `start`; the unknown is the
// displacement D = P − P⁰ of the control net from the start surface's, so that the fit is
//   S(u,v) = S⁰(u,v) + Σ R_I(u,v) D_I          (R: the rational basis of the start surface)
// and D minimises
//   Σ_k w_k |S(u_k,v_k) − x_k|²  +  λ · E(D)  +  ε |D|²
// where E is the thin-plate energy of the displacement field on the parameter domain, scaled to millimetres
// (∫∫ θ d_ss² + 2 d_st² + d_tt²/θ ds dt with s = L_u·u, t = L_v·v, L the mean speed |S_u|, |S_v| of the start;
// θ = 1 is the isotropic energy, and θ chosen by cross-validation lets a deformation that varies fast along one
// direction and slowly along the other, a wave or a crease across the face, be followed without the freedom to
// wiggle along both: the reference P-spline's two smoothing weights, issue 48),
// over the whole domain: boundary spans included, each span's share weighted by `span_weights` (a spatially
// varying penalty: small where the part departs sharply from nominal, large where it does not). E does not
// penalise a displacement that is linear on the domain, so a broad tilt or bulge costs little; ε (a whisker)
// only makes the system definite where no point and no curvature fixes a control point.
//
// λ minimises a cross-validation score (leave-one-out by default; leave-span-out on request, see CrossValidation),
// the leave-one-out one being (Allen's PRESS; Wahba, "Spline Models for Observational
// Data", 1990, ch. 4) CV(λ) = Σ w_k |r_k|² / (1 − h_k)², h_k the diagonal of the hat matrix H mapping the data to
// the fitted values: the λ whose fit predicts left-out points best, needing no noise estimate. (Not the
// generalised form, which replaces each h_k by their mean: on scattered points and a fine basis it cannot see a
// point that alone holds a control point, and picks a fit that swings between points of exact data.) tr H (the
// fit's effective degrees of freedom) and each point's hat diagonal come from the entries of (AᵀWA + λG)⁻¹
// inside its band, by the Takahashi recurrence on the band Cholesky factor (Takahashi, Fagan and Chin 1973; the
// "selected inversion" of sparse solvers), in O(K·b²) for K control points and bandwidth b, like the factorisation.

#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "probecomp/fitting/hierarchical.hpp"
#include "probecomp/fitting/least_squares.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::fitting {

// How the smoothing is chosen: the λ whose fit best predicts points left out of it.
enum class CrossValidation {
  LeaveOneOut,   // each point alone (Allen's PRESS)
  LeaveSpanOut,  // every point of a knot span at once: predicted from farther points, as the fit between scan
                 // lines is (see leave_span_out in penalized.cpp)
};

struct PenalizedFitOptions {
  // A fixed smoothing (log10 of λ relative to trace(AᵀWA) / trace(G)); empty: chosen by cross-validation in the
  // range below.
  std::optional<double> log10_smoothing;
  // The search: a scan in steps of `scan_step` decades over [min, max], then a golden-section search between the
  // best step's two neighbours; a range no wider than two steps (a search near a known λ) by golden sections alone. The score is smooth and has one minimum in practice, so the scan only brackets
  // it. Relative λ of 1e-9 lets the fit follow noise-free data to a few hundredths of a micrometre; 1e3 is far
  // beyond where the energy dominates any data set (the fit is then S⁰ plus a linear displacement).
  double min_log10_smoothing = -9.0;
  double max_log10_smoothing = 3.0;
  double scan_step = 1.5;
  int golden_steps = 6;
  // ε relative to the mean diagonal of AᵀWA: far below any data's weight on a control point.
  double ridge = 1e-9;
  CrossValidation cross_validation = CrossValidation::LeaveOneOut;
  // Leave-span-out's groups cut also by these breakpoints (both given, each covering the domain): two fits on
  // different nets are scored on the same groups when each is cut by the other's breakpoints (every span of the
  // union of both nets' breakpoints then lies in one span of each), so that their scores compare. Empty: the
  // net's own spans.
  std::vector<double> cv_fold_u{}, cv_fold_v{};
  // With leave-span-out: of the λ whose score is within one standard error of the best's, the largest (see
  // fit_penalized). For noisy data only: on exact data the spans' terms differ by the fit's misfit, not by noise,
  // and the rule would smooth away what the data show (shape suite S13 at 3 000 points: std 0.33 -> 1.01 µm).
  bool smoothest_within_one_standard_error = false;
  // The energy's anisotropy θ (see below), chosen by the same cross-validation after λ unless fixed here (log10)
  // or turned off (θ = 1). Two decades either way: beyond them one direction's bending costs nothing. Chosen on a
  // fixed grid with a slight preference for θ = 1, so that it moves continuously with the data (see fit_penalized).
  bool anisotropic = true;
  std::optional<double> log10_anisotropy;
  double max_log10_anisotropy = 2.0;
  // After λ and θ (chosen or given), the smoothing moved as two directional weights, λθ along u and λ/θ along v,
  // one at a time, where that predicts better (see fit_penalized): θ sought at one λ stops short where the best
  // lies along a diagonal valley of (λ, θ).
  bool directional_smoothing = false;
  // Decades added to the λ cross-validation chooses, for studies of that choice against the truth (shape_suite
  // --oracle); 0 in use.
  double log10_smoothing_offset = 0.0;
  // A fixed absolute λ (PenalizedFitResult::lambda), overriding the above: a fit on a finer net with the smoothing
  // of one already made (the relative λ is scaled by each net's traces).
  std::optional<double> lambda;
};

struct LinearFit;  // penalized.cpp

struct PenalizedFitResult {
  using Status = FitStatus;
  Status status = Status::NotDone;
  nurbs::Surface surface;           // the fit (the start surface unless OK)
  double log10_smoothing = 0.0;     // the λ used, relative (see the options)
  double log10_anisotropy = 0.0;    // the θ used
  double lambda = 0.0;              // the λ used, absolute
  double effective_dof = 0.0;       // tr H: the fit's effective number of parameters per coordinate
  double cv_score = 0.0;            // its cross-validation score (mean squared prediction error), mm²
  double rss = 0.0;                 // Σ w_k |S(u_k,v_k) − x_k|², mm²
  double weight_sum = 0.0;          // Σ w_k
  int points_used = 0;              // points with w_k > 0
  int evaluations = 0;              // factorisations made in the search
  bool directional_moved = false;   // the directional weights' search moved the smoothing (see the options)
  // Per point: a_kᵀ (AᵀWA + λG + εI)⁻¹ a_k, a_k its row of the basis. The fitted point's variance is σ² times
  // this (Wahba's Bayesian posterior variance, which also covers the smoothing bias on average: Nychka 1988);
  // w_k times this is the point's hat diagonal (its leverage). Defined for left-out points too.
  std::vector<double> variance_factor{};
  // Per knot span (a·(V spans) + b): the isotropic thin-plate energy of the fitted displacement over the span,
  // D̂ᵀ G_span D̂ with θ = 1 and without the span's weight (mm²·mm⁻⁴·mm²): what a spatially adaptive penalty follows
  // (fit_surface).
  std::vector<double> span_energy{};
  // Per point: the fit's smoothing bias there (the fitted point's expected error due to the penalty), estimated
  // by −λ·R(u,v)ᵀ(AᵀWA + λG)⁻¹·G·D̃, mm, with D̃ = D̂ corrected by passes of the same estimate (see fit_penalized).
  std::vector<Vector3> smoothing_bias{};
  // The fit at its λ as a linear map of the data (its factor and the points' basis rows), for null_statistics;
  // kept only where the rows were (below 2·16 384 points).
  std::shared_ptr<const LinearFit> linear{};

  [[nodiscard]] bool ok() const { return status == Status::OK; }
};

// `weights` empty means all 1; a zero weight leaves a point out of the fit (it still gets its variance factor).
// `span_weights`: the penalty's weight per knot span, span (a, b) at a·(V spans) + b; empty means all 1.
// Parallel (oneTBB) and deterministic.
[[nodiscard]] PenalizedFitResult fit_penalized(const nurbs::Surface& start, std::span<const Point3> points,
                                               std::span<const SurfaceParameter> params,
                                               std::span<const double> weights = {},
                                               const PenalizedFitOptions& options = {},
                                               std::span<const double> span_weights = {});

// The same fit in a hierarchical basis (hierarchical.hpp): the unknowns are its THB functions' displacements, the
// output is on `basis.surface` (the start refined to the output knots), and `span_weights` are per knot span of that
// surface; every per-span and per-point result is as above. With no cell refined, the same fit as the tensor one.
[[nodiscard]] PenalizedFitResult fit_penalized(const HierarchicalBasis& basis, std::span<const Point3> points,
                                               std::span<const SurfaceParameter> params,
                                               std::span<const double> weights = {},
                                               const PenalizedFitOptions& options = {},
                                               std::span<const double> span_weights = {});

// A statistic of a fit's residuals under pure noise: at its λ the fit is linear in the data, so its residuals of
// `probes` draws of pure noise (variance 1/w_k at point k, from a fixed seed) show what the fit alone does to the
// statistic (its residuals repel one another, for one). `statistic` is passed each draw's residuals, one per
// point; its values are returned in draw order. Empty where the fit kept no LinearFit. Deterministic.
[[nodiscard]] std::vector<double> null_statistics(const PenalizedFitResult& fit, int probes,
                                                  const std::function<double(std::span<const double>)>& statistic);

}  // namespace probecomp::fitting
