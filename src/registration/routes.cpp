#include "registration/routes.hpp"

#include <algorithm>

#include "compensation/conventional.hpp"

namespace probecomp::registration {

RegistrationResult register_to_offset_model(const cad::OffsetModel& offset, std::span<const Point3> raw_centres,
                                            const RegistrationOptions& options) {
  const cad::ModelLocator locator(offset.model);
  return register_to_offset_model(offset, locator, raw_centres, options);
}

RegistrationResult register_to_offset_model(const cad::OffsetModel& offset, const cad::ModelLocator& locator,
                                            std::span<const Point3> raw_centres, const RegistrationOptions& options) {
  // The offset faces are fits, within their deviation of the true offset: residuals below it are model error,
  // not data, so the robust scale is not allowed below it (else IRLS would weight points by the fit's ripple).
  RegistrationOptions o = options;
  for (const fitting::OffsetResult& f : offset.faces) o.robust.min_scale = std::max(o.robust.min_scale, f.deviation);
  return register_points(locator, raw_centres, o);
}

RegistrationResult register_conventional(const cad::Model& nominal, std::span<const Point3> raw_centres,
                                         std::span<const Vector3> approach_normals, double probe_radius,
                                         const RegistrationOptions& options) {
  const std::vector<Point3> contacts =
      compensation::conventional_contact_points(raw_centres, approach_normals, probe_radius);
  const cad::ModelLocator locator(nominal);
  return register_points(locator, contacts, options);
}

const char* to_string(MaterialSource s) {
  switch (s) {
    case MaterialSource::Solid: return "solid";
    case MaterialSource::ApproachNormals: return "approach-normals";
    case MaterialSource::Data: return "data";
    case MaterialSource::NoPoints: return "no-points";
  }
  return "?";
}

std::vector<MaterialSide> decide_material_side(cad::Model& model, std::span<const Point3> raw_centres,
                                               std::optional<std::span<const Vector3>> approach_normals,
                                               const RigidTransform& initial) {
  std::vector<MaterialSide> sides(model.faces.size());
  for (std::size_t f = 0; f < model.faces.size(); ++f) {
    sides[f].outward = model.faces[f].outward;
    if (model.faces[f].material_known) sides[f].source = MaterialSource::Solid;
  }
  const bool any_unknown = std::any_of(model.faces.begin(), model.faces.end(), [](const cad::Face& f) { return !f.material_known; });
  if (!any_unknown || raw_centres.empty()) return sides;

  const RigidTransform to_cad = initial.inverse();
  std::vector<Point3> x(raw_centres.size());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = to_cad * raw_centres[i];
  std::vector<cad::ModelPoint> feet;
  {
    const cad::ModelLocator locator(model);
    feet = locator.closest_points(x);
  }
  // Votes relative to the file's orientation (ModelPoint normals and distances use the current `outward`).
  std::vector<int> plus(model.faces.size(), 0), minus(model.faces.size(), 0);
  std::vector<std::vector<double>> distances(model.faces.size());
  for (std::size_t i = 0; i < feet.size(); ++i) {
    const cad::ModelPoint& m = feet[i];
    if (!m.ok() || m.on_trim_edge) continue;
    const std::size_t f = static_cast<std::size_t>(m.face);
    if (model.faces[f].material_known) continue;
    double vote = 0.0;
    if (approach_normals) {
      vote = m.normal.dot(to_cad.linear() * (*approach_normals)[i]);
    } else {
      vote = m.distance;
      distances[f].push_back(m.distance);
    }
    if (vote > 0.0) ++plus[f];
    if (vote < 0.0) ++minus[f];
  }
  for (std::size_t f = 0; f < model.faces.size(); ++f) {
    cad::Face& face = model.faces[f];
    if (face.material_known) continue;
    MaterialSide& s = sides[f];
    s.points = plus[f] + minus[f];
    if (s.points == 0) continue;
    s.source = approach_normals ? MaterialSource::ApproachNormals : MaterialSource::Data;
    // The probe side is where most approach normals point, or where most centres lie.
    const int flip = minus[f] > plus[f] ? -1 : 1;
    face.outward *= flip;
    s.outward = face.outward;
    s.agreeing = std::max(plus[f], minus[f]);
    if (!distances[f].empty()) {
      std::vector<double>& d = distances[f];
      const auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
      std::nth_element(d.begin(), mid, d.end());
      s.median_distance = flip * *mid;
    }
  }
  return sides;
}

}  // namespace probecomp::registration
