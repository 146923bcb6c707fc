#pragma once
// Prismatic parts built by OpenCASCADE's modelling (not by probecomp), written to STEP and read back as a model: the
// datum and characteristic tests measure them against closed forms.

#include "probecomp/cad/model.hpp"

namespace probecomp::testing {

// A 60 × 40 × 20 mm block from the origin along +x, +y, +z, with a through hole of radius 5 along z at (40, 20).
[[nodiscard]] cad::Model block_with_hole();
// Its faces (positions in model.faces), by where they are: z = 0, y = 0, x = 0, z = 20, x = 60, y = 40, the hole.
struct BlockWithHoleFaces {
  int bottom = -1, front = -1, left = -1, top = -1, right = -1, back = -1, hole = -1;
};
[[nodiscard]] BlockWithHoleFaces faces_of_block_with_hole(const cad::Model& model);

// A 60 × 40 × 20 mm block from the origin with a conical pocket (a countersink's shape) about the vertical through
// (30, 20): radius 4 at its flat floor z = 12, widening at 29.05° (tan = 5/9) to radius 9 at z = 21, above the top.
[[nodiscard]] cad::Model block_with_countersink();

// A 40 × 40 × 10 mm block from the origin with a pin of radius 4 standing 12 mm on its top at (20, 20).
[[nodiscard]] cad::Model block_with_pin();

// An L-shaped block: 40 × 20 × 20 mm from the origin along +x, +y, +z, less the 30 × 20 × 10 mm from (10, 0, 10), so
// that a floor (z = 10, x from 10 to 40) meets a wall (x = 10, z from 10 to 20) in a concave edge along y, rounded by
// a fillet of `fillet_radius` (its axis at x = z = 10 + fillet_radius).
[[nodiscard]] cad::Model l_block_with_fillet(double fillet_radius);

// A boss: a cylinder of radius 25 mm about z from the origin, 30 mm high, its top edge rounded by a fillet of radius
// 12 mm, so that its faces (the flat top, the toroidal fillet, the side) face every direction from vertical to
// horizontal, all round.
[[nodiscard]] cad::Model filleted_boss();

// The face whose surface passes through `p` (within 1e-6 mm); throws when none does.
[[nodiscard]] int face_through(const cad::Model& model, const Point3& p);

}  // namespace probecomp::testing
