#include "probecomp/simulation/deformation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "probecomp/fitting/offset.hpp"
#include "probecomp/fitting/spans.hpp"
#include "probecomp/nurbs/degree_elevation.hpp"
#include "probecomp/error.hpp"

namespace probecomp::simulation {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Displacements below this (mm) are not worth knots: a thousandth of a nanometre.
constexpr double kNegligible = 1e-9;
// How closely the actual surface follows nominal + displacement (mm): far below any CMM's noise. The actual
// NURBS is the truth the simulated probe touches, so this only bounds how far it is from the intended shape.
constexpr double kDeformedSurfaceTolerance = 1e-5;

// Distance from a Gaussian's centre beyond which a·exp(−r²/2w²) is negligible.
double reach(double amplitude, double width) {
  const double ratio = std::abs(amplitude) / kNegligible;
  return ratio <= 1.0 ? 0.0 : width * std::sqrt(2.0 * std::log(ratio));
}

double gaussian(const Point3& x, const Point3& c, double w) { return std::exp(-(x - c).squaredNorm() / (2.0 * w * w)); }

// A sinusoid's window at x: radial about its origin, or over the distance along its band direction.
double window(const Sinusoid& s, const Point3& x) {
  if (!(s.window > 0.0)) return 1.0;
  if (s.band.squaredNorm() == 0.0) return gaussian(x, s.origin, s.window);
  const double a = s.band.normalized().dot(x - s.origin);
  return std::exp(-a * a / (2.0 * s.window * s.window));
}

double window_distance(const Sinusoid& s, const Point3& x) {
  return s.band.squaredNorm() == 0.0 ? (x - s.origin).norm() : std::abs(s.band.normalized().dot(x - s.origin));
}

// Distance from a crease's plane beyond which its curvature is negligible: tanh's derivatives fall as
// e^(−4|a|/w), so h·e^(−4|a|/w) < kNegligible.
double crease_reach(const Crease& c) {
  const double ratio = std::abs(c.height) / kNegligible;
  return ratio <= 1.0 ? 0.0 : 0.25 * c.width * std::log(ratio);
}

// Knots to insert in one direction so that every span is short enough for the deformation. `samples` are the
// surface's points on a grid of `per_span` parameters per span (plus the end) along this direction (index a)
// by `rows` along the other (index b): point (a, b) at samples[a * rows + b].
std::vector<double> refining_knots(const std::vector<double>& breaks, int per_span, const std::vector<Point3>& samples,
                                   int rows, const Deformation& d) {
  std::vector<double> X;
  for (std::size_t s = 0; s + 1 < breaks.size(); ++s) {
    int pieces = 1;
    for (int b = 0; b < rows; ++b) {
      double length = 0.0, feature = kInfinity;
      for (int k = 0; k <= per_span; ++k) {
        const std::size_t a = s * static_cast<std::size_t>(per_span) + static_cast<std::size_t>(k);
        const Point3& x = samples[a * static_cast<std::size_t>(rows) + static_cast<std::size_t>(b)];
        feature = std::min(feature, d.feature_length(x));
        if (k > 0) length += (x - samples[(a - 1) * static_cast<std::size_t>(rows) + static_cast<std::size_t>(b)]).norm();
      }
      if (std::isfinite(feature)) {
        pieces = std::max(pieces, static_cast<int>(std::ceil(length * kSpansPerFeature / feature)));
      }
    }
    for (int k = 1; k < pieces; ++k) X.push_back(breaks[s] + (breaks[s + 1] - breaks[s]) * k / pieces);
  }
  return X;
}

}  // namespace

