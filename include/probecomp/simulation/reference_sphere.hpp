#pragma once
// Touches of a reference sphere, as a CMM takes them to qualify a stylus or for ISO 10360-5's probing test, in
// closed form: the probe travels along −n (n the sphere's outward normal at the programmed point) and its switch
// triggers p(−n) past the contact, so the centre it reports is C + (R + r − p(−n))·n, plus Gaussian noise on each
// coordinate. A sphere is convex and alone: the first contact needs no search.

#include <cstdint>
#include <functional>
#include <vector>

#include "probecomp/geometry/types.hpp"
#include "probecomp/simulation/pretravel.hpp"

namespace probecomp::simulation {

struct SphereTouches {
  std::vector<Point3> centres;   // reported tip centres, machine frame
  std::vector<Vector3> normals;  // programmed outward normals (i,j,k), unit
};

// `count` outward normals on a spiral from the top (+z) down to `lowest_deg` below the equator (negative: above
// it), evenly spread over that cap (golden-angle azimuths), turned by `azimuth_deg` about z.
[[nodiscard]] std::vector<Vector3> sphere_cap_normals(int count, double lowest_deg, double azimuth_deg = 0.0);

// ISO 10360-5's 25 probing directions (as outward normals about +z): the pole; 4 at 22.5° from it; 8 at 45°,
// turned 22.5°; 4 at 67.5°; 8 on the equator, turned 22.5°.
[[nodiscard]] std::vector<Vector3> iso10360_5_normals();

// The touches at the given normals (any length > 0) of a sphere of radius `sphere_radius` (mm) centred at
// `centre`, by a tip of radius `tip_radius` whose pre-travel is p(travel) (a Pretravel, or any function of the unit
// travel direction, mm); noise σ (mm) from `seed`, one draw of three per touch in order.
[[nodiscard]] SphereTouches touch_reference_sphere(const Point3& centre, double sphere_radius, double tip_radius,
                                                   const std::vector<Vector3>& normals,
                                                   const std::function<double(const Vector3&)>& pretravel,
                                                   double noise_sigma, std::uint64_t seed);

}  // namespace probecomp::simulation
