#pragma once
// Least-squares geometric elements, as ISO 10360-6 and ASME B89.4.10 define them for testing CMM software: the
// plane, sphere, cylinder, cone and torus that minimise the sum of squared orthogonal distances of the points
// ("Gaussian" fits). The plane is closed form (the smallest principal direction of the centred points); the others
// are Gauss-Newton on the orthogonal distances (Forbes, NPL Report DITC 140/89, "Least-squares best-fit geometric
// elements"), solved by QR, in coordinates centred on the points so that data far from the origin lose no digits.
// The cone and the torus start from a given element (a part's nominal face offset by the tip): a few points on a
// band of one admit other cones and tori far from it, which no start-free search should pick.

#include <span>

#include "probecomp/geometry/types.hpp"

namespace probecomp::fitting {

enum class ElementFitStatus {
  OK,
  NotConverged,  // Gauss-Newton did not settle within the iteration limit; the last estimate is returned
  Degenerate,    // too few points, or points that do not fix the element (all on a line, a plane for a sphere)
};

[[nodiscard]] const char* to_string(ElementFitStatus s);

struct PlaneFit {
  ElementFitStatus status = ElementFitStatus::Degenerate;
  Point3 point = Point3::Zero();    // the centroid, which the least-squares plane passes through
  Vector3 normal = Vector3::Zero(); // unit; its sign is arbitrary
  double rms = 0.0;                 // root mean square orthogonal distance, mm
};

struct SphereFit {
  ElementFitStatus status = ElementFitStatus::Degenerate;
  Point3 center = Point3::Zero();
  double radius = 0.0;
  double rms = 0.0;
  int iterations = 0;
};

struct CylinderFit {
  ElementFitStatus status = ElementFitStatus::Degenerate;
  Point3 axis_point = Point3::Zero();  // the axis's point nearest the points' centroid
  Vector3 axis = Vector3::Zero();      // unit; its sign is arbitrary
  double radius = 0.0;
  double rms = 0.0;
  int iterations = 0;
};

// The radius at the axis point grows along the axis at the half-angle (negative: it shrinks), as OpenCASCADE's
// cone with its semi-angle.
struct ConeFit {
  ElementFitStatus status = ElementFitStatus::Degenerate;
  Point3 axis_point = Point3::Zero();  // the axis's point nearest the points' centroid
  Vector3 axis = Vector3::UnitZ();     // unit
  double radius = 0.0;                 // at axis_point, mm
  double half_angle = 0.0;             // radians, in (−π/2, π/2)
  double rms = 0.0;
  int iterations = 0;
  int held = 0;                        // combinations of the parameters held at the start's (HoldPoorlyFixed)
};

struct TorusFit {
  ElementFitStatus status = ElementFitStatus::Degenerate;
  Point3 center = Point3::Zero();
  Vector3 axis = Vector3::UnitZ();  // unit; its sign is arbitrary
  double radius = 0.0;              // major: the tube's centre circle
  double minor_radius = 0.0;        // the tube's
  double rms = 0.0;
  int iterations = 0;
  int held = 0;                     // combinations of the parameters held at the start's (HoldPoorlyFixed)
};

// What a cone's or torus's points must fix for a combination of its parameters to be fitted, not held at the
// start's value: its least-squares standard deviation, `sigma` over its singular value (parameters in mm, a tilt
// times the points' size), at most `max_std` (mm). A few touches on a short arc of a fillet trade its major radius
// for its centre's place; started from the nominal, that combination stays the nominal's, and the rest is fitted.
// The default fits every parameter, and points that do not fix them all are Degenerate.
struct HoldPoorlyFixed {
  double sigma = 0.0;    // the points' noise along the normal, mm
  double max_std = 0.0;  // mm
};

// At least 3 points not on one line.
[[nodiscard]] PlaneFit fit_plane(std::span<const Point3> points);
// At least 4 points not on one plane. Starts from the algebraic (linear) sphere fit.
[[nodiscard]] SphereFit fit_sphere(std::span<const Point3> points);
// At least 5 points. Starts from each principal direction of the points in turn as the axis and keeps the best
// converged fit, so a short cylinder or an arc of one needs no guess.
[[nodiscard]] CylinderFit fit_cylinder(std::span<const Point3> points);
// At least 6 and 7 points (their parameters), from `start` (its status, rms and iterations are not read).
// Degenerate when the points do not fix the element: a band too narrow to tell a cone's angle from its radius.
// With `limits`, a combination the points fix too poorly is held at the start's value (HoldPoorlyFixed); the fit is
// then OK even where the points fix none (its `held` says how many).
[[nodiscard]] ConeFit fit_cone(std::span<const Point3> points, const ConeFit& start, const HoldPoorlyFixed& limits = {});
[[nodiscard]] TorusFit fit_torus(std::span<const Point3> points, const TorusFit& start,
                                 const HoldPoorlyFixed& limits = {});

// Signed orthogonal distances, mm: positive on the side away from the axis (cone) or the tube's centre circle
// (torus). The cone's is that from its nappe the axis point is on.
[[nodiscard]] double distance(const ConeFit& cone, const Point3& x);
[[nodiscard]] double distance(const TorusFit& torus, const Point3& x);

}  // namespace probecomp::fitting
