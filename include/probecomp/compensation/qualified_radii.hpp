#pragma once
// Each point's tip radius from its stylus's qualification (probe/qualification.hpp, DESIGN.md §8): the effective
// radius in the direction the probe travelled to touch it, and that radius's own uncertainty, which goes into the
// point's u. A stylus the qualification does not hold takes the point's own radius (a column r) or the run's
// default; with neither it is refused, by name.

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "probecomp/geometry/types.hpp"
#include "probecomp/probe/qualification.hpp"

namespace probecomp::compensation {

// How the points of one stylus took their radii (for --json's "qualification").
struct StylusRadii {
  std::string stylus;
  bool qualified = false;     // else its points took their own or the default radius
  int points = 0;
  int unsupported = 0;        // approached from directions its qualification never touched from
  double effective_radius = 0.0, variation = 0.0;  // the qualification's (mm): sphere-fit radius, rms by direction
  int degree = 0;
};

struct QualifiedRadii {
  std::vector<double> radius;       // per point, mm
  std::vector<double> uncertainty;  // per point, the radius's standard uncertainty, mm (0 where not qualified)
  std::vector<std::string> warnings;
  std::vector<StylusRadii> styli;   // in the order each first appears among the points
};

// `styli`: each point's stylus; empty when the points name none, and then the qualification must hold one stylus
// (that one measured every point). `travel`: each point's travel direction (−(i,j,k), or against a fitted normal;
// zero where it is not known: the sphere-fit radius, with the model's variation over all directions in its u).
// `own_radius`: per point (NaN: none) or empty; `default_radius` ≤ 0: none. Throws InputError for a stylus that is
// neither qualified nor given a radius, a stylus whose qualification failed, or points that name no stylus when
// several are qualified.
[[nodiscard]] QualifiedRadii qualified_radii(const probe::Qualification& qualification,
                                             std::span<const std::string> styli, std::span<const Vector3> travel,
                                             std::span<const double> own_radius, double default_radius);

}  // namespace probecomp::compensation
