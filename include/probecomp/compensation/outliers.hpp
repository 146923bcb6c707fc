#pragma once
// Gross outliers among one face's points, found before the fit so that refinement cannot chase them. A point's
// residual from the registered offset model (its deviation plus noise) is compared with a robust local quadratic
// through its nearest neighbours' residuals: a deformation is smooth, so its neighbours predict it (to third
// order in the point spacing), while a gross error is the point's alone. A point departing from its prediction
// by more than `sigmas` robust scales (and `min_departure`) is an outlier.

#include <cstdint>
#include <span>
#include <vector>

#include "probecomp/geometry/types.hpp"

namespace probecomp::compensation {

struct LocalOutlierOptions {
  int neighbours = 20;          // the quadratic's 6 coefficients from this many nearest points (k-d tree)
  double sigmas = 8.0;          // departures beyond this many robust scales (1.4826 × their MAD) ...
  double min_departure = 0.01;  // ... and beyond this (mm): far above a CMM's noise, far below a gross error
};

struct LocalOutliers {
  std::vector<char> outlier;  // per point
  double scale = 0.0;         // robust scale of the departures, mm
  int count = 0;
  std::vector<std::uint32_t> nearest;  // each point's nearest other point (for fitting::fit_surface)
};

// `residuals`: each point's signed distance from the model; `normals`: the model's unit normal there (the local
// chart is the plane across it). Parallel, deterministic. Fewer than neighbours + 1 points: none flagged.
[[nodiscard]] LocalOutliers local_outliers(std::span<const Point3> points, std::span<const double> residuals,
                                           std::span<const Vector3> normals, const LocalOutlierOptions& options = {});

}  // namespace probecomp::compensation
