#pragma once
// Each face's material side where the CAD file does not give it (DESIGN.md §4): a face that bounds a solid
// knows it; any other is decided from the approach normals of the points nearest to it, or else from the side
// its raw probe centres lie on (a probe radius off the part, on the probe's side).

#include <optional>
#include <span>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/geometry/rigid.hpp"

namespace probecomp::cad {

class ModelLocator;

enum class MaterialSource {
  Solid,            // the face bounds a closed solid in the file
  ApproachNormals,  // the approach normals of the points on the face point to one side
  Data,             // the raw centres lie on one side (they are a probe radius off the part, on the probe side)
  NoPoints,         // no points were nearest to it: the file's orientation is kept
  File,             // the file's orientation, kept because nothing decided it (the conventional method, or a face
                    // that gained points only in registration)
};
[[nodiscard]] const char* to_string(MaterialSource s);

struct MaterialSide {
  int outward = 1;  // as Face::outward
  MaterialSource source = MaterialSource::NoPoints;
  int points = 0;         // points whose nearest face this is (of a spread subset, when the subset decided)
  int agreeing = 0;       // of those, how many vote for the chosen side
  double median_distance = 0.0;  // median signed distance of the raw centres, on the chosen side (mm; Data)
};

// For every face without a known material side, chooses it from the approach normals when given, else
// from which side the raw centres lie on, after the initial transform (CAD to machine); updates
// model.faces[k].outward and returns what was decided per face. Faces from solids are kept as they are.
[[nodiscard]] std::vector<MaterialSide> decide_material_side(Model& model, std::span<const Point3> raw_centres,
                                                             std::optional<std::span<const Vector3>> approach_normals,
                                                             const geometry::RigidTransform& initial);
// The same with a locator of `model` made already (the caller keeps it: a locator reads `outward` at each query, so
// it serves after the decision too). Throws std::invalid_argument for a locator of another model.
[[nodiscard]] std::vector<MaterialSide> decide_material_side(Model& model, const ModelLocator& locator,
                                                             std::span<const Point3> raw_centres,
                                                             std::optional<std::span<const Vector3>> approach_normals,
                                                             const geometry::RigidTransform& initial);

}  // namespace probecomp::cad
