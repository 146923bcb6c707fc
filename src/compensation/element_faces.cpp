#include "element_faces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "probecomp/fitting/elements.hpp"
#include "probecomp/geometry/statistics.hpp"

namespace probecomp::compensation::detail {

namespace {

// A centre this many robust scales (1.4826 × MAD) of the element's residuals off it is left out: a gross error
// (a touch on a burr, a chip) would tilt a plane fitted to ten points. Among ten Gaussian residuals, one beyond 5
// scales has odds below 1 in 10^5.
constexpr double kElementOutlierScales = 5.0;
// The element must be the nominal's, moved by the part's own form and the registration's error, not another shape:
// its axis (a plane's normal) within this angle of the nominal's, and a cylinder's or sphere's radius within
// kMaxRadiusChange of the nominal's offset by the tip (a hole's centres lie at R − r, a pin's at R + r).
constexpr double kMaxElementTilt = 3.0 * std::numbers::pi / 180.0;
constexpr double kMaxRadiusChange = 0.1;  // mm
// A combination of a cone's or torus's parameters is fitted where the points fix it to this standard deviation (mm),
// and held at the nominal's where they do not (fitting::HoldPoorlyFixed): a move of 4 σ then stays within
// kMaxRadiusChange. Twelve touches on a short arc of a fillet fix its major radius and its centre's place together,
// not apart (CTC-04: fits that moved the radius 0.2–0.26 mm and were refused before).
constexpr double kMaxFittedStd = kMaxRadiusChange / 4.0;

// A face whose residuals' χ² against the pooled noise is beyond the quantile that noise alone exceeds with this
// probability is left out of the pool (element_face_noise). One in a hundred: on noise alone, a part of 60 element
// faces has one left out every other time, and that face keeps its own (then larger) estimate: on the safe side.
constexpr double kFormErrorFalseAlarm = 0.01;
// The pool's degrees of freedom from which it is preferred to the NURBS-fitted faces' estimate: its σ is then
// within 10 % (1 / √(2ν), one standard deviation).
constexpr double kMinPooledDegrees = 50.0;
// Leaving a face out lowers the pooled noise, which may show another face's form error: at most this many rounds.
constexpr int kMaxPoolingRounds = 4;

// The scale is not taken below this (mm): on exact data the residuals are rounding, and every point would stand out.
constexpr double kScaleFloor = 1e-4;

struct Fitted {
  ElementFaceFit e;
  bool ok = false;
};

// The element as ElementFaceFit holds it: the fit's status, point, axis (a plane's normal), radius and rms.
Fitted as_element(cad::ElementaryKind kind, fitting::ElementFitStatus status, const Point3& point, const Vector3& axis,
                  double radius, double rms, int parameters, std::size_t used) {
  Fitted out;
  out.ok = status == fitting::ElementFitStatus::OK;
  out.e = {.kind = kind, .point = point, .axis = axis, .radius = radius, .rms = rms, .used = static_cast<int>(used),
           .parameters = parameters};
  return out;
}

fitting::ConeFit as_cone(const ElementFaceFit& e) {
  return {.status = fitting::ElementFitStatus::OK, .axis_point = e.point, .axis = e.axis, .radius = e.radius,
          .half_angle = e.half_angle};
}

fitting::TorusFit as_torus(const ElementFaceFit& e) {
  return {.status = fitting::ElementFitStatus::OK, .center = e.point, .axis = e.axis, .radius = e.radius,
          .minor_radius = e.minor_radius};
}

// The surface the face's tip centres lie on when the part is as its nominal: the face offset by r along its outward
// normal, in the machine frame. The start of a cone's or torus's fit, and what every fit is checked against.
std::optional<ElementFaceFit> centres_element(const cad::Face& face, const geometry::RigidTransform& to_machine,
                                              double r) {
  const std::optional<cad::ElementarySurface> offset = face.analytic->offset_surface(face.outward * r);
  if (!offset) return std::nullopt;  // a hole or fillet tighter than the tip
  const cad::ElementarySurface& s = *offset;
  ElementFaceFit e;
  e.kind = s.kind;
  e.point = to_machine * s.origin;
  e.axis = to_machine.linear() * s.z;
  e.radius = s.radius;
  e.half_angle = s.half_angle;
  e.minor_radius = s.minor_radius;
  return e;
}

Fitted fit_kind(cad::ElementaryKind kind, std::span<const Point3> pts, const ElementFaceFit& start, double noise) {
  const fitting::HoldPoorlyFixed limits{.sigma = std::max(noise, kScaleFloor), .max_std = kMaxFittedStd};
  Fitted out;
  if (kind == cad::ElementaryKind::Plane) {
    const fitting::PlaneFit f = fitting::fit_plane(pts);
    out = as_element(kind, f.status, f.point, f.normal, 0.0, f.rms, 3, pts.size());
  } else if (kind == cad::ElementaryKind::Cylinder) {
    const fitting::CylinderFit f = fitting::fit_cylinder(pts);
    out = as_element(kind, f.status, f.axis_point, f.axis, f.radius, f.rms, 5, pts.size());
  } else if (kind == cad::ElementaryKind::Sphere) {
    const fitting::SphereFit f = fitting::fit_sphere(pts);
    out = as_element(kind, f.status, f.center, Vector3::Zero(), f.radius, f.rms, 4, pts.size());
  } else if (kind == cad::ElementaryKind::Cone) {
    const fitting::ConeFit f = fitting::fit_cone(pts, as_cone(start), limits);
    out = as_element(kind, f.status, f.axis_point, f.axis, f.radius, f.rms, 6 - f.held, pts.size());
    out.e.half_angle = f.half_angle;
    out.e.held = f.held;
  } else if (kind == cad::ElementaryKind::Torus) {
    const fitting::TorusFit f = fitting::fit_torus(pts, as_torus(start), limits);
    out = as_element(kind, f.status, f.center, f.axis, f.radius, f.rms, 7 - f.held, pts.size());
    out.e.minor_radius = f.minor_radius;
    out.e.held = f.held;
  }
  // At least one degree of freedom more than the element has: else the fit passes through the points and says
  // nothing of the noise.
  out.ok = out.ok && out.e.used > out.e.parameters;
  return out;
}

// Whether the fitted element is the nominal one offset by r (`nominal`, centres_element): see kMaxElementTilt.
bool like_nominal(const ElementFaceFit& e, const ElementFaceFit& nominal) {
  if (e.kind != cad::ElementaryKind::Sphere && std::abs(e.axis.dot(nominal.axis)) < std::cos(kMaxElementTilt)) {
    return false;
  }
  switch (e.kind) {
    case cad::ElementaryKind::Plane: return true;
    case cad::ElementaryKind::Cone: {
      // The nominal's radius at the height of the fitted cone's axis point.
      const double h = (e.point - nominal.point).dot(nominal.axis);
      return std::abs(e.half_angle - nominal.half_angle) <= kMaxElementTilt &&
             std::abs(e.radius - (nominal.radius + h * std::tan(nominal.half_angle))) <= kMaxRadiusChange;
    }
    case cad::ElementaryKind::Torus:
      return std::abs(e.radius - nominal.radius) <= kMaxRadiusChange &&
             std::abs(e.minor_radius - nominal.minor_radius) <= kMaxRadiusChange;
    default: return std::abs(e.radius - nominal.radius) <= kMaxRadiusChange;  // cylinder, sphere
  }
}

// A face's own noise along the normal: its residuals' rms with the element's parameters' share of the degrees of
// freedom given back (√(n / (n − k))); infinity with no degree of freedom left.
double element_noise(const ElementFaceFit& e) {
  if (e.used <= e.parameters) return std::numeric_limits<double>::infinity();
  return e.rms * std::sqrt(static_cast<double>(e.used) / static_cast<double>(e.used - e.parameters));
}

}  // namespace

std::optional<ElementFaceFit> fit_element_face(const cad::Face& face, std::span<const Point3> centres,
                                               const geometry::RigidTransform& to_machine, double r, double noise,
                                               std::vector<char>& outlier) {
  if (!face.analytic || centres.empty()) return std::nullopt;
  const cad::ElementaryKind kind = face.analytic->surface().kind;
  const std::optional<ElementFaceFit> nominal = centres_element(face, to_machine, r);
  if (!nominal) return std::nullopt;
  outlier.assign(centres.size(), 0);
  Fitted all = fit_kind(kind, centres, *nominal, noise);
  if (!all.ok || !like_nominal(all.e, *nominal)) {
    outlier.assign(centres.size(), 0);
    return std::nullopt;
  }
  std::vector<double> off(centres.size());
  for (std::size_t k = 0; k < centres.size(); ++k) off[k] = std::abs(element_distance(all.e, centres[k]));
  std::vector<double> work = off;
  const double scale = std::max(geometry::kMadToSigma * geometry::median_in_place(work), kScaleFloor);
  std::vector<Point3> kept;
  for (std::size_t k = 0; k < centres.size(); ++k) {
    outlier[k] = off[k] > kElementOutlierScales * scale;
    if (!outlier[k]) kept.push_back(centres[k]);
  }
  if (kept.size() == centres.size()) return all.e;
  Fitted again = fit_kind(kind, kept, *nominal, noise);
  if (!again.ok || !like_nominal(again.e, *nominal)) {
    outlier.assign(centres.size(), 0);
    return all.e;
  }
  return again.e;
}

double element_distance(const ElementFaceFit& e, const Point3& x) {
  switch (e.kind) {
    case cad::ElementaryKind::Plane: return e.axis.dot(x - e.point);
    case cad::ElementaryKind::Cylinder: {
      const Vector3 d = x - e.point;
      return (d - d.dot(e.axis) * e.axis).norm() - e.radius;
    }
    case cad::ElementaryKind::Sphere: return (x - e.point).norm() - e.radius;
    case cad::ElementaryKind::Cone: return fitting::distance(as_cone(e), x);
    case cad::ElementaryKind::Torus: return fitting::distance(as_torus(e), x);
    default: return 0.0;
  }
}

Vector3 element_normal(const ElementFaceFit& e, const Point3& x, const Vector3& towards) {
  Vector3 n = e.axis;
  if (e.kind == cad::ElementaryKind::Cylinder) {
    const Vector3 d = x - e.point;
    n = d - d.dot(e.axis) * e.axis;
  } else if (e.kind == cad::ElementaryKind::Sphere) {
    n = x - e.point;
  } else if (e.kind == cad::ElementaryKind::Cone || e.kind == cad::ElementaryKind::Torus) {
    const Vector3 d = x - e.point;
    const double h = d.dot(e.axis);
    const Vector3 radial = (d - h * e.axis).normalized();
    // The cone's distance (ρ − r − h tan α) cos α grows along cos α ρ̂ − sin α a; the torus's away from the tube's
    // centre circle.
    if (e.kind == cad::ElementaryKind::Cone) {
      n = std::cos(e.half_angle) * radial - std::sin(e.half_angle) * e.axis;
    } else {
      n = x - (e.point + e.radius * radial);
    }
  }
  if (!(n.norm() > 0.0)) return towards.normalized();
  n.normalize();
  return n.dot(towards) < 0.0 ? Vector3(-n) : n;
}

ElementNoise element_face_noise(std::span<const ElementFaceFit* const> faces, std::optional<double> fitted_noise) {
  const double none = std::numeric_limits<double>::infinity();
  auto degrees = [](const ElementFaceFit& e) { return static_cast<double>(e.used - e.parameters); };
  auto rss = [](const ElementFaceFit& e) { return e.rms * e.rms * static_cast<double>(e.used); };
  std::vector<char> pooled(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    pooled[i] = faces[i]->used > faces[i]->parameters && std::isfinite(faces[i]->rms);
  }
  double sum = 0.0, dof = 0.0;
  for (int round = 0;; ++round) {
    sum = 0.0;
    dof = 0.0;
    for (std::size_t i = 0; i < faces.size(); ++i) {
      if (!pooled[i]) continue;
      sum += rss(*faces[i]);
      dof += degrees(*faces[i]);
    }
    if (!(dof > 0.0) || !(sum > 0.0) || round == kMaxPoolingRounds) break;
    // Each face against the pool of the others, so that one large face's form error does not raise the noise it is
    // tested against; never below the floor, where exact data's rounding differs from face to face.
    auto explained = [&](const ElementFaceFit& e) {
      const double others = dof - degrees(e);
      const double variance = others > 0.0 ? (sum - rss(e)) / others : sum / dof;
      return rss(e) / std::max(variance, kScaleFloor * kScaleFloor) <=
             geometry::chi2_upper_quantile(degrees(e), kFormErrorFalseAlarm);
    };
    bool changed = false;
    for (std::size_t i = 0; i < faces.size(); ++i) {
      if (pooled[i] && !explained(*faces[i])) {
        pooled[i] = 0;
        changed = true;
      }
    }
    if (!changed) break;
  }
  // Exact data: the residuals are rounding, and u is not claimed below what a CMM resolves.
  ElementNoise out{.pooled = dof > 0.0 ? std::max(std::sqrt(sum / dof), kScaleFloor) : none};
  out.shared = dof >= kMinPooledDegrees || !fitted_noise ? out.pooled : std::max(*fitted_noise, kScaleFloor);
  const double shared = out.shared;
  out.face.assign(faces.size(), shared);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const double own = element_noise(*faces[i]);
    if (!pooled[i] && std::isfinite(own)) out.face[i] = std::isfinite(shared) ? std::max(own, shared) : own;
  }
  return out;
}

}  // namespace probecomp::compensation::detail
