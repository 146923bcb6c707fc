#pragma once
// Prismatic parts built by OpenCASCADE's modelling (not by probecomp), written to STEP and read back as a model: the
// datum and characteristic tests measure them against closed forms.

#include "probecomp/cad/model.hpp"

namespace probecomp::testing {

// A 60 × 40 × 20 mm block from the origin along +x, +y, +z, with a through hole of radius 5 along z at (40, 20).
[[nodiscard]] cad::Model block_with_hole();

// A 40 × 40 × 10 mm block from the origin with a pin of radius 4 standing 12 mm on its top at (20, 20).
[[nodiscard]] cad::Model block_with_pin();

// The face whose surface passes through `p` (within 1e-6 mm); throws when none does.
[[nodiscard]] int face_through(const cad::Model& model, const Point3& p);

}  // namespace probecomp::testing
