// compensate_points: each raw centre's contact point, normal, deviation and uncertainty.

#include "contact_points.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "probecomp/compensation/contact.hpp"
#include "probecomp/geometry/statistics.hpp"
#include "probecomp/nurbs/closest_point.hpp"
#include "probecomp/registration/constraints.hpp"

#include "element_faces.hpp"
#include "warnings.hpp"

namespace probecomp::compensation {

namespace detail {

Point3 as_smallest_tip(const PreparedModel& prepared, const registration::RegistrationResult& registration,
                       std::span<const Point3> raw, std::size_t k, const nurbs::Surface* fit,
                       int outward, fitting::SurfaceParameter at) {
  const geometry::TipRadii& radii = prepared.radii;
  if (radii.uniform() || radii[k] == radii.smallest()) return raw[k];
  Vector3 normal = Vector3::Zero();
  if (fit != nullptr) {
    const nurbs::UnitNormal n = nurbs::unit_normal(*fit, at.u, at.v);
    if (n.status != nurbs::UnitNormal::Status::Degenerate) normal = static_cast<double>(outward) * n.n;
  }
  if (normal == Vector3::Zero()) {
    const registration::PointMatch& m = registration.matches[k];
    normal = registration.transform.linear() * prepared.nominal_locator->outward_normal(m.face, m.u, m.v);
  }
  return raw[k] - (radii[k] - radii.smallest()) * normal;
}

}  // namespace detail

namespace {

using detail::as_smallest_tip;
using detail::element_distance;
using detail::element_normal;
using detail::normal_doubt;

// The distance of x from its foot point on `face`, + on the outward side. Only the side is taken from the normal,
// so Newton's own tangents serve where it gives them and they are not (nearly) parallel: one evaluation fewer a
// point (a million deviations: 2 evaluations each instead of 3).
double signed_distance(const cad::Face& face, const Point3& x, const nurbs::ClosestPointResult& foot) {
  Vector3 n = foot.Su.cross(foot.Sv);
  if (!(n.norm() > 1e-8 * foot.Su.norm() * foot.Sv.norm())) n = nurbs::unit_normal(face.surface, foot.u, foot.v).n;
  const double side = (x - foot.point).dot(static_cast<double>(face.outward) * n);
  return side < 0.0 ? -foot.distance : foot.distance;
}

// A correspondence as the hint of a search on the nominal model (which shares the offset model's faces and
// parametrisation).
cad::ModelPoint match_as_hint(const registration::PointMatch& m) {
  cad::ModelPoint hint;
  hint.status = m.status;
  hint.face = m.face;
  hint.u = m.u;
  hint.v = m.v;
  return hint;
}

// The contact of a tip whose centre `raw` (machine frame; `x` in the CAD frame) touched the nominal part where it is
// nearest: towards that point `foot`, from a centre inside the material too (a face whose material side is wrong:
// surf128's face 2, whose contacts were put 2r away, on the far side of the centre), as its deviation says.
Point3 contact_towards(const Point3& raw, double r, const geometry::RigidTransform& T, const Point3& x,
                       const cad::ModelPoint& foot) {
  return raw - r * (T.linear() * (x - foot.point).normalized());
}

// A fitted row whose contact normal is turned more than this (degrees) from the nominal part's normal at its
// correspondence: no deformation of a part measured against its CAD model tilts its surface that far (the shape
// suite's steepest dents: 26°), so the fit has followed something else there. On surf128's narrow end, where the
// face's radius offset folds over and is millimetres off, the fit turned inside out: contacts 2 mm off at a u of
// 34–90 µm. Such a row's u holds the distance to the contact the nominal part gives (offset towards its point
// nearest the centre), which of the two is right not being known; turned past 90°, the fit is inside out there
// and the row is an outlier.
constexpr double kTurnedDegrees = 45.0;

// One warning per face with turned rows: how many, the largest turn and disagreement, and the outliers.
void turned_normal_warnings(std::span<const CompensatedPoint> out, std::span<const double> turned,
                            std::span<const double> disagreement, std::vector<std::string>& warnings) {
  struct Tally {
    int rows = 0, inside_out = 0;
    double angle = 0.0, distance = 0.0;
  };
  std::map<int, Tally> by_face;
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (!(turned[k] > 0.0)) continue;
    Tally& t = by_face[out[k].face];
    ++t.rows;
    t.inside_out += turned[k] > std::numbers::pi / 2.0;
    t.angle = std::max(t.angle, turned[k]);
    t.distance = std::max(t.distance, disagreement[k]);
  }
  for (const auto& [face, t] : by_face) {
    char angle[32];
    std::snprintf(angle, sizeof angle, "%.0f", t.angle * 180.0 / std::numbers::pi);
    warnings.push_back("face " + std::to_string(face) + ": at " + std::to_string(t.rows) + " row" +
                       (t.rows == 1 ? "" : "s") + " the fitted normal is turned up to " + angle +
                       "° from the nominal part's, more than a deformation does (the fit followed something else, "
                       "as where a face's radius offset folds over): their u holds the "
                       "distance to the contact the nominal part gives, up to " + detail::mm(t.distance) + " mm" +
                       (t.inside_out > 0 ? "; the " + std::to_string(t.inside_out) +
                                               " turned past 90° (the fit inside out) are outliers"
                                         : ""));
  }
}

}  // namespace

