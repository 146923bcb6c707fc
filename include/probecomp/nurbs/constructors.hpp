#pragma once
// Exact NURBS representations of simple shapes (The NURBS Book, ch. 7 and 8).

#include "probecomp/nurbs/curve.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::nurbs {

// The plane patch S(u,v) = origin + u·a + v·b for (u,v) in [0,1]², exactly, with degrees (p, q) and
// (spans_u, spans_v) uniform spans: control points at the Greville abscissae reproduce a linear
// parametrisation exactly (linear precision of B-splines).
[[nodiscard]] Surface make_plane_patch(const Point3& origin, const Vector3& a, const Vector3& b, int p = 1,
                                       int q = 1, int spans_u = 1, int spans_v = 1);

// A7.1: the circular arc of radius r about `center` in the plane of the orthonormal pair (x_axis, y_axis),
// from angle `start` to `end` (radians, end > start, sweep at most 2π), as a rational quadratic with
// one segment per 90° or less; interior weights cos(Δθ/2). Parameter domain [0, 1] (not arc length).
[[nodiscard]] Curve make_circular_arc(const Point3& center, const Vector3& x_axis, const Vector3& y_axis, double r,
                                      double start, double end);

// A section of a circular cylinder: the arc of make_circular_arc in u (rational quadratic, unequal weights),
// a straight line of length `height` along axis = x_axis × y_axis in v (degree 1). Domain [0,1]².
// S_u × S_v points away from the axis.
[[nodiscard]] Surface make_cylinder_section(const Point3& center, const Vector3& x_axis, const Vector3& y_axis,
                                            double r, double start, double end, double height);

// A8.1 in effect: `profile` swept about the axis through `axis_point` along `axis_dir`, from angle `start` to
// `end` (radians about axis_dir, measured from the direction in which the profile lies off the axis). u: the
// circular direction (make_circular_arc's knots and weights, times the profile's weight), v: the profile's.
// The profile must lie in one half-plane bounded by the axis; a control point on the axis stays there (a pole,
// as at a sphere's ends). Throws InvalidGeometry otherwise.
[[nodiscard]] Surface make_revolved_surface(const Curve& profile, const Point3& axis_point, const Vector3& axis_dir,
                                            double start, double end);

// The whole sphere about `center`: a half circle from the pole −axis to +axis revolved once about `axis`.
// S_u × S_v points outwards.
[[nodiscard]] Surface make_sphere(const Point3& center, const Vector3& axis, double radius);

// The whole torus: the tube circle of radius `minor` at distance `major` > `minor` from the axis, revolved once.
// S_u × S_v points outwards (away from the tube's centre circle).
[[nodiscard]] Surface make_torus(const Point3& center, const Vector3& axis, double major, double minor);

}  // namespace probecomp::nurbs
