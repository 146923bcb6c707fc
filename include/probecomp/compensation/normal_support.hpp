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
};

// Per point (`centres` and `params` as fitted, `weights` as given to the fit: zero for points left out): the angle
// (radians, 0 to π/2) between `fit`'s normal at the point's parameters and the local models' normals there, for
// left-out points and in-fit points near them; 0 elsewhere. NaN where it could not be told (no normal on
// the fit, or no neighbours spanning a surface within max_neighbours). Empty when no point was left out.
// Parallel, deterministic.
[[nodiscard]] std::vector<double> normal_disagreement(const nurbs::Surface& fit, std::span<const Point3> centres,
                                                      std::span<const fitting::SurfaceParameter> params,
                                                      std::span<const double> weights, const NormalCheck& check = {});

}  // namespace probecomp::compensation
