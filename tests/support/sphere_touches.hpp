#pragma once
// Touches of a reference sphere as a CMM takes them to qualify a stylus, made in closed form: the probe travels
// along −n (n the sphere's outward normal at the programmed point) and stops where its tip, of effective radius
// r − p(−n), meets the sphere, so the centre it reports is C + (R + r − p(−n))·n, plus Gaussian noise.
#include <cstdint>
#include <functional>
#include <vector>

#include "probecomp/geometry/types.hpp"
#include "probecomp/simulation/reference_sphere.hpp"

namespace probecomp::test {

// The simulator's closed form (simulation/reference_sphere.hpp): the cap's spiral of programmed normals, and the
// touches with any pre-travel function (a degree-1 one, an ideal probe) as well as simulation::Pretravel.
using simulation::SphereTouches;
using simulation::sphere_cap_normals;
inline SphereTouches touch_sphere(const Point3& centre, double sphere_radius, double tip_radius,
                                  const std::vector<Vector3>& normals,
                                  const std::function<double(const Vector3&)>& pretravel, double noise_sigma,
                                  std::uint64_t seed) {
  return simulation::touch_reference_sphere(centre, sphere_radius, tip_radius, normals, pretravel, noise_sigma, seed);
}

}  // namespace probecomp::test
