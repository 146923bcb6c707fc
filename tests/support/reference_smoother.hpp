#pragma once
// An independent reference smoother for scattered heights z_k at (s_k, t_k): a tensor-product cubic P-spline
// (Eilers & Marx 1996; 2-D form Eilers, Currie & Durbán 2006) whose two smoothing weights are chosen by GCV.
// It is a yardstick for the project's own surface fits and shares no code with them; it needs only Eigen.
//
// Contract. The fit f minimises
//     Σ_k w_k (z_k − f(s_k,t_k))² + λ_s Σ_r e^{a(r)} (Δ²_s c / h_s²)_r² + λ_t Σ_r e^{a(r)} (Δ²_t c / h_t²)_r²
// over uniform cubic B-spline coefficients c (spans_s × spans_t equal spans of lengths h_s, h_t, knots continued
// evenly past the rectangle, i.e. not clamped), Δ² the second difference of c along one direction. Dividing by
// h² makes Δ²c/h² approximate the second derivative, so λ_s and λ_t (in w·mm⁴) are comparable whatever the
// span lengths. The penalty's null space is {α + βs + γt + δst}, reproduced exactly.
// a(r) is 0 unless `adaptive`; then it is the log-weight of the K×K block of the rectangle holding the centre
// of difference r (the Greville point of its middle coefficient, clamped into the rectangle).
// λ_s, λ_t minimise GCV = n·RSS/(n − tr H)², n the points used, RSS = Σ w r², H the hat matrix: a 13 × 13 grid
// of log10(λ/λ_ref) over [−5, 7], then golden-section coordinate search; then, if adaptive, the K² log-weights
// one block at a time (a few sweeps, each bounded to ±7). Each λ tried costs O(N b²), N the coefficients and
// b ≈ 3(min(spans) + 3) the bandwidth.
// Points outside the rectangle, with non-finite values or with w_k ≤ 0 are left out (their h_k is 0).
// Data problems are reported in `status`, never thrown; std::invalid_argument only for a malformed call
// (empty or inverted rectangle, spans < 1, sizes that differ). Deterministic; prints nothing.

#include <cstddef>
#include <span>
#include <vector>

namespace probecomp::reference {

enum class SmootherStatus {
  OK,
  NotEnoughData,   // fewer than 5 points used, or they do not fix a bilinear function (all equal, on a line)
  NumericalError,  // the normal matrix could not be factorised at any λ tried, or the result is not finite
};

struct SmootherOptions {
  double s0 = 0.0, s1 = 1.0, t0 = 0.0, t1 = 1.0;  // the rectangle, mm
  int spans_s = 10, spans_t = 10;                 // equal spans in each direction
  // Both > 0: fit at these λ (no GCV search for them). Otherwise GCV chooses them.
  double lambda_s = 0.0, lambda_t = 0.0;
  bool adaptive = false;  // block-wise penalty weights e^{a_m}, chosen by GCV after λ_s, λ_t
  int adaptive_blocks = 4;  // K: the rectangle is cut into K × K blocks
  int adaptive_sweeps = 2;  // coordinate-descent sweeps over the K² log-weights
};

struct SmootherResult {
  SmootherStatus status = SmootherStatus::NotEnoughData;
  // The basis, copied from the options so that evaluate() needs nothing else.
  double s0 = 0.0, s1 = 1.0, t0 = 0.0, t1 = 1.0;
  int spans_s = 0, spans_t = 0;
  // (spans_s + 3)(spans_t + 3) coefficients; B-spline i_s along s times j_t along t is at i_s·(spans_t + 3) + j_t.
  // Basis function i along a direction starts at x0 + (i − 3)h and its Greville point is x0 + (i − 1)h.
  std::vector<double> coefficients;
  double lambda_s = 0.0, lambda_t = 0.0;
  double lambda_reference = 0.0;  // trace(BᵀWB) / trace(P_s + P_t) at unit weights: the scale of the λ grid
  // K² log-weights a_m, block (b_s, b_t) at b_s·K + b_t, b_s = ⌊K(s − s0)/(s1 − s0)⌋ clamped to [0, K−1];
  // empty unless adaptive.
  std::vector<double> log_weights;
  double edf = 0.0;    // tr H, effective degrees of freedom
  double gcv = 0.0;    // n·RSS/(n − tr H)²; +∞ if a fixed λ makes tr H ≥ n (then sigma is 0)
  double sigma = 0.0;  // sqrt(RSS / (n − tr H)), the noise of a unit-weight point, mm
  std::size_t points_used = 0;
  std::vector<double> hat;  // h_k = ∂f(s_k,t_k)/∂z_k per input point, 0 for points left out
};

struct SmootherValue {
  double value = 0.0, ds = 0.0, dt = 0.0;  // f and ∂f/∂s, ∂f/∂t
};

// Fits z (mm) at (s, t); w empty means all weights 1, else one weight per point.
[[nodiscard]] SmootherResult smooth(std::span<const double> s, std::span<const double> t, std::span<const double> z,
                                    const SmootherOptions& options, std::span<const double> w = {});

// f and its first derivatives at (s, t) in the rectangle (outside it, the edge spans' polynomials continue).
// NaN when the coefficients are not of the documented size (they are empty unless status is OK).
[[nodiscard]] SmootherValue evaluate(const SmootherResult& fit, double s, double t);

}  // namespace probecomp::reference
