#include "reference_compensation.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "probecomp/cad/locator.hpp"
#include "probecomp/nurbs/closest_point.hpp"
#include "support/reference_smoother.hpp"

namespace probecomp::bench {

namespace {

// The P-spline's spans: about this long (mm), at most kMaxSpans a direction (7 000 points on 60 × 30 spans: a few
// seconds with the adaptive penalties).
constexpr double kSpanLength = 1.5;
constexpr int kMaxSpans = 60;

// The unit normal's derivative along u or v by central differences (the reference's own, not the kernel's
// Weingarten map): a step of 1e-6 of the domain leaves an error far below the fit's.
Vector3 normal_derivative(const nurbs::Surface& S, double u, double v, bool along_u, int outward) {
  const nurbs::Domain d = S.domain();
  const double h = 1e-6 * (along_u ? d.u1 - d.u0 : d.v1 - d.v0);
  const double du = along_u ? h : 0.0, dv = along_u ? 0.0 : h;
  return outward * (nurbs::unit_normal(S, u + du, v + dv).n - nurbs::unit_normal(S, u - du, v - dv).n) / (2.0 * h);
}

}  // namespace

ReferenceScore score_reference(const studies::ShapeCaseResult& s, bool adaptive) {
  ReferenceScore out;
  const nurbs::Surface& S = s.nominal.faces.at(0).surface;
  const int outward = s.cad.material.empty() ? 1 : s.cad.material[0].outward;
  const double r = s.shape.probe_radius;
  const geometry::RigidTransform& T = s.cad.registration.transform;  // CAD to machine
  const geometry::RigidTransform to_cad = T.inverse();
  const nurbs::Domain d = S.domain();
  const double Lu = simulation::length_along(S, true), Lv = simulation::length_along(S, false);

  // Each raw centre's height above the nominal along its normal, at its foot point, in the CAD frame.
  const std::size_t n = s.touches.size();
  std::vector<double> u(n), v(n), ps(n), pt(n), height(n);
  const nurbs::ClosestPointSolver solver(S);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t k) {
    const Point3 x = to_cad * s.touches[k].measured;
    const nurbs::ClosestPointResult foot = solver.closest_point(x);
    u[k] = foot.u;
    v[k] = foot.v;
    ps[k] = (foot.u - d.u0) / (d.u1 - d.u0) * Lu;
    pt[k] = (foot.v - d.v0) / (d.v1 - d.v0) * Lv;
    height[k] = (x - nurbs::evaluate(S, foot.u, foot.v)).dot(outward * nurbs::unit_normal(S, foot.u, foot.v).n);
  });
  reference::SmootherOptions o;
  o.s0 = 0.0;
  o.s1 = Lu;
  o.t0 = 0.0;
  o.t1 = Lv;
  o.spans_s = std::clamp(static_cast<int>(std::ceil(Lu / kSpanLength)), 4, kMaxSpans);
  o.spans_t = std::clamp(static_cast<int>(std::ceil(Lv / kSpanLength)), 4, kMaxSpans);
  o.adaptive = adaptive;
  const reference::SmootherResult fit = reference::smooth(ps, pt, height, o);
  if (fit.status != reference::SmootherStatus::OK) {
    out.std = out.mean = out.max_abs = std::numeric_limits<double>::quiet_NaN();
    return out;
  }
  out.log10_lambda_s = std::log10(fit.lambda_s);
  out.log10_lambda_t = std::log10(fit.lambda_t);
  out.edf = fit.edf;

  // The smoothed centre X = S + f·n at each point's foot, its normal from X_u × X_v, and the contact X − r·N.
  std::vector<Point3> contacts(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t k) {
    const reference::SmootherValue f = reference::evaluate(fit, ps[k], pt[k]);
    const nurbs::SurfaceD1 D = nurbs::derivatives_d1(S, u[k], v[k]);
    const Vector3 nn = outward * nurbs::unit_normal(S, u[k], v[k]).n;
    const double fu = f.ds * Lu / (d.u1 - d.u0), fv = f.dt * Lv / (d.v1 - d.v0);
    const Vector3 Xu = D.Su + fu * nn + f.value * normal_derivative(S, u[k], v[k], true, outward);
    const Vector3 Xv = D.Sv + fv * nn + f.value * normal_derivative(S, u[k], v[k], false, outward);
    Vector3 N = Xu.cross(Xv).normalized();
    if (N.dot(nn) < 0.0) N = -N;
    contacts[k] = T * (D.S + f.value * nn - r * N);
  });

  // Scored where the product trusted the row, against the same actual part.
  const cad::Model actual = simulation::actual_model(s.nominal, simulation::deformation_of(s.shape, s.nominal),
                                                     s.shape.placement());
  const cad::ModelLocator locator(actual);
  std::vector<double> errors(n, std::numeric_limits<double>::quiet_NaN());
  std::vector<Point3> scored;
  std::vector<std::size_t> index;
  for (std::size_t k = 0; k < n; ++k) {
    if (s.cad.points[k].status != compensation::PointStatus::Ok) continue;
    scored.push_back(contacts[k]);
    index.push_back(k);
  }
  const std::vector<cad::ModelPoint> feet = locator.closest_points(scored);
  for (std::size_t i = 0; i < feet.size(); ++i) {
    if (feet[i].ok()) errors[index[i]] = feet[i].distance;
  }
  const studies::ErrorSummary e = studies::summarise(errors);
  out.points = e.points;
  out.std = e.std;
  out.mean = e.mean;
  out.max_abs = e.max_abs();
  return out;
}

}  // namespace probecomp::bench