double Deformation::displacement(const Point3& x) const {
  double d = 0.0;
  for (const Bump& b : bumps) d += b.amplitude * gaussian(x, b.centre, b.width);
  for (const Sinusoid& s : sinusoids) {
    const double phase = 2.0 * std::numbers::pi * s.direction.normalized().dot(x - s.origin) / s.wavelength +
                         s.phase * std::numbers::pi / 180.0;
    d += s.amplitude * std::sin(phase) * window(s, x);
  }
  for (const Crease& c : creases) {
    d += c.height * 0.5 * (1.0 + std::tanh(2.0 * c.direction.normalized().dot(x - c.origin) / c.width));
  }
  for (const Twist& t : twists) {
    d += t.amplitude * t.first.normalized().dot(x - t.origin) * t.second.normalized().dot(x - t.origin) /
         (t.length * t.length);
  }
  return d;
}

double Deformation::feature_length(const Point3& x) const {
  double length = kInfinity;
  for (const Bump& b : bumps) {
    if ((x - b.centre).norm() <= reach(b.amplitude, b.width)) length = std::min(length, b.width);
  }
  for (const Sinusoid& s : sinusoids) {
    if (s.window > 0.0 && window_distance(s, x) > reach(s.amplitude, s.window)) continue;
    length = std::min(length, s.wavelength / 4.0);
    if (s.window > 0.0) length = std::min(length, s.window);
  }
  // A step rising over w changes its curvature over about w/2; a twist is a quadratic the nominal's knots take as
  // they are (the displaced surface's own refinement meets its tolerance).
  for (const Crease& c : creases) {
    if (std::abs(c.direction.normalized().dot(x - c.origin)) <= crease_reach(c)) length = std::min(length, 0.5 * c.width);
  }
  return length;
}

nurbs::Surface deformed_surface(const nurbs::Surface& s, int outward, const Deformation& d) {
  if (d.empty()) return s;
  // Eight samples per span resolve a span's length along a row to well under a per cent.
  constexpr int kPerSpan = 8;
  // A degree-1 direction (planes, a cylinder's rulings) would stay piecewise linear, with creases at the new
  // knots: cubic first.
  nurbs::Surface refined = s;
  if (refined.p() < 2) refined = nurbs::elevate_degree_u(refined, 3 - refined.p());
  if (refined.q() < 2) refined = nurbs::elevate_degree_v(refined, 3 - refined.q());
  for (int direction = 0; direction < 2; ++direction) {
    const std::vector<double> breaks_u = refined.U().breakpoints();
    const std::vector<double> breaks_v = refined.V().breakpoints();
    const std::vector<double> tu = fitting::span_parameters(breaks_u, kPerSpan);
    const std::vector<double> tv = fitting::span_parameters(breaks_v, kPerSpan);
    const bool along_u = direction == 0;
    const std::vector<double>& ta = along_u ? tu : tv;
    const std::vector<double>& tb = along_u ? tv : tu;
    std::vector<Point3> samples;
    samples.reserve(ta.size() * tb.size());
    for (double a : ta) {
      for (double b : tb) samples.push_back(nurbs::evaluate(refined, along_u ? a : b, along_u ? b : a));
    }
    const std::vector<double> X =
        refining_knots(along_u ? breaks_u : breaks_v, kPerSpan, samples, static_cast<int>(tb.size()), d);
    if (!X.empty()) refined = along_u ? nurbs::refine_knots_u(refined, X) : nurbs::refine_knots_v(refined, X);
  }
  // The actual surface fits nominal + displacement on the refined knots (least squares, knots inserted where it
  // misses): a smooth surface, also across the knots where the nominal is only C0 in parameter but smooth in
  // shape (a rational arc's double knot), which moving each control point by the displacement would crease.
  const fitting::OffsetResult fit = fitting::displaced_surface(
      refined, [&](const Point3& x) { return static_cast<double>(outward) * d.displacement(x); },
      {.tolerance = kDeformedSurfaceTolerance, .samples_per_span = 3, .checks_per_span = 8, .max_rounds = 8});
  if (fit.status == fitting::OffsetResult::Status::Degenerate) {
    throw InputError("deformed surface: the face has no normal somewhere, so it cannot be displaced along it");
  }
  return fit.surface;
}

}  // namespace probecomp::simulation
