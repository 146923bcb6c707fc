#pragma once
// The penalised fit's cross-validation (cross_validation.cpp): the points' basis rows, made once per fit, and the
// leave-one-out and leave-span-out scores of a trial λ from its displacement and the band of its inverse.
// Private to fitting/.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "basis_rows.hpp"

namespace probecomp::fitting::detail {

// Points the cross-validation score is summed over at most.
inline constexpr std::size_t kCvPoints = 16384;
// The cross-validation takes every stride-th point: every point below 2·kCvPoints.
inline std::size_t cv_stride(std::size_t n_points) { return std::max<std::size_t>(1, n_points / kCvPoints); }

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
  // Where each knot span's rows begin (rows are in span order), and the end: for leave-span-out (with folds, each
  // piece of a span a fold line cuts).
  std::vector<std::size_t> span_starts;
  [[nodiscard]] bool cover_every_point() const { return !row_of_point.empty(); }
};

// The rows of the points (every stride-th, weight > 0), in span order; with fold breakpoints (PenalizedFitOptions::
// cv_fold_u, cv_fold_v), each span's rows in the order of the fold cells, span_starts marking each piece.
[[nodiscard]] CvRows cv_rows(const RowMaker& maker, std::span<const Point3> points,
                             std::span<const SurfaceParameter> params, std::span<const double> weights,
                             const std::vector<double>& fold_u = {}, const std::vector<double>& fold_v = {});

// Σ w_k |r_k|² / (1 − h_k)² over the rows (leave_one_out) or each point's residual with its whole knot span left
// out (leave_span_out), D the trial's displacement (n × 3) and Z its band of the inverse (band_inverse, half-bandwidth b).
[[nodiscard]] double leave_one_out(const CvRows& rows, const std::vector<double>& D, std::span<const double> Z, int b);
// leave_span_out also gives each span's own term (in span order) in `span_terms` when asked.
[[nodiscard]] double leave_span_out(const CvRows& rows, const std::vector<double>& D, std::span<const double> Z, int b,
                                    std::vector<double>* span_terms = nullptr);

}  // namespace probecomp::fitting::detail
