#include "probecomp/registration/routes.hpp"

#include <algorithm>
#include <cstdint>
#include <vector>


namespace probecomp::registration {

RegistrationResult register_to_offset_model(const cad::OffsetModel& offset, std::span<const Point3> raw_centres,
                                            const RegistrationOptions& options) {
  const cad::ModelLocator locator(offset.model);
  return register_to_offset_model(offset, locator, raw_centres, options);
}

RegistrationResult register_to_offset_model(const cad::OffsetModel& offset, const cad::ModelLocator& locator,
                                            std::span<const Point3> raw_centres, const RegistrationOptions& options,
                                            std::span<const double> beyond) {
  // The offset faces are fits, within their deviation of the true offset: residuals below it are model error,
  // not data, so the robust scale is not allowed below it (else IRLS would weight points by the fit's ripple).
  // A face whose offset folds over (a concave fillet tighter than the tip) or has no normal somewhere is wrong
  // there by up to the radius: its deviation says nothing of the other faces' accuracy, and as a floor it would
  // switch the robust weights off for the whole model (the die-cast sample: 1.43 mm).
  RegistrationOptions o = options;
  for (const fitting::OffsetResult& f : offset.faces) {
    const bool fitted = f.status == fitting::OffsetResult::Status::OK ||
                        f.status == fitting::OffsetResult::Status::ToleranceNotReached;
    if (fitted) o.robust.min_scale = std::max(o.robust.min_scale, f.deviation);
  }
  return register_points(locator, raw_centres, o, beyond);
}

RegistrationResult register_by_faces(const cad::OffsetModel& offset, const cad::ModelLocator& locator,
                                     std::span<const Point3> raw_centres, std::span<const int> faces,
                                     const RegistrationOptions& options, std::span<const double> beyond) {
  std::vector<char> chosen_face(offset.model.faces.size(), 0);
  for (const int f : faces) {
    if (f >= 0 && static_cast<std::size_t>(f) < chosen_face.size()) chosen_face[static_cast<std::size_t>(f)] = 1;
  }
  const auto on_chosen = [&](const PointMatch& m) {
    return m.ok() && !m.on_edge && m.face >= 0 && chosen_face[static_cast<std::size_t>(m.face)] != 0;
  };
  std::vector<PointMatch> at = matches_at(locator, raw_centres, options.initial, beyond);
  std::vector<std::uint8_t> locating(raw_centres.size(), 0);
  RegistrationResult r;
  RegistrationOptions o = options;
  for (int round = 0; round < kFeatureRounds; ++round) {
    std::vector<std::uint8_t> next(raw_centres.size(), 0);
    for (std::size_t k = 0; k < at.size(); ++k) next[k] = on_chosen(at[k]) ? 1 : 0;
    if (round > 0 && next == locating) break;
    locating = std::move(next);
    o.located_by = locating;
    if (round > 0) o.initial = r.transform;
    r = register_to_offset_model(offset, locator, raw_centres, o, beyond);
    if (r.status == Status::TooFewPoints || r.status == Status::NumericalError) break;
    at = r.matches;
  }
  return r;
}

}  // namespace probecomp::registration
