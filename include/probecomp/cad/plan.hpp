#pragma once
// Measurement planning: nominal points spread over chosen faces, inside their trims, with outward normals,
// for a CMM program (PTMEAS targets) or for simulation.

#include <vector>

#include "probecomp/cad/model.hpp"

namespace probecomp::cad {

struct PlannedPoint {
  Point3 point;
  Vector3 normal;  // outward unit normal
  int face;
  double u, v;
};

// On each face, a grid of cell centres in (u, v), over the trim's parameter box, whose spacing along the surface is about `spacing` mm
// (estimated from the lengths of iso-curves; strongly non-uniform parametrisations give uneven spacing),
// keeping the points inside the trim and with a defined normal. `faces` empty means every face.
// Throws std::invalid_argument for a non-positive spacing or an unknown face index.
[[nodiscard]] std::vector<PlannedPoint> plan_points(const Model& model, double spacing, const std::vector<int>& faces);

}  // namespace probecomp::cad
