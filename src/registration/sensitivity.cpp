#include "probecomp/registration/sensitivity.hpp"

#include <algorithm>
#include <cmath>

namespace probecomp::registration {

geometry::Twist shift_leaving_out(const cad::ModelLocator& model, std::span<const Point3> machine_points,
                                  const RegistrationResult& r, std::span<const std::size_t> left_out) {
  const Constraints& c = r.constraints;
  const geometry::RigidTransform to_cad = r.transform.inverse();
  geometry::Twist g = geometry::Twist::Zero();
  for (const std::size_t k : left_out) {
    const PointMatch& m = r.matches[k];
    if (!(m.weight > 0.0)) continue;
    const Vector3 n = model.outward_normal(m.face, m.u, m.v);
    geometry::Twist J;
    J.head<3>() = (to_cad * machine_points[k] - c.centre).cross(n) / c.length;
    J.tail<3>() = n;
    g += m.weight * m.distance * J;
  }
  return c.covariance * g;
}

bool leaving_out_moves(const cad::ModelLocator& model, std::span<const Point3> machine_points,
                       const RegistrationOptions& options, const RegistrationResult& r,
                       std::span<const std::size_t> left_out) {
  if (static_cast<double>(left_out.size()) > kMaxSkippedShare * static_cast<double>(r.used)) return true;
  const Constraints& c = r.constraints;
  const geometry::RigidTransform to_cad = r.transform.inverse();
  const geometry::Twist delta = shift_leaving_out(model, machine_points, r, left_out);
  double reach = 0.0;  // the farthest point from H's centre, mm
  for (const Point3& x : machine_points) {
    if (x.allFinite()) reach = std::max(reach, (to_cad * x - c.centre).norm());
  }
  const double moved = delta.head<3>().norm() / c.length * reach + delta.tail<3>().norm();
  const double tolerance =
      std::max(options.criteria.motion_tolerance, options.criteria.relative_motion_tolerance * r.scale /
                                                      std::sqrt(static_cast<double>(std::max<std::size_t>(r.used, 1))));
  return !(moved <= tolerance);
}

}  // namespace probecomp::registration
