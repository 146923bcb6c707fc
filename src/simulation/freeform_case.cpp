#include "probecomp/simulation/freeform_case.hpp"

#include <cmath>
#include <numbers>

namespace probecomp::simulation {

// 9 × 6 control points over x ∈ [−50, 50], y ∈ [−25, 25] at the Greville abscissae of non-uniform knots, heights
// from two crossing waves (a few mm), weights between 0.8 and 1.25: smooth like a designed panel, curvature radii
// above 20 mm.
nurbs::Surface paper_panel() {
  nurbs::KnotVector U({0, 0, 0, 0, 0.16, 0.3, 0.48, 0.66, 0.82, 1, 1, 1, 1}, 3);
  nurbs::KnotVector V({0, 0, 0, 0, 0.37, 0.64, 1, 1, 1, 1}, 3);
  std::vector<Point3> P;
  std::vector<double> w;
  for (int i = 0; i < U.num_basis(); ++i) {
    for (int j = 0; j < V.num_basis(); ++j) {
      const double x = -50.0 + 100.0 * U.greville(i);
      const double y = -25.0 + 50.0 * V.greville(j);
      const double z = 6.0 * std::sin(std::numbers::pi * x / 70.0) * std::cos(std::numbers::pi * y / 60.0) + 0.03 * x * y / 10.0;
      P.emplace_back(x, y, z);
      w.push_back(1.0 + 0.2 * std::sin(1.3 * i + 0.7 * j));
    }
  }
  return nurbs::Surface(std::move(U), std::move(V), P, w);
}

FreeformCase paper_freeform_case(bool reversed) {
  FreeformCase c;
  const nurbs::Surface s = paper_panel();
  // A lone surface: its material side comes from the approach normals or the data, not the file.
  cad::Face face{.index = 0, .name = "freeform panel", .source_type = "bspline",
                 .surface = reversed ? nurbs::transposed(s) : s, .trim = nullptr, .outward = reversed ? -1 : 1,
                 .material_known = false, .exact = true};
  c.nominal.path = "built-in free-form panel";
  c.nominal.file_units = "mm";
  c.nominal.faces.push_back(std::move(face));

  // A broad bulge (0.25 mm over about 25 mm) and a dent 1 mm deep and about 6 mm across (Gaussian σ = 2.5 mm):
  // its flanks slope up to 1/2.5 · e^(−1/2) = 0.24, i.e. 13.6°; the nominal spans (10-18 mm) cannot follow it.
  c.deformation.bumps.push_back({nurbs::evaluate(s, 0.3, 0.4), 0.25, 12.0});
  c.deformation.bumps.push_back({nurbs::evaluate(s, 0.64, 0.62), -1.0, 2.5});
  c.placement = geometry::from_pose({.rx = 0.0, .ry = 1.5, .rz = 0.0, .t = Vector3(0.0, 0.0, 0.2)});
  return c;
}

}  // namespace probecomp::simulation
