#pragma once
// Each point's nearest other points in space (k-d trees, geometry/point_tree.hpp), for tests that compare a point
// with what is around it: the noise from neighbouring differences, a residual against its neighbours'.

#include <cstdint>
#include <span>
#include <vector>

#include "probecomp/geometry/types.hpp"

namespace probecomp::geometry {

// Point k's `count` nearest other points, nearest first, at [k·count, (k + 1)·count). A duplicate of a point counts
// as another point (its own measurement). Fewer points than count + 1: the lists repeat the farthest available
// point (a point alone, or one with a non-finite coordinate, lists itself). Parallel, deterministic.
[[nodiscard]] std::vector<std::uint32_t> nearest_others(std::span<const Point3> points, int count);

// For each point, the index of the first point (lowest index) within `tolerance` (mm) of it: itself unless it
// repeats an earlier point's position. Parallel, deterministic.
[[nodiscard]] std::vector<std::uint32_t> first_at_same_position(std::span<const Point3> points, double tolerance);

}  // namespace probecomp::geometry
