// Degree elevation leaves the surface and its parametrisation unchanged (checked pointwise against the
// original, to 1e-12 mm), in u and in v, for a rational surface with interior knots and a bilinear one.

#include <gtest/gtest.h>

#include <random>

#include "probecomp/nurbs/constructors.hpp"
#include "probecomp/nurbs/degree_elevation.hpp"
#include "support/test_surfaces.hpp"

namespace {

using namespace probecomp;

double largest_gap(const nurbs::Surface& a, const nurbs::Surface& b) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  const nurbs::Domain d = a.domain();
  double worst = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const double u = d.u0 + t(rng) * (d.u1 - d.u0), v = d.v0 + t(rng) * (d.v1 - d.v0);
    worst = std::max(worst, (nurbs::evaluate(a, u, v) - nurbs::evaluate(b, u, v)).norm());
  }
  return worst;
}

TEST(DegreeElevation, RationalSurfaceWithInteriorKnotsKeepsItsShape) {
  const nurbs::Surface s = probecomp::testing::random_rational_surface(11, {.p = 3, .q = 2, .nu = 7, .nv = 6});
  const nurbs::Surface u = nurbs::elevate_degree_u(s, 2);
  const nurbs::Surface v = nurbs::elevate_degree_v(s, 1);
  EXPECT_EQ(u.p(), s.p() + 2);
  EXPECT_EQ(v.q(), s.q() + 1);
  EXPECT_EQ(u.q(), s.q());
  EXPECT_LT(largest_gap(s, u), 1e-12);
  EXPECT_LT(largest_gap(s, v), 1e-12);
  // Bézier decomposition: each of the u spans becomes one segment of degree p + t.
  EXPECT_EQ(u.num_u(), s.U().num_spans() * u.p() + 1);
}

TEST(DegreeElevation, BilinearPatchBecomesACubicOfTheSameShape) {
  const nurbs::Surface s = nurbs::make_plane_patch(Point3(1, 2, 3), Vector3(10, 0, 1), Vector3(0, 5, 0));
  const nurbs::Surface c = nurbs::elevate_degree_v(nurbs::elevate_degree_u(s, 2), 2);
  EXPECT_EQ(c.p(), 3);
  EXPECT_EQ(c.q(), 3);
  EXPECT_EQ(c.num_u(), 4);
  EXPECT_LT(largest_gap(s, c), 1e-12);
  EXPECT_THROW((void)nurbs::elevate_degree_u(s, nurbs::kMaxDegree), nurbs::InvalidGeometry);
}

}  // namespace
