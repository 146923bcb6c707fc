// The reference sphere's touches against their closed form: ISO 10360-5's 25 directions by their polar angles,
// the cap's spiral within its cap, and each reported centre R + r − p(−n) from the sphere's centre along n.

#include "probecomp/simulation/reference_sphere.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

namespace probecomp::simulation {
namespace {

TEST(ReferenceSphere, IsoProbingDirectionsAreTheStandardsFiveRings) {
  const std::vector<Vector3> n = iso10360_5_normals();
  ASSERT_EQ(n.size(), 25u);
  std::map<long, int> by_polar;  // polar angle in tenths of a degree → touches
  Vector3 sum = Vector3::Zero();
  for (const Vector3& v : n) {
    EXPECT_NEAR(v.norm(), 1.0, 1e-15);
    by_polar[std::lround(std::acos(std::clamp(v.z(), -1.0, 1.0)) * 1800.0 / std::numbers::pi)]++;
    sum += v;
  }
  EXPECT_EQ(by_polar, (std::map<long, int>{{0, 1}, {225, 4}, {450, 8}, {675, 4}, {900, 8}}));
  // Each ring is evenly spread in azimuth: the normals' horizontal parts cancel.
  EXPECT_NEAR(sum.x(), 0.0, 1e-14);
  EXPECT_NEAR(sum.y(), 0.0, 1e-14);
}

TEST(ReferenceSphere, CapNormalsStayOnTheirCapAndSpreadOverIt) {
  const double lowest = 10.0;
  const std::vector<Vector3> n = sphere_cap_normals(200, lowest, 7.0);
  ASSERT_EQ(n.size(), 200u);
  const double z_low = -std::sin(lowest * std::numbers::pi / 180.0);
  double z_min = 1.0, z_max = -1.0;
  Vector3 sum = Vector3::Zero();
  for (const Vector3& v : n) {
    EXPECT_NEAR(v.norm(), 1.0, 1e-14);
    z_min = std::min(z_min, v.z());
    z_max = std::max(z_max, v.z());
    sum += v;
  }
  EXPECT_GE(z_min, z_low);
  EXPECT_LT(z_min, z_low + 0.02);  // reaches the cap's rim
  EXPECT_GT(z_max, 0.99);          // and its top
  // Equal areas: the mean z of points evenly spread over the cap z ∈ [z_low, 1] is its middle.
  EXPECT_NEAR(sum.z() / 200.0, 0.5 * (1.0 + z_low), 1e-3);
  EXPECT_LT(std::hypot(sum.x(), sum.y()) / 200.0, 0.02);
}

TEST(ReferenceSphere, EachCentreLiesTheTipRadiusLessThePretravelOutAlongItsNormal) {
  const Pretravel p = lobing_probe();  // 2 µm + 3 µm cos²θ + 4 µm sin²θ cos(3(φ − 20°)), written out below
  const Point3 c(12.0, -40.0, 7.5);
  const double R = 12.5, r = 1.5;
  std::vector<Vector3> normals = sphere_cap_normals(50, 20.0);
  normals.push_back(Vector3(0.0, 0.0, 3.0));  // any length: the direction counts
  const SphereTouches t = touch_reference_sphere(c, R, r, normals, p, 0.0, 1);
  ASSERT_EQ(t.centres.size(), normals.size());
  for (std::size_t k = 0; k < normals.size(); ++k) {
    const Vector3 n = normals[k].normalized();
    const Vector3 travel = -n;
    // p(d) written out for this stylus (−z): θ from −z, φ about it, as Pretravel's header states.
    const double cos_t = travel.dot(-Vector3::UnitZ()), sin2 = 1.0 - cos_t * cos_t;
    const double phi = std::atan2(-travel.y(), travel.x());
    const double pd = 0.002 + 0.003 * cos_t * cos_t + 0.004 * sin2 * std::cos(3.0 * (phi - 20.0 * std::numbers::pi / 180));
    EXPECT_LT((t.centres[k] - (c + (R + r - pd) * n)).norm(), 1e-12) << k;
    EXPECT_LT((t.normals[k] - n).norm(), 1e-15);
  }
}

TEST(ReferenceSphere, NoiseHasItsSigmaOnEachCoordinate) {
  const std::vector<Vector3> normals(4000, Vector3::UnitZ());
  const SphereTouches t = touch_reference_sphere(Point3::Zero(), 10.0, 1.0, normals, Pretravel{}, 0.001, 5);
  Vector3 sum = Vector3::Zero(), sum2 = Vector3::Zero();
  for (const Point3& c : t.centres) {
    const Vector3 e = c - Point3(0.0, 0.0, 11.0);
    sum += e;
    sum2 += e.cwiseProduct(e);
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(sum[i] / 4000.0, 0.0, 0.0001);                // 6 standard errors of the mean
    EXPECT_NEAR(std::sqrt(sum2[i] / 4000.0), 0.001, 0.00007);  // about 6 standard errors of σ
  }
}

}  // namespace
}  // namespace probecomp::simulation
