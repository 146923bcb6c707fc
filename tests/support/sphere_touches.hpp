#pragma once
// Touches of a reference sphere as a CMM takes them to qualify a stylus, made in closed form: the probe travels
// along −n (n the sphere's outward normal at the programmed point) and stops where its tip, of effective radius
// r − p(−n), meets the sphere, so the centre it reports is C + (R + r − p(−n))·n, plus Gaussian noise.
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include "probecomp/geometry/types.hpp"

namespace probecomp::test {

struct SphereTouches {
  std::vector<Point3> centres;
  std::vector<Vector3> normals;  // outward, as (i,j,k)
};

// `count` programmed normals on a spiral from the top (+z) down to `lowest_deg` below the equator (negative: above
// it), evenly spread over that cap (golden-angle azimuths), turned by `azimuth_deg`.
inline std::vector<Vector3> sphere_cap_normals(int count, double lowest_deg, double azimuth_deg = 0.0) {
  std::vector<Vector3> out;
  const double z_low = -std::sin(lowest_deg * std::numbers::pi / 180.0);
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < count; ++k) {
    const double z = 1.0 - (1.0 - z_low) * (k + 0.5) / count;
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * k + azimuth_deg * std::numbers::pi / 180.0;
    out.emplace_back(rho * std::cos(phi), rho * std::sin(phi), z);
  }
  return out;
}

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
