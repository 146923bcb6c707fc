#pragma once
// The two ways to register probe data to a CAD model (DESIGN.md §2 step 3, paper §5.1):
//   proposed      the raw probe centres against the model offset by the tip radius: no compensation error
//                 can enter the registration;
//   conventional  first compensate each centre along its approach normal, then register the contact points
//                 to the nominal model (the errors of that compensation bias the alignment).
// And the choice of each face's material side where the CAD model does not give it (DESIGN.md §4).

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "cad/model.hpp"
#include "cad/offset_model.hpp"
#include "registration/icp.hpp"

namespace probecomp::registration {

// The raw centres (machine frame) registered to `offset` (the nominal offset by +r on every face's outward
// side; see cad::offset_model).
// The robust scale is kept at or above the offset faces' deviation from the true offset (model error).
[[nodiscard]] RegistrationResult register_to_offset_model(const cad::OffsetModel& offset,
                                                          std::span<const Point3> raw_centres,
                                                          const RegistrationOptions& options = {});
// The same with the offset model already indexed (`locator` built on offset.model).
[[nodiscard]] RegistrationResult register_to_offset_model(const cad::OffsetModel& offset, const cad::ModelLocator& locator,
                                                          std::span<const Point3> raw_centres,
                                                          const RegistrationOptions& options = {});

// Conventional route: contact points c − r·(i,j,k) registered to the nominal model.
[[nodiscard]] RegistrationResult register_conventional(const cad::Model& nominal, std::span<const Point3> raw_centres,
                                                       std::span<const Vector3> approach_normals, double probe_radius,
                                                       const RegistrationOptions& options = {});

enum class MaterialSource {
  Solid,            // the face bounds a closed solid in the file
  ApproachNormals,  // the approach normals of the points on the face point to one side
  Data,             // the raw centres lie on one side (they are a probe radius off the part, on the probe side)
  NoPoints,         // nothing to decide from: the file's orientation is kept
};
[[nodiscard]] const char* to_string(MaterialSource s);

struct MaterialSide {
  int outward = 1;  // as cad::Face::outward
  MaterialSource source = MaterialSource::NoPoints;
  int points = 0;         // points whose nearest face this is
  int agreeing = 0;       // of those, how many vote for the chosen side
  double median_distance = 0.0;  // median signed distance of the raw centres, on the chosen side (mm; Data)
};

// For every face without a known material side, chooses it from the approach normals when given, else
// from which side the raw centres lie on, after the initial transform (CAD to machine); updates
// model.faces[k].outward and returns what was decided per face. Faces from solids are kept as they are.
[[nodiscard]] std::vector<MaterialSide> decide_material_side(cad::Model& model, std::span<const Point3> raw_centres,
                                                             std::optional<std::span<const Vector3>> approach_normals,
                                                             const RigidTransform& initial);

}  // namespace probecomp::registration
