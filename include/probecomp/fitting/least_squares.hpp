#pragma once
// Least-squares fit of a NURBS surface's control points to points with known parameters: degrees, knots and
// weights fixed, so S(u_k, v_k) = Σ R_ij(u_k, v_k) P_ij is linear in the unknown P (R: the rational basis).
//
// Minimises Σ_k w_k |S(u_k, v_k) − x_k|² by proximal iterations from the start surface P⁰:
//   P^{t+1} = argmin Σ_k w_k |S(u_k, v_k) − x_k|² + λ_p |P − P^t|² + λ_s |Δ²(P − P^t)|²,
// Δ² the second differences of the control net along u and v. Each step is one solve with the same sparse
// Cholesky factor. The iterates converge to the least-squares solution nearest the start in the metric of the
// two terms: where the data determine the control points, the exact least-squares fit (no bias); where they
// do not (spans with few or no points), the start plus the smoothest change. A fixed cap on the iterations
// also damps directions the data determine only weakly, like early-stopped conjugate gradients (the paper's
// solver, warm-started at the nominal control points).

#include <span>
#include <vector>

#include "probecomp/nurbs/surface.hpp"

namespace probecomp::fitting {

struct SurfaceParameter {
  double u = 0.0, v = 0.0;
};

struct FitOptions {
  // λ_p and λ_s as fractions of the mean diagonal of the data's normal matrix AᵀWA, so that they do not depend
  // on the number of points or their weights. Small: they only make the system definite. Measured on a random
  // rational bicubic with data on half its domain: with both at 1e-6 the iterations converge (to 1e-11 mm on
  // the data's half) in about 65 steps and the free control points move less than the start's error; a
  // smoothness of 1e-4 slows convergence a hundredfold (it weighs the net's short waves, which the data fix).
  double pull = 1e-6;
  double smoothness = 1e-6;
  // Proximal iterations stop when no control point moves by more than `convergence` (mm), or at the cap.
  int max_iterations = 200;
  double convergence = 1e-11;
};

// The outcome of one fit of the control points on fixed knots (fit_control_points, fit_penalized).
enum class FitStatus {
  OK,              // fitted
  NotDone,         // bad input: counts differ, no points, a parameter or point not finite, a negative weight
  NumericalError,  // the factorisation failed or produced non-finite control points
};

struct FitResult {
  using Status = FitStatus;
  Status status = Status::NotDone;
  nurbs::Surface surface;  // the fit (the start surface unless status is OK)
  int iterations = 0;      // proximal iterations
  double rms = 0.0;        // √(Σ w_k |S(u_k,v_k) − x_k|² / Σ w_k), mm
  double max_residual = 0.0;  // max |S(u_k,v_k) − x_k| over points with w_k > 0, mm

  [[nodiscard]] bool ok() const { return status == Status::OK; }
};

// `weights` empty means all 1; a zero weight leaves a point out. Parallel (oneTBB) and deterministic.
[[nodiscard]] FitResult fit_control_points(const nurbs::Surface& start, std::span<const Point3> points,
                                           std::span<const SurfaceParameter> params,
                                           std::span<const double> weights = {}, const FitOptions& options = {});

// |S(u_k, v_k) − x_k| for each point, in parallel.
[[nodiscard]] std::vector<double> parametric_residuals(const nurbs::Surface& s, std::span<const Point3> points,
                                                       std::span<const SurfaceParameter> params);

}  // namespace probecomp::fitting
