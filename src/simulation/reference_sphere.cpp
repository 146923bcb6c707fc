#include "probecomp/simulation/reference_sphere.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "probecomp/simulation/random.hpp"

namespace probecomp::simulation {

namespace {
constexpr double kRadiansPerDegree = std::numbers::pi / 180.0;
}  // namespace

std::vector<Vector3> sphere_cap_normals(int count, double lowest_deg, double azimuth_deg) {
  std::vector<Vector3> out;
  const double z_low = -std::sin(lowest_deg * kRadiansPerDegree);
  // The golden angle: successive azimuths never line up, so any run of touches spreads round the cap.
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < count; ++k) {
    // Equal steps in z are equal areas of the cap (Archimedes), so the touches are evenly spread over it.
    const double z = 1.0 - (1.0 - z_low) * (k + 0.5) / count;
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * k + azimuth_deg * kRadiansPerDegree;
    out.emplace_back(rho * std::cos(phi), rho * std::sin(phi), z);
  }
  return out;
}

std::vector<Vector3> iso10360_5_normals() {
  std::vector<Vector3> out;
  const auto ring = [&](double polar_deg, int count, double turn_deg) {
    for (int k = 0; k < count; ++k) {
      const double t = polar_deg * kRadiansPerDegree, f = (turn_deg + 360.0 * k / count) * kRadiansPerDegree;
      out.emplace_back(std::sin(t) * std::cos(f), std::sin(t) * std::sin(f), std::cos(t));
    }
  };
  ring(0.0, 1, 0.0);
  ring(22.5, 4, 0.0);
  ring(45.0, 8, 22.5);
  ring(67.5, 4, 0.0);
  ring(90.0, 8, 22.5);
  return out;
}

SphereTouches touch_reference_sphere(const Point3& centre, double sphere_radius, double tip_radius,
                                     const std::vector<Vector3>& normals,
                                     const std::function<double(const Vector3&)>& pretravel, double noise_sigma,
                                     std::uint64_t seed) {
  SphereTouches t;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (const Vector3& normal : normals) {
    const Vector3 n = normal.normalized();
    const Vector3 e = draw_vector(noise, rng);
    t.centres.push_back(centre + (sphere_radius + tip_radius - pretravel(-n)) * n + noise_sigma * e);
    t.normals.push_back(n);
  }
  return t;
}

}  // namespace probecomp::simulation
