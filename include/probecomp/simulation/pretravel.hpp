#pragma once
// A touch-trigger probe's pre-travel as the simulator applies it (DESIGN.md §8): the machine travels on past the
// first contact by p(d) before the switch triggers, so the centre it reports lies p(d) beyond the true one along the
// travel direction d, and the tip looks smaller by p(d) (its effective radius is r − p(d)). Kinematic probes
// trigger on three contacts about the stylus, so a horizontal touch's pre-travel has three lobes in azimuth, and a
// touch along the stylus differs from a horizontal one. With θ the angle between d and the stylus's direction
// (pointing from the head to the tip: a vertical touch from above has θ = 0) and φ d's azimuth about it:
//   p(d) = p₀ + b·cos²θ + a·sin²θ·cos(n(φ − φ₀))
// cos²θ and the lobes' sin²θ are not a finite sum of low-order spherical harmonics, on purpose: the qualification
// model must approximate the physics, not contain it.

#include "probecomp/geometry/types.hpp"

namespace probecomp::simulation {

struct Pretravel {
  double constant = 0.0;  // p₀, mm
  double axial = 0.0;     // b: a touch along the stylus minus a horizontal one (lobes aside), mm
  double lobes = 0.0;     // a: half the peak-to-valley of the horizontal lobing, mm
  int lobe_count = 3;     // n
  double phase = 0.0;     // φ₀, degrees from the first axis of the stylus frame
  // The stylus's direction, from the probe head to the tip, machine frame: a vertical stylus points down.
  Vector3 stylus = -Vector3::UnitZ();

  // p(d), mm, for a travel direction d (any length > 0).
  [[nodiscard]] double operator()(const Vector3& travel) const;
  [[nodiscard]] bool none() const { return constant == 0.0 && axial == 0.0 && lobes == 0.0; }
};

// The kinematic probe of issue 52 and the approach-angle study: ±4 µm of three lobes about a vertical stylus (phase
// 20°), 3 µm more along the stylus than across it, 2 µm constant.
[[nodiscard]] Pretravel lobing_probe();

}  // namespace probecomp::simulation
