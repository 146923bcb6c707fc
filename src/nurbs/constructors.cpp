#include "probecomp/nurbs/constructors.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace probecomp::nurbs {

Surface make_plane_patch(const Point3& origin, const Vector3& a, const Vector3& b, int p, int q, int spans_u,
                         int spans_v) {
  KnotVector U = KnotVector::uniform(p, spans_u);
  KnotVector V = KnotVector::uniform(q, spans_v);
  std::vector<Point3> P;
  P.reserve(static_cast<std::size_t>(U.num_basis()) * V.num_basis());
  for (int i = 0; i < U.num_basis(); ++i)
    for (int j = 0; j < V.num_basis(); ++j) P.push_back(origin + U.greville(i) * a + V.greville(j) * b);
  return Surface(std::move(U), std::move(V), P);
}

Curve make_circular_arc(const Point3& center, const Vector3& x_axis, const Vector3& y_axis, double r, double start,
                        double end) {
  if (!(r > 0.0)) throw InvalidGeometry("circular arc: the radius must be positive");
  if (!(end > start) || end - start > 2.0 * std::numbers::pi + 1e-12) {
    throw InvalidGeometry("circular arc: the sweep must be in (0, 2π]");
  }
  const Vector3 X = x_axis.normalized();
  const Vector3 Y = y_axis.normalized();
  const double theta = end - start;
  const int narcs = static_cast<int>(std::ceil(theta / (std::numbers::pi / 2.0) - 1e-12));
  const double dtheta = theta / narcs;
  const double w1 = std::cos(dtheta / 2.0);

  std::vector<Point3> P(static_cast<std::size_t>(2 * narcs + 1));
  std::vector<double> w(P.size());
  auto on_circle = [&](double a) { return Point3(center + r * std::cos(a) * X + r * std::sin(a) * Y); };
  auto tangent = [&](double a) { return Vector3(-std::sin(a) * X + std::cos(a) * Y); };
  P[0] = on_circle(start);
  w[0] = 1.0;
  double angle = start;
  for (int k = 1; k <= narcs; ++k) {
    const double a0 = angle;
    angle = start + k * dtheta;
    const Point3 P0 = P[2 * k - 2];
    const Point3 P2 = on_circle(angle);
    // The middle control point is where the end tangents meet: at distance r / cos(Δθ/2) from the centre.
    const Vector3 T0 = tangent(a0);
    const Point3 P1 = P0 + T0 * (r * std::tan(dtheta / 2.0));
    P[2 * k - 1] = P1;
    w[2 * k - 1] = w1;
    P[2 * k] = P2;
    w[2 * k] = 1.0;
  }
  std::vector<double> knots;
  knots.insert(knots.end(), 3, 0.0);
  for (int k = 1; k < narcs; ++k) knots.insert(knots.end(), 2, static_cast<double>(k) / narcs);
  knots.insert(knots.end(), 3, 1.0);
  return Curve(KnotVector(std::move(knots), 2), P, w);
}

Surface make_cylinder_section(const Point3& center, const Vector3& x_axis, const Vector3& y_axis, double r,
                              double start, double end, double height) {
  if (!(height > 0.0)) throw InvalidGeometry("cylinder section: the height must be positive");
  const Curve arc = make_circular_arc(center, x_axis, y_axis, r, start, end);
  const Vector3 axis = x_axis.normalized().cross(y_axis.normalized());
  const int n = arc.num_control_points();
  std::vector<Point3> P;
  std::vector<double> w;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < 2; ++j) {
      P.push_back(arc.control_point(i) + j * height * axis);
      w.push_back(arc.weight(i));
    }
  }
  // S_u is the arc's tangent (counter-clockwise about axis), S_v = height·axis, so S_u × S_v is radial outwards.
  return Surface(arc.knots(), KnotVector::uniform(1, 1), P, w);
}

namespace {

// A unit vector perpendicular to `a`.
Vector3 perpendicular_to(const Vector3& a) {
  const Vector3 trial = std::abs(a.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY();
  return a.cross(trial).normalized();
}

}  // namespace

Surface make_revolved_surface(const Curve& profile, const Point3& axis_point, const Vector3& axis_dir, double start,
                              double end) {
  const Vector3 a = axis_dir.normalized();
  if (!a.allFinite()) throw InvalidGeometry("revolved surface: the axis direction is zero");
  const int m = profile.num_control_points();
  // The half-plane of the profile: the radial direction of its control point farthest from the axis. A point
  // nearer the axis than this (relative to the profile's size) is on it.
  Vector3 X = Vector3::Zero();
  double reach = 0.0;
  for (int j = 0; j < m; ++j) {
    const Vector3 d = profile.control_point(j) - axis_point;
    const Vector3 radial = d - d.dot(a) * a;
    if (radial.norm() > reach) {
      reach = radial.norm();
      X = radial / reach;
    }
  }
  if (!(reach > 0.0)) throw InvalidGeometry("revolved surface: the profile lies on the axis");
  const double on_axis = 1e-12 * reach;
  const Vector3 Y = a.cross(X);
  // The arc's knots and weights are the same at every radius: from a unit arc.
  const Curve unit = make_circular_arc(Point3::Zero(), X, Y, 1.0, start, end);
  const int n = unit.num_control_points();
  std::vector<Point3> P(static_cast<std::size_t>(n) * m);
  std::vector<double> w(P.size());
  for (int j = 0; j < m; ++j) {
    const Vector3 d = profile.control_point(j) - axis_point;
    const Point3 O = axis_point + d.dot(a) * a;
    const Vector3 radial = d - d.dot(a) * a;
    const double r = radial.dot(X);
    if ((radial - r * X).norm() > on_axis || r < -on_axis) {
      throw InvalidGeometry("revolved surface: the profile must lie in one half-plane bounded by the axis");
    }
    for (int i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(i) * m + j;
      // The unit arc's control points scaled about the axis (a pole stays at O).
      P[k] = O + std::max(r, 0.0) * (unit.control_point(i) - Point3::Zero());
      w[k] = unit.weight(i) * profile.weight(j);
    }
  }
  return Surface(unit.knots(), profile.knots(), P, w);
}

Surface make_sphere(const Point3& center, const Vector3& axis, double radius) {
  if (!(radius > 0.0)) throw InvalidGeometry("sphere: the radius must be positive");
  const Vector3 a = axis.normalized();
  const Vector3 X = perpendicular_to(a);
  // From the south pole up: with u counter-clockwise about a, S_u × S_v then points outwards.
  const Curve half = make_circular_arc(center, X, a, radius, -std::numbers::pi / 2.0, std::numbers::pi / 2.0);
  return make_revolved_surface(half, center, a, 0.0, 2.0 * std::numbers::pi);
}

Surface make_torus(const Point3& center, const Vector3& axis, double major, double minor) {
  if (!(minor > 0.0) || !(major > minor)) throw InvalidGeometry("torus: needs 0 < minor radius < major radius");
  const Vector3 a = axis.normalized();
  const Vector3 X = perpendicular_to(a);
  const Curve tube = make_circular_arc(center + major * X, X, a, minor, 0.0, 2.0 * std::numbers::pi);
  return make_revolved_surface(tube, center, a, 0.0, 2.0 * std::numbers::pi);
}

}  // namespace probecomp::nurbs
