#pragma once
// The measurement noise from residuals, without trusting the fit to have followed the shape: each point's residual
// against what its nearest neighbours' residuals predict for it through a local quadratic, so that a smooth misfit
// the fit still leaves (a broad bulge between its knots) cancels and only independent noise remains.

#include <cstdint>
#include <span>
#include <vector>

#include "probecomp/fitting/least_squares.hpp"
#include "probecomp/geometry/types.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::fitting {

// A difference-based noise estimate (in the spirit of Rice 1984 and Gasser, Sroka and Jennen-Steinmetz 1986, for
// scattered points on a surface): for point k, the residuals of its kNeighbours nearest points are fitted with a
// quadratic over their tangent plane (from the neighbourhood's principal axes), or along the line where they lie
// on one (a scan line);
// e_k = r_k − that quadratic at k has variance σ²(1 + a_k) exactly when the residuals' smooth part is locally
// quadratic (a_k: the prediction's own variance factor), whatever the fit did. σ is 1.4826 × the median of
// |e_k| / √(1 + a_k): a minority of gross errors or of points on a narrow feature does not move it.
class LocalPredictionNoise {
 public:
  static constexpr int kNeighbours = 12;

  // A noise estimate reads the same from a sample as from every point: this many at most.
  static constexpr std::size_t kMaxPoints = 50'000;

  // Built once per face from the points' positions and weights (zero: left out, as tested point and as
  // neighbour). Over max_points points, every m-th point and its neighbours among those (deterministic).
  LocalPredictionNoise(std::span<const Point3> points, std::span<const double> weights,
                       std::size_t max_points = kMaxPoints);

  // σ of the noise in `residuals` (one per point, in the order given at construction), mm; infinity where no
  // point has a usable neighbourhood.
  [[nodiscard]] double sigma(std::span<const double> residuals) const;
  // The correlation of each tested point's residual with its kNeighbours nearest ones', Σ r_k r_j / (K Σ r_k²):
  // about 0 (a little below: a fit's residuals repel) on noise alone, positive where a misfit smooth over
  // several points remains.
  [[nodiscard]] double neighbour_correlation(std::span<const double> residuals) const;
  // Points tested (those with a well-posed local quadratic).
  [[nodiscard]] std::size_t tested() const { return tested_.size(); }
  // The max_points it was built with.
  [[nodiscard]] std::size_t max_points() const { return max_points_; }
  // How many tested points' prediction errors stand out beyond `sigmas` times sigma(residuals) and beyond `floor`
  // (mm): a gross error's mark whatever the smooth shape around it (a local quadratic follows that). A sharp feature
  // the quadratic cannot follow (a crease between the neighbours) is counted too.
  [[nodiscard]] std::size_t standing_out(std::span<const double> residuals, double sigmas, double floor) const;
  // Per point (as many as `residuals`), 1 where a tested point stands out as above and its prediction error is also
  // the largest of its neighbourhood's: an isolated error (a gross error spoils its neighbours' predictions by less
  // than its own; a feature the quadratic cannot follow raises several neighbouring errors alike, and only its
  // local peaks are marked).
  [[nodiscard]] std::vector<char> isolated_errors(std::span<const double> residuals, double sigmas, double floor) const;

 private:
  // Each tested point's prediction error |e_k| / √(1 + a_k), in the order of tested_.
  [[nodiscard]] std::vector<double> prediction_errors(std::span<const double> residuals) const;
  // sigma() from those errors (n_points: the residuals' count); tested_ not empty.
  [[nodiscard]] double sigma_of(const std::vector<double>& e, std::size_t n_points) const;
  std::vector<std::uint32_t> tested_;     // the tested points
  std::vector<std::uint32_t> neighbour_;  // kNeighbours per tested point
  std::vector<float> weight_;             // the prediction's weight of each neighbour's residual
  std::vector<float> scale_;              // 1 / √(1 + a_k)
  std::size_t max_points_ = kMaxPoints;
};

// The points whose residuals stand out alone (LocalPredictionNoise::isolated_errors), found again among the rest
// without those found (a cluster of errors among each other's neighbours shows its largest first), up to eight
// passes, each over as many points as `local` (built over `points` with no weights) took.
[[nodiscard]] std::vector<char> peel_isolated_errors(const LocalPredictionNoise& local, std::span<const Point3> points,
                                                     std::span<const double> residuals, double sigmas, double floor);

// A screen for gross errors before any fit, of the points' distances from `s` along its normal (at each point's
// parameters), with `local` built by the caller over the points (no weights), to be used again (fit_surface takes
// it). The local quadratic follows the smooth deformation from `s`; a feature it cannot follow (a dent's rim, a
// crease) stands out too.
struct GrossErrorScreen {
  // Whether any point may be a gross error: one that stands out from what its neighbours predict by more than
  // `sigmas` times their noise and more than `floor` (mm), or one without a neighbourhood to judge it by (every
  // point is tested).
  bool may_hold = false;
  // Per point, 1 where it is peeled as an isolated error (peel_isolated_errors) beyond `peel_floor` (mm) too; empty
  // when none is.
  std::vector<char> isolated;
};
[[nodiscard]] GrossErrorScreen screen_for_gross_errors(const LocalPredictionNoise& local, const nurbs::Surface& s,
                                                       std::span<const Point3> points,
                                                       std::span<const SurfaceParameter> params, double sigmas,
                                                       double floor, double peel_floor);

}  // namespace probecomp::fitting
