#pragma once
// The radius-offset model (DESIGN.md §2 step 2): every face offset by the probe radius along its outward
// normal, keeping its trim (the offset keeps the face's parametrisation), so that raw probe-centre points can
// be registered to it directly.

#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/fitting/offset.hpp"

namespace probecomp::cad {

struct OffsetModel {
  Model model;                                // faces in the same order, each offset; trims shared
  std::vector<fitting::OffsetResult> faces;   // per face: status, deviation reached, curvature radius, rounds
  [[nodiscard]] int failed() const;           // faces whose offset is not within the tolerance (or folds)
};

// Offsets each face by d along its outward normal (d > 0: away from the material). Faces are independent and
// run in parallel; the result does not depend on the thread count.
[[nodiscard]] OffsetModel offset_model(const Model& model, double d, const fitting::OffsetOptions& options = {});

}  // namespace probecomp::cad
