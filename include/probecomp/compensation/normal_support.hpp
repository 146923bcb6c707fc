#pragma once
// Whether the data around a point support the fitted normal the point is offset along, where points were left out
// of the fit. Over the gap that left-out points (outliers) leave, only the penalty holds the fit's shape, and on
// exact data a flexible fit may swing there: the positions it fits at the gap's rim stay right, but its normal can
// tilt, and the contact point, offset by r along it, is then r(1 − cos θ) off along the normal (measured on the
// free-form panel, 120 × 60 noise-free points with 1 % moved 0.1–5 mm: 23° and 54° next to a dozen points left out,
// rows 81 and 436 µm off with a u of 0.1 µm).
//
// The check compares the fit's normal at each point near a left-out one (and at the left-out points) with the
// normals of the least-squares quadric and cubic through the nearest in-fit centres, at the same place, and keeps
// the larger disagreement: models of fixed, low degree that the fit's flexibility does not enter, and two of them,
// because next to a narrow feature the quadric alone can share the fit's error (measured: a row 2 µm off whose fit
// normal the quadric confirmed to 0.07° and the cubic did not). Their own slope error on noisy data (σ over the
// neighbourhood's size: milliradians) makes r(1 − cos θ) a few nanometres. Elsewhere the fit's normal is held by
// the points themselves and nothing is checked (no cost on faces with nothing left out).
//
// Points that lie along lines (a scanning probe's, millimetres apart and dense along) are checked too, all of
// them: across the lines only the penalty holds the fit, and on exact or nearly exact data it swings between them
// (measured on the shape suite, lines 4 mm apart, σ = 0: normals tens of degrees off, contacts up to 0.56 mm off
// with a u of 0.1 µm). Their local models take neighbours from enough lines to span a surface: four for the cubic
// (through three its t³ is fixed only by the lines' waviness), else the quadric through three. What neither shows,
// the normal across the lines where nothing was measured, is compensation/scan_lines.hpp's.

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "probecomp/fitting/least_squares.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::compensation {

struct NormalCheck {
  // In-fit points within this many point spacings (the median distance to the nearest other in-fit point) of a
  // left-out point are checked: a bicubic fit's control points reach about two knot spans, and refinement on exact
  // data stops at spans of one to two spacings. Measured on the noise-free panel with 1 % gross errors (120 × 60,
  // seeds 1–3), worst row in stated u: 1.28, 2.48, 1.03 at 3 spacings; 1.28, 1.39, 0.99 at 4 and at 6.
  double reach_spacings = 4.0;
  // The quadric is fitted through this many nearest in-fit centres (the point's own included), more where they
  // do not span two directions (points along one scan line).
  int neighbours = 20;
  int max_neighbours = 160;
  // For points along lines: the neighbourhood grows to span four lines (a cubic across them), at 0.2 mm along and
  // 5 mm across about 600 points.
  int max_line_neighbours = 1280;
  // A point is on a line when its nearest in-fit neighbours (this many, itself included) spread across less than
  // a tenth of their spread along (variance ratio 1e-2); a face is sampled along lines when a quarter of a sample
  // of its points is.
  int line_neighbours = 8;
  // Points on lines checked at most (each takes a neighbourhood of a few hundred points across four lines): a
  // bounded cost on a million points; the others take the angle of a neighbour checked.
  std::size_t max_line_checks = 20000;
  double line_variance_ratio = 1e-2;
  double line_share = 0.25;
  // Whether the points lie along lines, when the caller has decided it (sampled_along_lines); empty: decided here.
  std::optional<bool> along_lines{};
};

struct NormalDisagreement {
  // Per point (see normal_disagreement); empty when nothing was checked.
  std::vector<double> angle;
  bool along_lines = false;  // the face is sampled along lines, and every point on one was checked
};

// Whether the points lie along lines (a scanning probe's): a quarter of the points tested each with its nearest
// neighbours on a line (NormalCheck::line_neighbours, line_variance_ratio, line_share), those tested being the
// points of 16 small blocks spread over the set.
[[nodiscard]] bool sampled_along_lines(std::span<const Point3> centres, const NormalCheck& check = {});

// Per point (`centres` and `params` as fitted, `weights` as given to the fit: zero for points left out): the angle
// (radians, 0 to π/2) between `fit`'s normal at the point's parameters and the local models' normals there, for
// left-out points, in-fit points near them and, on a face sampled along lines, points on a line; 0 elsewhere. NaN
// where it could not be told (no normal on the fit, or no neighbours spanning a surface within the neighbourhood
// allowed). Empty when nothing was checked.
// Parallel, deterministic.
[[nodiscard]] NormalDisagreement normal_disagreement(const nurbs::Surface& fit, std::span<const Point3> centres,
                                                      std::span<const fitting::SurfaceParameter> params,
                                                      std::span<const double> weights, const NormalCheck& check = {});

}  // namespace probecomp::compensation
