#pragma once
// The two ways to register probe data to a CAD model (DESIGN.md §2 step 3, paper §5.1):
//   proposed      the raw probe centres against the model offset by the tip radius: no compensation error
//                 can enter the registration;
//   conventional  first compensate each centre along its approach normal, then register the contact points
//                 to the nominal model (the errors of that compensation bias the alignment); it is
//                 compensation::register_conventional, as it needs the conventional compensation first.

#include <span>
#include <string>
#include <vector>

#include "probecomp/cad/offset_model.hpp"
#include "probecomp/registration/icp.hpp"

namespace probecomp::registration {

// The raw centres (machine frame) registered to `offset` (the nominal offset by +r on every face's outward
// side; see cad::offset_model).
// The robust scale is kept at or above the offset faces' deviation from the true offset (model error).
[[nodiscard]] RegistrationResult register_to_offset_model(const cad::OffsetModel& offset,
                                                          std::span<const Point3> raw_centres,
                                                          const RegistrationOptions& options = {});
// The same with the offset model already indexed (`locator` built on offset.model). `beyond`, when given (one per
// centre, mm), is how much larger each centre's tip is than the radius the model is offset by
// (geometry::TipRadii::beyond_smallest): its target lies that much farther out.
[[nodiscard]] RegistrationResult register_to_offset_model(const cad::OffsetModel& offset, const cad::ModelLocator& locator,
                                                          std::span<const Point3> raw_centres,
                                                          const RegistrationOptions& options = {},
                                                          std::span<const double> beyond = {});

// A part located by some of its faces alone (its datum features, `faces` positions in offset.model.faces): the raw
// centres whose correspondence lies inside one of those faces register the part, from options.initial, and are
// chosen again where that puts the part until the choice settles (at most kFeatureRounds registrations). Every
// centre gets its correspondence at the final transform; the result's located_by marks those that located it.
inline constexpr int kFeatureRounds = 4;
[[nodiscard]] RegistrationResult register_by_faces(const cad::OffsetModel& offset, const cad::ModelLocator& locator,
                                                   std::span<const Point3> raw_centres, std::span<const int> faces,
                                                   const RegistrationOptions& options = {},
                                                   std::span<const double> beyond = {});

}  // namespace probecomp::registration