std::vector<CompensatedPoint> compensate_points(const PreparedModel& prepared, std::span<const Point3> raw,
                                                const registration::RegistrationResult& registration,
                                                const FitResult& fits, std::vector<std::string>* warnings) {
  const cad::Model& work = *prepared.nominal;
  const geometry::TipRadii& radii = prepared.radii;
  const geometry::RigidTransform& T = registration.transform;
  std::vector<CompensatedPoint> out(raw.size());
  for (std::size_t k = 0; k < raw.size(); ++k) out[k].radius = radii[k];
  // Points no fit stands behind (past an edge, against two faces, on a face with too few points): the tip touched
  // the nominal part where it is nearest to the registered centre, on whichever face that is. Offset towards that
  // point (along its face's normal inside a face, towards the edge past one); the deviation is the centre's
  // distance from it less r.
  const geometry::RigidTransform to_cad = T.inverse();
  auto double_contact = [&](std::size_t k) { return !fits.second_contact.empty() && fits.second_contact[k] >= 0; };
  // Every point with a correspondence but not in a fitted face's fit (edge and double-contact points never are).
  std::vector<char> unfitted(raw.size(), 0);
  for (std::size_t k = 0; k < raw.size(); ++k) unfitted[k] = registration.matches[k].ok();
  for (const FaceFit& ff : fits.faces) {
    if (ff.report.fitted) {
      for (std::size_t k : ff.members) unfitted[k] = 0;
    }
  }
  // Each fitted face by position, for the rows past its edges; each face fitted as its element, and which of its
  // points that fit left out.
  std::vector<const FaceFit*> fitted_face(work.faces.size(), nullptr), element_face(work.faces.size(), nullptr);
  std::vector<char> element_outlier(raw.size(), 0);
  for (const FaceFit& ff : fits.faces) {
    if (ff.report.fitted && ff.fit) fitted_face[static_cast<std::size_t>(ff.face)] = &ff;
    if (ff.element) {
      element_face[static_cast<std::size_t>(ff.face)] = &ff;
      for (std::size_t i = 0; i < ff.members.size(); ++i) element_outlier[ff.members[i]] = !ff.trusted[i];
    }
  }
  tbb::parallel_for(std::size_t{0}, raw.size(), [&](std::size_t k) {
    if (!unfitted[k] || !raw[k].allFinite()) return;
    const registration::PointMatch& m = registration.matches[k];
    const Point3 x = to_cad * raw[k];
    const cad::ModelPoint foot = prepared.nominal_locator->closest_point(x, match_as_hint(m));
    CompensatedPoint& c = out[k];
    if (!foot.ok() || !((x - foot.point).norm() > 0.0)) {
      c.status = PointStatus::Failed;
      return;
    }
    const Vector3 towards = (foot.distance < 0.0 ? -1.0 : 1.0) * (x - foot.point).normalized();
    const FaceFit* ef = m.face >= 0 ? element_face[static_cast<std::size_t>(m.face)] : nullptr;
    if (ef != nullptr && !m.on_edge && !double_contact(k)) {
      // On a face fitted as its element: offset along the element's normal, which the data show, not the
      // nominal's. The contact keeps the centre's own noise along it (the point is not smoothed onto the element:
      // a plane's ten points keep their form deviations).
      // (The element was fitted in the machine frame, as the faces' NURBS are.)
      const ElementFaceFit& e = *ef->element;
      const Vector3 n = element_normal(e, raw[k], T.linear() * towards);
      const double r = radii[k];
      c.status = element_outlier[k] ? PointStatus::Outlier : PointStatus::Ok;
      c.face = work.faces[static_cast<std::size_t>(m.face)].index;
      c.normal = n;
      c.contact = raw[k] - r * n;
      const cad::ModelPoint at = prepared.nominal_locator->closest_point(to_cad * c.contact, foot);
      c.deviation = at.ok() ? at.distance : foot.distance - r;
      c.uncertainty = std::isfinite(e.noise) ? e.noise : registration.scale;
      // An outlier's reading and the element disagree by its distance from it; which is right is not known.
      if (element_outlier[k]) c.uncertainty = std::hypot(c.uncertainty, std::abs(element_distance(e, raw[k])));
      return;
    }
    c.status = m.on_edge ? PointStatus::Edge : double_contact(k) ? PointStatus::DoubleContact : PointStatus::FewPoints;
    c.face = work.faces[static_cast<std::size_t>(foot.face)].index;
    c.normal = T.linear() * towards;
    const double r = radii[k];
    c.contact = contact_towards(raw[k], r, T, x, foot);
    c.deviation = foot.distance - (foot.distance < 0.0 ? -r : r);
    c.uncertainty = registration.scale;
    // A tip past a fitted face's edge touched the part's rim, which the part's deformation moved with the face: its
    // contact is taken on the nominal rim, and u says how far the face's fit puts the part from the nominal there.
    // (The fitted centre surface's displacement from the registered offset, less r times the turn of its normal:
    // a slope of 1° near the rim alone moves the centre surface 17 µm sideways at r = 1 mm.) Measured on the panel
    // with a 0.1 mm bump reaching its edge, 1.1° off: edge rows within 2u of the part 59 % -> 93 %.
    const FaceFit* ff = m.on_edge ? fitted_face[static_cast<std::size_t>(foot.face)] : nullptr;
    if (ff != nullptr) {
      const nurbs::Surface& offset = prepared.offset->model.faces[static_cast<std::size_t>(foot.face)].surface;
      const nurbs::UnitNormal n_fit = nurbs::unit_normal(ff->fit->surface, foot.u, foot.v);
      const nurbs::UnitNormal n_off = nurbs::unit_normal(offset, foot.u, foot.v);
      const double side = work.faces[static_cast<std::size_t>(foot.face)].outward;
      Vector3 moved = nurbs::evaluate(ff->fit->surface, foot.u, foot.v) - T * nurbs::evaluate(offset, foot.u, foot.v);
      if (n_fit.status != nurbs::UnitNormal::Status::Degenerate && n_off.status != nurbs::UnitNormal::Status::Degenerate) {
        moved -= prepared.probe_radius * side * (n_fit.n - T.linear() * n_off.n);
      }
      c.uncertainty = std::hypot(c.uncertainty, moved.norm());
    }
  });
  for (const FaceFit& ff : fits.faces) {
    if (!ff.report.fitted) continue;
    const cad::Face& face = work.faces[static_cast<std::size_t>(ff.face)];
    const std::vector<std::uint32_t>& members = ff.members;
    // The fit is of the smallest tip's centre surface: each member's centre moved onto it along the fit's normal.
    // In blocks, so that a face of a million points holds the contacts of a block at a time (96 bytes a point).
    constexpr std::size_t kBlock = 1 << 16;
    std::vector<Point3> pts;
    for (std::size_t first = 0; first < members.size(); first += kBlock) {
      const std::size_t count = std::min(kBlock, members.size() - first);
      pts.resize(count);
      for (std::size_t i = 0; i < count; ++i) {
        pts[i] = as_smallest_tip(prepared, registration, raw, members[first + i], &ff.fit->surface, face.outward,
                                 ff.params[first + i]);
      }
      const std::vector<ContactPoint> contacts = contact_points(
          ff.fit->surface, face.outward, radii.smallest(), pts, std::span(ff.params).subspan(first, count));
      for (std::size_t b = 0; b < count; ++b) {
        const std::size_t i = first + b;
        CompensatedPoint& c = out[members[i]];
        c.face = face.index;
        if (!contacts[b].ok()) {
          c.status = PointStatus::Failed;
          continue;
        }
        c.status = ff.trusted[i] ? PointStatus::Ok : PointStatus::Outlier;
        c.contact = contacts[b].contact;
        c.normal = contacts[b].normal;
        // (Along scan lines the bias is also read from the residuals along the line: compensation/scan_lines.hpp.)
        const double bias = ff.line_bias.empty() ? ff.fit->misfit[i] : std::max(ff.fit->misfit[i], ff.line_bias[i]);
        c.uncertainty = std::hypot(ff.fit->noise_sigma * std::sqrt(ff.fit->variance_factor[i]), bias);
        // An outlier's reading and the fit disagree by its residual, and which of them is right is not known (a
        // gross error, or shape the fit cannot follow): its u covers both. So does that of a point the last fit
        // left out but found within its bound (the refits ran out before taking it back): the fit there is a
        // prediction made without it (measured: a noise-free point 1.3 µm from such a prediction, u 0.18 µm).
        if (!ff.trusted[i] || !ff.in_last_fit[i]) c.uncertainty = std::hypot(c.uncertainty, ff.fit->residuals[i]);
        // Next to points left out, the fit's normal may not be what the data show: the contact point is then
        // r(1 − cos θ) off along it (normal_support.hpp). Where θ could not be told, the worst case: r.
        if (!ff.normal_angle.empty()) c.uncertainty = std::hypot(c.uncertainty, normal_doubt(radii[members[i]], ff.normal_angle[i]));
        // And across scan lines, how far it may be off where no data show it (compensation/scan_lines.hpp).
        if (!ff.normal_unseen_angle.empty()) {
          c.uncertainty = std::hypot(c.uncertainty, normal_doubt(radii[members[i]], ff.normal_unseen_angle[i]));
        }
      }
    }
  }

  // Deviations of the fitted points: Newton from the correspondence's (u, v) (nominal and offset faces share their
  // parametrisation), with the face's global search where Newton fails. And whether the fit's normal is turned
  // from the nominal part's beyond what a deformation does (kTurnedDegrees).
  std::vector<char> retry(raw.size(), 0);
  std::vector<double> turned(raw.size(), 0.0), disagreement(raw.size(), 0.0);
  const double turned_cos = std::cos(kTurnedDegrees * std::numbers::pi / 180.0);
  tbb::parallel_for(std::size_t{0}, raw.size(), [&](std::size_t k) {
    CompensatedPoint& c = out[k];
    if (!c.computed() || unfitted[k]) return;
    const registration::PointMatch& m = registration.matches[k];
    const cad::Face& face = work.faces[static_cast<std::size_t>(m.face)];
    const double cos_turn = c.normal.dot(T.linear() * prepared.nominal_locator->outward_normal(m.face, m.u, m.v));
    if (cos_turn < turned_cos) {
      turned[k] = std::acos(std::max(cos_turn, -1.0));
      disagreement[k] = 2.0 * radii[k];  // where the nominal part gives no contact either
      const Point3 x = to_cad * raw[k];
      const cad::ModelPoint near = prepared.nominal_locator->closest_point(x, match_as_hint(m));
      if (near.ok() && (x - near.point).norm() > 0.0) {
        disagreement[k] = (c.contact - contact_towards(raw[k], radii[k], T, x, near)).norm();
      }
      c.uncertainty = std::hypot(c.uncertainty, disagreement[k]);
      if (cos_turn < 0.0) c.status = PointStatus::Outlier;
    }
    const Point3 x = to_cad * c.contact;
    const nurbs::ClosestPointResult foot = nurbs::refine_closest_point(face.surface, x, m.u, m.v);
    if (foot.ok()) {
      c.deviation = signed_distance(face, x, foot);
    } else {
      retry[k] = 1;
    }
  });
  // The registration's share of u, in quadrature with the fit's: the registered model's position along the
  // normal varies with the measurement noise as normal_variance says (most along weakly fixed motions). The noise
  // is the fits' estimate (FitResult::noise_sigma), not the registration's residual scale, which holds the part's
  // deformation too: that is what the deviations measure, not an uncertainty of where the model sits.
  const double noise = std::isfinite(fits.noise_sigma) ? fits.noise_sigma : registration.scale;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, raw.size(), 4096), [&](const auto& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      CompensatedPoint& c = out[k];
      if (!c.computed()) continue;
      const double reg = noise * noise * registration::normal_variance(registration.constraints, to_cad * c.contact,
                                                                      to_cad.linear() * c.normal);
      c.uncertainty = std::sqrt(c.uncertainty * c.uncertainty + std::max(reg, 0.0));
    }
  });
  if (warnings != nullptr) turned_normal_warnings(out, turned, disagreement, *warnings);
  std::map<int, nurbs::ClosestPointSolver> solvers;  // built for the faces that need one
  for (std::size_t k = 0; k < raw.size(); ++k) {
    if (!retry[k]) continue;
    const registration::PointMatch& m = registration.matches[k];
    const cad::Face& face = work.faces[static_cast<std::size_t>(m.face)];
    const nurbs::ClosestPointSolver& solver = solvers.try_emplace(m.face, face.surface).first->second;
    const Point3 x = to_cad * out[k].contact;
    const nurbs::ClosestPointResult foot = solver.closest_point(x);
    if (foot.ok()) {
      out[k].deviation = signed_distance(face, x, foot);
    } else {
      out[k].status = PointStatus::Failed;
      out[k].uncertainty = std::numeric_limits<double>::quiet_NaN();
    }
  }
  return out;
}

}  // namespace probecomp::compensation
