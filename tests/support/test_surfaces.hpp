#pragma once
// Test geometry: random rational surfaces, a two-turn spiral sheet, random points near a surface, and noisy
// samples of a surface with their true parameters (for the fits).
// Deterministic for a given seed.

#include <cstdint>
#include <vector>

#include "probecomp/fitting/least_squares.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::testing {

struct RandomSurfaceSpec {
  int p = 3, q = 3;
  int nu = 8, nv = 7;          // control points per direction
  double size = 100.0;         // extent of the net in x and y, mm
  double height = 15.0;        // random z amplitude of the control points, mm
  double weight_min = 0.5, weight_max = 2.0;
  bool repeated_knots = true;  // one interior knot of multiplicity 2 in each direction where room allows
};

// A free-form rational surface over [0,1]² with random non-uniform knots, bumpy z and random weights.
[[nodiscard]] nurbs::Surface random_rational_surface(std::uint64_t seed, const RandomSurfaceSpec& spec = {});

// A smooth free-form panel like a body or blade surface: n × n control points over 200 × 200 mm, heights from
// two crossing waves (about ±25 mm), random non-uniform knots, weights in [0.8, 1.25]. Degree 3 × 3.
// Random knots under evenly spaced control points make creases of radius down to about 2 mm; with uniform
// knots the panel bends no tighter than its waves (radius about 20 mm), like a designed part surface.
[[nodiscard]] nurbs::Surface freeform_panel(std::uint64_t seed, int n = 20, bool uniform_knots = false);

// A two-turn Archimedean spiral sheet (radius 10 mm growing 6 mm per turn), 64 cubic spans along the spiral,
// extruded 30 mm in z (degree 1). Neighbouring sheets are 6 mm apart.
[[nodiscard]] nurbs::Surface spiral_sheet();

// `s` with every control point moved by up to `amount` mm in each coordinate (uniform); weights unchanged.
[[nodiscard]] nurbs::Surface perturbed(const nurbs::Surface& s, double amount, std::uint64_t seed);

// n points S(u,v) + t·n(u,v) with (u,v) uniform on the domain and t uniform in [-max_offset, max_offset].
[[nodiscard]] std::vector<Point3> random_points_near(const nurbs::Surface& s, std::size_t n, double max_offset,
                                                     std::uint64_t seed);

// Points sampled from a surface at known parameters: the data of a fit whose truth is the surface.
struct SurfaceSamples {
  std::vector<Point3> points;
  std::vector<fitting::SurfaceParameter> params;
};

enum class Noise {
  AlongNormal,  // one Gaussian draw of σ along the surface normal
  Isotropic,    // a Gaussian draw of σ in each coordinate
};

// n points S(u,v) at uniform random parameters, u in the first `u_fraction` of the domain, moved by Gaussian noise
// of standard deviation sigma (none drawn when sigma is 0); `params` are the true (u,v).
[[nodiscard]] SurfaceSamples sample_surface(const nurbs::Surface& s, std::size_t n, double sigma, std::uint64_t seed,
                                            Noise noise, double u_fraction = 1.0);

// |fit − truth| over a grid × grid lattice of parameters over truth's domain, u in its first `u_fraction` (the
// two surfaces share a parametrisation, as a fit on fixed knots and its truth do): largest and rms, mm.
struct SurfaceDeviation {
  double max = 0.0, rms = 0.0;
};
[[nodiscard]] SurfaceDeviation surface_deviation(const nurbs::Surface& fit, const nurbs::Surface& truth, int grid,
                                                 double u_fraction = 1.0);

}  // namespace probecomp::testing
