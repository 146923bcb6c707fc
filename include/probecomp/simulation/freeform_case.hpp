#pragma once
// The built-in free-form case modelled on the paper's §7.3 (Table 2): a rational bicubic panel about 100 × 50 mm,
// deformed by a broad bulge and a narrow dent the nominal knots cannot follow, misaligned by 0.2 mm in z and 1.5°
// about y, measured on a 120 × 60 grid with a 1 mm tip and σ = 4.5 µm noise. `probecomp demo`, the freeform
// study and the end-to-end tests all use it.

#include <cstdint>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/geometry/rigid.hpp"
#include "probecomp/simulation/deformation.hpp"
#include "probecomp/simulation/measure.hpp"

namespace probecomp::simulation {

struct FreeformCase {
  cad::Model nominal;  // one face, CAD frame; material below (outward +z where S_u × S_v is +z)
  Deformation deformation;
  geometry::RigidTransform placement;  // CAD to machine: where the actual part sits
  double probe_radius = 1.0;               // mm
  double noise_sigma = 0.0045;             // mm
  int grid_u = 120, grid_v = 60;
};

// The case's nominal panel: rational bicubic, 9 × 6 control points over x ∈ [−50, 50], y ∈ [−25, 25], heights of
// a few mm from two crossing waves, weights 0.8–1.25; S_u × S_v points up (+z, out of the material).
[[nodiscard]] nurbs::Surface paper_panel();

// The paper's case. `reversed`: the same part with u and v exchanged, so that S_u × S_v points into the material
// (the face's outward is then −1, and nothing in the file says so).
[[nodiscard]] FreeformCase paper_freeform_case(bool reversed = false);

}  // namespace probecomp::simulation
