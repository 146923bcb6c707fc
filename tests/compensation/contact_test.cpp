// contact_points on exact centre surfaces: the contact points must land on the part surface itself.

#include "probecomp/compensation/contact.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "probecomp/fitting/offset.hpp"
#include "probecomp/nurbs/constructors.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::compensation {
namespace {

TEST(ContactPoints, OnACylinderTheContactsLieOnTheCylinderWithRadialNormals) {
  // A shaft of radius 10 mm probed from outside with a 1.5 mm tip: centres on the radius-11.5 cylinder, moved
  // off it by up to 0.02 mm (noise the smoothing removes).
  const nurbs::Surface centre =
      nurbs::make_cylinder_section({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 11.5, 0.1, 2.5, 40.0);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> t(0.0, 1.0), e(-0.02, 0.02);
  std::vector<Point3> raw;
  std::vector<fitting::SurfaceParameter> params;
  for (int k = 0; k < 2000; ++k) {
    const double u = t(rng), v = t(rng);
    const Point3 s = nurbs::evaluate(centre, u, v);
    raw.push_back(s + e(rng) * Vector3(s.x(), s.y(), 0.0).normalized());
    params.push_back({std::clamp(u + 0.01 * e(rng), 0.0, 1.0), v});  // parameters a little off, as from registration
  }
  const std::vector<ContactPoint> c = contact_points(centre, +1, 1.5, raw, params);
  ASSERT_EQ(c.size(), raw.size());
  for (std::size_t k = 0; k < c.size(); ++k) {
    ASSERT_TRUE(c[k].ok()) << k;
    EXPECT_NEAR(std::hypot(c[k].contact.x(), c[k].contact.y()), 10.0, 1e-9);
    const Vector3 radial = Vector3(c[k].contact.x(), c[k].contact.y(), 0.0).normalized();
    EXPECT_NEAR(c[k].normal.dot(radial), 1.0, 1e-12);
    EXPECT_NEAR(c[k].contact.z(), raw[k].z(), 1e-9);  // the projection is radial
  }
}

TEST(ContactPoints, InsideABoreTheMaterialIsOutwardOfTheAxis) {
  // A bore of radius 10 mm probed from inside with a 1 mm tip: centres on radius 9, material beyond radius 10,
  // so S_u × S_v (away from the axis) points into the material: outward = −1.
  const nurbs::Surface centre = nurbs::make_cylinder_section({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 9.0, 0.0, 3.0, 20.0);
  std::vector<Point3> raw;
  std::vector<fitting::SurfaceParameter> params;
  for (int k = 0; k <= 100; ++k) {
    raw.push_back(nurbs::evaluate(centre, k / 100.0, 0.5));
    params.push_back({k / 100.0, 0.5});
  }
  for (const ContactPoint& c : contact_points(centre, -1, 1.0, raw, params)) {
    ASSERT_TRUE(c.ok());
    EXPECT_NEAR(std::hypot(c.contact.x(), c.contact.y()), 10.0, 1e-12);
  }
}

TEST(ContactPoints, OnAFreeFormOffsetTheContactsLieOnThePartWithinTheOffsetTolerance) {
  const nurbs::Surface part = testing::random_rational_surface(31, {.nu = 9, .nv = 8, .height = 3.0});
  const fitting::OffsetResult centre = fitting::offset_surface(part, 2.0);
  ASSERT_TRUE(centre.ok());
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  std::vector<Point3> raw;
  std::vector<fitting::SurfaceParameter> params;
  std::vector<Point3> truth;
  for (int k = 0; k < 2000; ++k) {
    const double u = t(rng), v = t(rng);
    raw.push_back(nurbs::evaluate(centre.surface, u, v));
    params.push_back({u, v});
    truth.push_back(nurbs::evaluate(part, u, v));
  }
  const std::vector<ContactPoint> c = contact_points(centre.surface, +1, 2.0, raw, params);
  for (std::size_t k = 0; k < c.size(); ++k) {
    ASSERT_TRUE(c[k].ok());
    // The contact lies on the part (within the offset's tolerance, 1e-4 mm), next to the point whose offset
    // the centre is, with the part's normal there.
    const nurbs::ClosestPointResult on_part = nurbs::refine_closest_point(part, c[k].contact, params[k].u, params[k].v);
    ASSERT_TRUE(on_part.ok());
    EXPECT_LE(on_part.distance, 1e-4) << k;
    EXPECT_LE((c[k].contact - truth[k]).norm(), 1e-3) << k;
    EXPECT_NEAR(c[k].normal.dot(nurbs::unit_normal(part, on_part.u, on_part.v).n), 1.0, 1e-6);
  }
}

TEST(ContactPoints, AFailedProjectionKeepsItsRowAndSaysSo) {
  const nurbs::Surface centre = nurbs::make_plane_patch({0, 0, 0}, {10, 0, 0}, {0, 10, 0});
  const std::vector<Point3> raw{{1, 1, 1}, {std::nan(""), 0, 0}};
  const std::vector<fitting::SurfaceParameter> params{{0.1, 0.1}, {0.5, 0.5}};
  const std::vector<ContactPoint> c = contact_points(centre, +1, 1.0, raw, params);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_TRUE(c[0].ok());
  EXPECT_NEAR((c[0].contact - Point3(1, 1, -1)).norm(), 0.0, 1e-12);
  EXPECT_FALSE(c[1].ok());
}

}  // namespace
}  // namespace probecomp::compensation
