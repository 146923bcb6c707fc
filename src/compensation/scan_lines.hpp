#pragma once
// What points along scan lines (a scanning probe's, millimetres apart and dense along) leave the fit unsure of,
// beyond its own variance and bias estimates. Private to compensation/.
//
// Across lines millimetres apart only the penalty holds the fit. Shape the lines do not resolve across (a feature
// about as wide as their spacing, crossing them) bends the fit on the lines too, and tilts its normal there:
//  - the bias along a line shows in the residuals of the points on it, dense along it: shape suite D500 (lines
//    4.5 mm apart, 0.15 mm along), over eight draws of the noise, the contacts' bias is 1.27 µm rms, varying along
//    each line over millimetres, where the penalty's own estimate (PenalizedFitResult::smoothing_bias) reads 0.1 µm;
//  - the normal across the lines no data show: the local models through three lines
//    (compensation/normal_support.hpp) share the fit's error there (shape suite S13 without noise, a dent 2 mm wide
//    between lines 4 mm apart: rows 7–9 µm off, the fit's normal 7° off, the models within 1–4° of it). Taken as
//    the turn of the fitted deformation's slope along the line over half the lines' spacing: the deformation is
//    assumed to bend no more sharply across the lines than along them. On exact data the largest such turn over the
//    same line within one spacing: a feature crossing the lines obliquely meets each line further along than the
//    last, and the fit's normal is wrong as far along a line as the feature moves from one line to the next (shape
//    suite S29, lines 4 mm apart across a 1 mm crease at 60°, no noise: normals 2–4° rms off where the turn at the
//    point itself, zero at the crease's inflection, left ±2u covering 79.1 % of the worst region's errors).

#include <span>
#include <vector>

#include "probecomp/fitting/least_squares.hpp"
#include "probecomp/geometry/types.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::compensation::detail {

struct ScanLineDoubts {
  // Per point (0 off lines): the fit's bias estimated from the residuals along the line, mm (see below).
  std::vector<double> bias;
  // Per point (0 off lines): the angle its normal may be off across the lines unseen (radians).
  std::vector<double> normal_angle;
  double line_spacing = 0.0;  // the lines' spacing (median over a sample), mm; 0 when not told
};

// A point is on a line when its kNearLine nearest in-fit centres (weights > 0) spread across less than
// `line_variance_ratio` times their spread along (as NormalCheck). There:
//  - bias: the size of those neighbours' residuals' mean less that mean's noise, √max(0, m² − σ²/K) (σ the fit's
//    noise), whose square is an unbiased estimate of the bias's; its root mean square over the point's 64 nearest
//    (the bias's local level: the estimate alone is too noisy to tell one point from the next);
//  - normal_angle: |∂²δ/∂s²|·h/2, δ the fit's displacement from `start` along its normal, s the arc length along the
//    line and h the lines' spacing; where `exact_data`, its largest over the in-fit points within h that lie along
//    the point's line (their direction from it within 60° of the line's).
// `fit` and `start` share their parametrisation (the fit is start's net moved); `residuals` along the fit's normal.
// Parallel, deterministic.
[[nodiscard]] ScanLineDoubts scan_line_doubts(const nurbs::Surface& fit, const nurbs::Surface& start,
                                              std::span<const Point3> centres,
                                              std::span<const fitting::SurfaceParameter> params,
                                              std::span<const double> residuals, std::span<const double> weights,
                                              double sigma, double line_variance_ratio, bool exact_data);

// Points along scan lines, in the order measured, numbered by line (0, 1, …): a line ends where the step to the
// next point is over kLineBreakSteps times the median step. Empty where that gives fewer than `min_lines` lines or
// does not follow lines (their median length under kMinLinePoints points: points listed in another order).
[[nodiscard]] std::vector<int> scan_line_numbers(std::span<const Point3> centres, int min_lines);

}  // namespace probecomp::compensation::detail
