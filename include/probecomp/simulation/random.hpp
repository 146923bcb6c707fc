#pragma once
// Three draws from one distribution as a vector, in a fixed order. The arguments of one call are evaluated in an
// order the compiler chooses (gcc takes the last first, clang the first), so Vector3(d(rng), d(rng), d(rng)) gave
// each compiler other points for the same seed. These are drawn z, then y, then x: gcc's order, with which the
// figures in docs/ were measured.

#include "probecomp/geometry/types.hpp"

namespace probecomp::simulation {

template <class Distribution, class Engine>
[[nodiscard]] Vector3 draw_vector(Distribution& d, Engine& rng) {
  const double z = d(rng);
  const double y = d(rng);
  const double x = d(rng);
  return {x, y, z};
}

}  // namespace probecomp::simulation
