#include "probecomp/nurbs/curve.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "probecomp/nurbs/constructors.hpp"

namespace probecomp::nurbs {
namespace {

Curve wavy_rational_curve() {
  const KnotVector U({0, 0, 0, 0, 0.3, 0.3, 0.55, 1, 1, 1, 1}, 3);
  std::vector<Point3> P = {{0, 0, 0}, {1, 2, 0}, {2, -1, 1}, {3, 3, -1}, {4, 0, 2}, {5, 1, 0}, {6, -2, 1}};
  std::vector<double> w = {1.0, 0.6, 1.8, 0.9, 1.3, 0.7, 1.1};
  return Curve(U, P, w);
}

TEST(Curve, DerivativesMatchCentralDifferences) {
  const Curve c = wavy_rational_curve();
  const double h = 1e-6;
  for (double u : {0.05, 0.2, 0.42, 0.5, 0.8, 0.97}) {
    const CurveD2 d = derivatives_d2(c, u);
    EXPECT_LT((d.C - evaluate(c, u)).norm(), 1e-14);
    const Vector3 fd1 = (evaluate(c, u + h) - evaluate(c, u - h)) / (2 * h);
    const Vector3 fd2 = (derivatives_d2(c, u + h).Cu - derivatives_d2(c, u - h).Cu) / (2 * h);
    EXPECT_LT((d.Cu - fd1).norm(), 1e-6 * (1 + d.Cu.norm())) << u;
    EXPECT_LT((d.Cuu - fd2).norm(), 1e-5 * (1 + d.Cuu.norm())) << u;
  }
}

TEST(Curve, KnotInsertionLeavesTheCurveUnchanged) {
  const Curve c = wavy_rational_curve();
  const Curve once = insert_knot(c, 0.7);
  const Curve twice = insert_knot(c, 0.3, 1);  // 0.3 reaches multiplicity 3 = p
  EXPECT_EQ(once.num_control_points(), c.num_control_points() + 1);
  EXPECT_EQ(twice.knots().multiplicity(0.3), 3);
  for (int k = 0; k <= 200; ++k) {
    const double u = k / 200.0;
    EXPECT_LT((evaluate(once, u) - evaluate(c, u)).norm(), 1e-12);
    EXPECT_LT((evaluate(twice, u) - evaluate(c, u)).norm(), 1e-12);
  }
  EXPECT_THROW((void)insert_knot(c, 0.3, 2), InvalidGeometry);  // multiplicity 4 > p
  EXPECT_THROW((void)insert_knot(c, 1.0), InvalidGeometry);     // not inside the domain
}

TEST(Curve, RejectsNonPositiveWeights) {
  const KnotVector U = KnotVector::uniform(1, 1);
  EXPECT_THROW(Curve(U, std::vector<Point3>{{0, 0, 0}, {1, 0, 0}}, {1.0, 0.0}), InvalidGeometry);
  EXPECT_THROW(Curve(U, std::vector<Point3>{{0, 0, 0}}), InvalidGeometry);
}

TEST(CircularArc, LiesExactlyOnTheCircleWithUnequalWeights) {
  const Point3 centre(1, -2, 3);
  const Vector3 X = Vector3(1, 1, 0).normalized();
  const Vector3 Y = Vector3(-1, 1, 1).normalized();  // orthogonal to X
  const Vector3 Z = X.cross(Y);
  for (double sweep : {0.3, std::numbers::pi / 2, 2.0, 1.5 * std::numbers::pi, 2 * std::numbers::pi}) {
    const double start = 0.4;
    const Curve arc = make_circular_arc(centre, X, Y, 7.5, start, start + sweep);
    bool unequal = false;
    for (int i = 1; i < arc.num_control_points(); ++i) unequal |= arc.weight(i) != arc.weight(0);
    EXPECT_TRUE(unequal);
    for (int k = 0; k <= 400; ++k) {
      const Point3 P = evaluate(arc, k / 400.0);
      const Vector3 d = P - centre;
      EXPECT_NEAR(d.norm(), 7.5, 1e-12);
      EXPECT_NEAR(d.dot(Z), 0.0, 1e-12);
    }
    const Point3 end = centre + 7.5 * (std::cos(start + sweep) * X + std::sin(start + sweep) * Y);
    EXPECT_LT((evaluate(arc, 1.0) - end).norm(), 1e-12);
    // The parameter runs counter-clockwise about Z: the tangent at the start is along +Y rotated by start.
    const Vector3 t0 = derivatives_d2(arc, 0.0).Cu.normalized();
    EXPECT_LT((t0 - (-std::sin(start) * X + std::cos(start) * Y)).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace probecomp::nurbs
