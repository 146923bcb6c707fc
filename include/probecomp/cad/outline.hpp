#pragma once
// Polylines that draw a face for people (the report's 3-D view): its boundary and a few interior iso-parameter
// lines clipped to it. A picture, not geometry to compute with: the points lie on the face's surface exactly, the
// chords between them do not.

#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/geometry/types.hpp"

namespace probecomp::cad {

using Polyline = std::vector<Point3>;

struct OutlineOptions {
  int isolines = 3;           // interior iso-parameter lines each way (u and v); 0: the boundary only
  int samples_per_line = 48;  // points along an iso-parameter line or a side of an untrimmed face
  int max_boundary_samples = 64;  // per boundary curve (a trim's sampling may be much finer)
};

// The face's boundary (each trim loop's curves, or the four sides of an untrimmed surface) and its isolines, in the
// model's frame (mm). An isoline is split where it leaves the face; pieces of fewer than two points are dropped.
[[nodiscard]] std::vector<Polyline> face_outline(const Face& face, const OutlineOptions& options = {});

}  // namespace probecomp::cad
