#include "probecomp/nurbs/constructors.hpp"

#include <gtest/gtest.h>

#include <numbers>

namespace probecomp::nurbs {
namespace {

TEST(PlanePatch, IsExactlyTheLinearMapInEveryDegree) {
  const Point3 o(3, -1, 2);
  const Vector3 a(40, 5, 0), b(-2, 30, 7);
  const Vector3 n = a.cross(b).normalized();
  for (auto [p, q, su, sv] : {std::array{1, 1, 1, 1}, std::array{3, 3, 4, 5}, std::array{2, 5, 3, 1}}) {
    const Surface s = make_plane_patch(o, a, b, p, q, su, sv);
    EXPECT_EQ(s.p(), p);
    EXPECT_EQ(s.U().num_spans(), su);
    for (int i = 0; i <= 20; ++i) {
      for (int j = 0; j <= 20; ++j) {
        const double u = i / 20.0, v = j / 20.0;
        const SurfaceD2 d = derivatives_d2(s, u, v);
        EXPECT_LT((d.S - (o + u * a + v * b)).norm(), 1e-12);
        EXPECT_LT((d.Su - a).norm(), 1e-12);
        EXPECT_LT((d.Sv - b).norm(), 1e-12);
        EXPECT_LT(d.Suu.norm() + d.Suv.norm() + d.Svv.norm(), 1e-10);
        EXPECT_LT((unit_normal(s, u, v).n - n).norm(), 1e-14);
      }
    }
  }
}

TEST(CylinderSection, IsExactWithUnequalWeightsAndOutwardNormal) {
  const Point3 c(5, 5, -3);
  const Vector3 X(0, 1, 0), Y(0, 0, 1);  // axis = X × Y = +x
  const double R = 12.5, h = 40.0;
  const Surface s = make_cylinder_section(c, X, Y, R, -0.3, 2.2, h);
  EXPECT_TRUE(s.is_rational());
  EXPECT_EQ(s.p(), 2);
  EXPECT_EQ(s.q(), 1);
  for (int i = 0; i <= 50; ++i) {
    for (int j = 0; j <= 10; ++j) {
      const double u = i / 50.0, v = j / 10.0;
      const Point3 P = evaluate(s, u, v);
      const Vector3 d = P - c;
      const Vector3 radial(0, d.y(), d.z());
      EXPECT_NEAR(radial.norm(), R, 1e-12);
      EXPECT_NEAR(d.x(), v * h, 1e-12);
      EXPECT_LT((unit_normal(s, u, v).n - radial.normalized()).norm(), 1e-12);
    }
  }
  const Point3 start = c + R * (std::cos(-0.3) * X + std::sin(-0.3) * Y);
  EXPECT_LT((evaluate(s, 0, 0) - start).norm(), 1e-12);
}

TEST(Revolved, SphereIsExactWithOutwardNormalsAndPoles) {
  const Point3 c(150, 80, -40);
  const Vector3 axis = Vector3(1, 2, 2).normalized();
  const double R = 12.5;
  const Surface s = make_sphere(c, axis, R);
  EXPECT_EQ(s.p(), 2);
  EXPECT_EQ(s.q(), 2);
  for (int i = 0; i <= 40; ++i) {
    for (int j = 0; j <= 20; ++j) {
      const double u = i / 40.0, v = j / 20.0;
      const Vector3 d = evaluate(s, u, v) - c;
      EXPECT_NEAR(d.norm(), R, 1e-12) << u << " " << v;
      EXPECT_LT((unit_normal(s, u, v).n - d.normalized()).norm(), 1e-9) << u << " " << v;
    }
  }
  EXPECT_LT((evaluate(s, 0.3, 0.0) - (c - R * axis)).norm(), 1e-12);  // v = 0: the pole -axis
  EXPECT_LT((evaluate(s, 0.7, 1.0) - (c + R * axis)).norm(), 1e-12);
}

TEST(Revolved, TorusIsExactWithOutwardNormals) {
  const Point3 c(-20, 5, 7);
  const Vector3 a = Vector3(0, 1, 1).normalized();
  const double R = 30.0, r = 4.0;
  const Surface s = make_torus(c, a, R, r);
  for (int i = 0; i <= 40; ++i) {
    for (int j = 0; j <= 40; ++j) {
      const double u = i / 40.0, v = j / 40.0;
      const Vector3 d = evaluate(s, u, v) - c;
      // The torus's implicit form: the point's distance from the centre circle is r.
      const Vector3 in_plane = d - d.dot(a) * a;
      const Vector3 from_tube_centre = d - R * in_plane.normalized();
      EXPECT_NEAR(from_tube_centre.norm(), r, 1e-12) << u << " " << v;
      EXPECT_LT((unit_normal(s, u, v).n - from_tube_centre.normalized()).norm(), 1e-9) << u << " " << v;
    }
  }
}

TEST(Constructors, RejectBadArguments) {
  EXPECT_THROW((void)make_circular_arc({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0.0, 0, 1), InvalidGeometry);
  EXPECT_THROW((void)make_circular_arc({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 1.0, 1, 1), InvalidGeometry);
  EXPECT_THROW((void)make_circular_arc({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 1.0, 0, 7), InvalidGeometry);
  EXPECT_THROW((void)make_cylinder_section({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 1.0, 0, 1, -1), InvalidGeometry);
  EXPECT_THROW((void)make_torus({0, 0, 0}, {0, 0, 1}, 1.0, 2.0), InvalidGeometry);
  // A profile crossing the axis does not sweep one surface.
  const Curve across = make_circular_arc({0, 0, 0}, {1, 0, 0}, {0, 0, 1}, 1.0, 0.0, 2.0 * std::numbers::pi);
  EXPECT_THROW((void)make_revolved_surface(across, {0, 0, 0}, {0, 0, 1}, 0.0, 1.0), InvalidGeometry);
}

}  // namespace
}  // namespace probecomp::nurbs
