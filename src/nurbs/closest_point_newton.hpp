#pragma once
// The closest point's local Newton iteration (closest_point_newton.cpp), as the solver (closest_point.cpp) uses it:
// projected Newton inside a domain or a cell, and how flat the distance is at a point. Private to nurbs/.

#include "probecomp/nurbs/closest_point.hpp"

namespace probecomp::nurbs::detail {

struct Iterate {
  double u, v;
  SurfaceD2 d;
  Vector3 r;  // S − P
  double f;   // |S − P|²
  bool approximate = false;  // the derivatives are stored ones, rounded to floats (S is exact): good for a step only
};

// The surface and its derivatives at (u, v), with f = |S − P|² (spans as for derivatives_d2).
Iterate make_iterate(const Surface& s, const Point3& P, double u, double v, KnotSpans spans);

// The Hessian of f: J = JᵀJ (Gauss–Newton part, tangents' dot products) and H = J + (S − P)·S''.
struct Hessian {
  double Juu, Juv, Jvv, Huu, Huv, Hvv;
};

[[gnu::always_inline]] inline Hessian hessian(const Iterate& it) {
  const auto& d = it.d;
  const double Juu = d.Su.dot(d.Su), Juv = d.Su.dot(d.Sv), Jvv = d.Sv.dot(d.Sv);
  return {Juu, Juv, Jvv, Juu + it.r.dot(d.Suu), Juv + it.r.dot(d.Suv), Jvv + it.r.dot(d.Svv)};
}

// How flat f is: 1 for a plane, towards 0 near a centre of curvature (closest_point_newton.cpp).
double flatness(const Hessian& h);

// Projected Newton inside `dom` from (u0, v0); `spans`, `flat` and `start` as closest_point_newton.cpp describes.
ClosestPointResult refine_in(const Surface& s, const Point3& P, double u0, double v0, const Domain& dom,
                             int max_iterations, KnotSpans spans, double* flat = nullptr,
                             const SurfaceD2* start = nullptr);

}  // namespace probecomp::nurbs::detail
