#include "probecomp/registration/routes.hpp"

#include <algorithm>


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

}  // namespace probecomp::registration
