#pragma once
// Shape deviations for simulated parts: displacements along the nominal outward normal, functions of the nominal
// point's position (so they mean the same on every face of a model, whatever its parametrisation):
//   bump      a·exp(−|x − c|² / (2w²))       (a < 0: a dent; w is the Gaussian's standard deviation, mm)
//   sinusoid  a·sin(2π (d·(x − o)) / λ + φ)  (d a unit direction; optional Gaussian window of width w about o,
//             or across a band: the window taken over the distance along a second direction only)
//   crease    h·½(1 + tanh(2 d·(x − o) / w))  (a smoothed step of height h across the plane through o normal to d,
//             rising from 12 % to 88 % of h over the width w)
//   twist     a·(d₁·(x − o))(d₂·(x − o)) / L²  (a hyperbolic paraboloid about o; with d₂ ⊥ d₁ a twist, and a
//             saddle when turned by 45°: s·t = ((s+t)/√2)² / 2 − ((s−t)/√2)² / 2)
// A deformed face is a NURBS: the nominal (raised to degree 3 in a degree-1 direction) with knots inserted where
// the deformation needs them, fitted to nominal + displacement to 1e-5 mm (fitting::displaced_surface). That
// NURBS *is* the simulated actual surface.

#include <vector>

#include "probecomp/nurbs/surface.hpp"

namespace probecomp::simulation {

struct Bump {
  Point3 centre = Point3::Zero();
  double amplitude = 0.0;  // mm, + out of the material
  double width = 1.0;      // standard deviation of the Gaussian, mm
};

struct Sinusoid {
  double amplitude = 0.0;   // mm
  double wavelength = 1.0;  // mm
  Vector3 direction = Vector3::UnitX();
  Point3 origin = Point3::Zero();
  double window = 0.0;  // > 0: Gaussian window of this standard deviation about `origin` (a local wave), mm
  double phase = 0.0;   // φ, degrees: 90 puts a crest (of height a) at `origin`
  // Zero: the window is radial about `origin`. A unit vector: the window applies to the distance along it only,
  // so that the wave fills a band through `origin` across this direction.
  Vector3 band = Vector3::Zero();
};

struct Crease {
  Point3 origin = Point3::Zero();
  Vector3 direction = Vector3::UnitX();  // across the crease, towards its high side
  double height = 0.0;  // the step, mm (+ out of the material on the high side)
  double width = 1.0;   // over which it rises (12 % to 88 %), mm
};

struct Twist {
  Point3 origin = Point3::Zero();
  Vector3 first = Vector3::UnitX(), second = Vector3::UnitY();
  double amplitude = 0.0;  // mm at s = t = length
  double length = 1.0;     // mm
};

struct Deformation {
  std::vector<Bump> bumps;
  std::vector<Sinusoid> sinusoids;
  std::vector<Crease> creases;
  std::vector<Twist> twists;

  [[nodiscard]] bool empty() const { return bumps.empty() && sinusoids.empty() && creases.empty() && twists.empty(); }
  // Displacement along the outward normal at the nominal point x, mm.
  [[nodiscard]] double displacement(const Point3& x) const;
  // The shortest length the displacement varies over near x (mm): knots are spaced a fraction of it.
  [[nodiscard]] double feature_length(const Point3& x) const;
};

// Refined spans are at most this fraction of the local feature length (a Gaussian's width, a quarter wave).
inline constexpr double kSpansPerFeature = 4.0;

// The face `s` (outward normal = outward · S_u × S_v) deformed by `d`. Knots are inserted (shape unchanged)
// until every span is shorter than feature_length / kSpansPerFeature wherever the deformation is not
// negligible (below 1e-9 mm), then the surface is fitted. Returns `s` itself when `d` is empty; throws
// std::invalid_argument for a face without a normal somewhere.
[[nodiscard]] nurbs::Surface deformed_surface(const nurbs::Surface& s, int outward, const Deformation& d);

}  // namespace probecomp::simulation
