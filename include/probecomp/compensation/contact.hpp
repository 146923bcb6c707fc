#pragma once
// The last steps of DESIGN.md §2 (6–7): smooth the raw probe-centre points by projecting them on the surface
// fitted through them, and move each by the probe radius along that surface's unit normal, towards the
// material: the contact point on the part.

#include <span>
#include <vector>

#include "probecomp/fitting/least_squares.hpp"
#include "probecomp/nurbs/closest_point.hpp"

namespace probecomp::compensation {

struct ContactPoint {
  nurbs::ClosestPointStatus status = nurbs::ClosestPointStatus::NotConverged;  // of the projection
  double u = 0.0, v = 0.0;              // foot point of the raw centre on the fitted centre surface
  Point3 centre = Point3::Zero();       // the smoothed probe centre (the foot point)
  Point3 contact = Point3::Zero();      // centre − r·n: the point where the tip touched the part
  Vector3 normal = Vector3::Zero();     // the part's outward unit normal there (the fitted surface's, oriented)

  [[nodiscard]] bool ok() const {
    return status == nurbs::ClosestPointStatus::Converged || status == nurbs::ClosestPointStatus::OnBoundary;
  }
};

// `centre_surface` is fitted through the probe-centre points; `outward` is +1 when its S_u × S_v points away
// from the material (out of the part, towards where the probe came from), −1 otherwise. Each point is
// projected by Newton from its parameters, and by the global search where Newton does not converge. A point
// whose projection fails, or where the surface has no normal, comes back with that status and its raw centre.
// Parallel, deterministic.
[[nodiscard]] std::vector<ContactPoint> contact_points(const nurbs::Surface& centre_surface, int outward,
                                                       double probe_radius, std::span<const Point3> raw_centres,
                                                       std::span<const fitting::SurfaceParameter> params);

}  // namespace probecomp::compensation
