#pragma once
// Touches of a reference sphere as a CMM takes them to qualify a stylus, made in closed form: the probe travels
// along −n (n the sphere's outward normal at the programmed point) and stops where its tip, of effective radius
// r − p(−n), meets the sphere, so the centre it reports is C + (R + r − p(−n))·n, plus Gaussian noise.
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "probecomp/geometry/types.hpp"
#include "probecomp/simulation/reference_sphere.hpp"

namespace probecomp::test {

struct SphereTouches {
  std::vector<Point3> centres;
  std::vector<Vector3> normals;  // outward, as (i,j,k)
};

// The cap's spiral of programmed normals is the simulator's (simulation/reference_sphere.hpp).
using simulation::sphere_cap_normals;

inline SphereTouches touch_sphere(const Point3& centre, double sphere_radius, double tip_radius,
                                  const std::vector<Vector3>& normals,
                                  const std::function<double(const Vector3&)>& pretravel, double noise_sigma,
                                  std::uint64_t seed) {
  SphereTouches t;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (const Vector3& n : normals) {
    const Vector3 e(noise(rng), noise(rng), noise(rng));
    t.centres.push_back(centre + (sphere_radius + tip_radius - pretravel(-n)) * n + noise_sigma * e);
    t.normals.push_back(n);
  }
  return t;
}

}  // namespace probecomp::test
