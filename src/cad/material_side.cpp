#include "probecomp/cad/material_side.hpp"

#include <algorithm>

#include "probecomp/cad/locator.hpp"
#include "probecomp/geometry/statistics.hpp"

namespace probecomp::cad {

const char* to_string(MaterialSource s) {
  switch (s) {
    case MaterialSource::Solid: return "solid";
    case MaterialSource::ApproachNormals: return "approach-normals";
    case MaterialSource::Data: return "data";
    case MaterialSource::NoPoints: return "no-points";
    case MaterialSource::File: return "file";
  }
  return "?";
}

std::vector<MaterialSide> decide_material_side(Model& model, std::span<const Point3> raw_centres,
                                               std::optional<std::span<const Vector3>> approach_normals,
                                               const geometry::RigidTransform& initial) {
  std::vector<MaterialSide> sides(model.faces.size());
  for (std::size_t f = 0; f < model.faces.size(); ++f) {
    sides[f].outward = model.faces[f].outward;
    if (model.faces[f].material_known) sides[f].source = MaterialSource::Solid;
  }
  const bool any_unknown = std::any_of(model.faces.begin(), model.faces.end(), [](const Face& f) { return !f.material_known; });
  if (!any_unknown || raw_centres.empty()) return sides;

  const geometry::RigidTransform to_cad = initial.inverse();
  std::vector<Point3> x(raw_centres.size());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = to_cad * raw_centres[i];
  std::vector<ModelPoint> feet;
  {
    const ModelLocator locator(model);
    feet = locator.closest_points(x);
  }
  // Votes relative to the file's orientation (ModelPoint normals and distances use the current `outward`).
  std::vector<int> plus(model.faces.size(), 0), minus(model.faces.size(), 0);
  std::vector<std::vector<double>> distances(model.faces.size());
  for (std::size_t i = 0; i < feet.size(); ++i) {
    const ModelPoint& m = feet[i];
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
    Face& face = model.faces[f];
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
      s.median_distance = flip * geometry::upper_median_in_place(d);
    }
  }
  return sides;
}

}  // namespace probecomp::cad
