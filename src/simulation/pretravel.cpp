#include "probecomp/simulation/pretravel.hpp"

#include <cmath>
#include <numbers>

namespace probecomp::simulation {

double Pretravel::operator()(const Vector3& travel) const {
  const Vector3 s = stylus.normalized(), d = travel.normalized();
  // The stylus frame's first axis: the machine's x made normal to the stylus (its y for a stylus along x).
  const Vector3 x = std::abs(s.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY();
  const Vector3 e1 = (x - x.dot(s) * s).normalized(), e2 = s.cross(e1);
  const double cos_theta = d.dot(s);
  const double sin2_theta = 1.0 - cos_theta * cos_theta;
  const double phi = std::atan2(d.dot(e2), d.dot(e1));
  const double phase_rad = phase * std::numbers::pi / 180.0;
  return constant + axial * cos_theta * cos_theta + lobes * sin2_theta * std::cos(lobe_count * (phi - phase_rad));
}

Pretravel lobing_probe() {
  Pretravel p;
  p.constant = 0.002;
  p.axial = 0.003;
  p.lobes = 0.004;
  p.lobe_count = 3;
  p.phase = 20.0;
  return p;
}

}  // namespace probecomp::simulation
