#pragma once
// Gross errors put into simulated readings, for the outlier tests: deterministic for a given seed.

#include <cstdint>
#include <vector>

#include "probecomp/geometry/types.hpp"
#include "probecomp/simulation/measure.hpp"

namespace probecomp::testing {

// 1 % of the points, chosen by `seed`, moved 0.1–5 mm along their programmed normal, out or in: the probe's
// direction of travel, where a dirty tip or a vibration puts a reading's error (a move along the surface would only
// be a reading of another place). Returns which were moved.
std::vector<char> move_one_percent(std::vector<Point3>& points, const std::vector<simulation::ProgrammedPoint>& plan,
                                   std::uint64_t seed);

}  // namespace probecomp::testing
