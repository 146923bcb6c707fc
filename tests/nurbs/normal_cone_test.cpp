// The normal polynomial N = W³ S_u × S_v of a rational Bézier patch, against the surface's own normals, and the
// cone of its coefficients as a bound on every normal of a sub-patch.

#include "probecomp/nurbs/normal_cone.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "probecomp/nurbs/knot_insertion.hpp"
#include "probecomp/nurbs/surface.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::nurbs {
namespace {

// Σ B_i(s) B_j(t) c_ij, the Bernstein basis from its definition C(n,i) s^i (1−s)^(n−i).
Vector3 evaluate_patch(const BernsteinVectorPatch& f, double s, double t) {
  auto bernstein = [](int n, int i, double x) {
    double c = 1.0;
    for (int k = 1; k <= i; ++k) c = c * (n - i + k) / k;
    return c * std::pow(x, i) * std::pow(1.0 - x, n - i);
  };
  Vector3 sum = Vector3::Zero();
  for (int i = 0; i <= f.du; ++i)
    for (int j = 0; j <= f.dv; ++j) sum += bernstein(f.du, i, s) * bernstein(f.dv, j, t) * f.c[static_cast<std::size_t>(i * (f.dv + 1) + j)];
  return sum;
}

// One rational Bézier patch: the single span of a random surface with p+1 × q+1 control points.
Surface bezier_patch(std::uint64_t seed, int p, int q, double weight_max) {
  return testing::random_rational_surface(seed, {.p = p, .q = q, .nu = p + 1, .nv = q + 1, .height = 40.0,
                                                 .weight_min = 0.3, .weight_max = weight_max});
}

std::vector<HomogeneousPoint> net_of(const Surface& s) { return s.homogeneous(); }

// N at random (u, v) points the way of S_u × S_v: same sense, parallel to 1e-10.
void expect_along_the_normals(const Surface& s, const BernsteinVectorPatch& N, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    const double u = t(rng), v = t(rng);
    const SurfaceD1 d = derivatives_d1(s, u, v);
    const Vector3 cross = d.Su.cross(d.Sv);
    const Vector3 n = evaluate_patch(N, u, v);
    EXPECT_GT(n.dot(cross), 0.0);
    EXPECT_NEAR(n.normalized().cross(cross.normalized()).norm(), 0.0, 1e-10) << s.p() << "x" << s.q();
  }
}

// N = W³ S_u × S_v up to the positive factor p·q dropped from the derivatives.
TEST(NormalCone, NormalPolynomialPointsAlongTheSurfaceNormal) {
  const int degrees[][2] = {{3, 3}, {2, 3}, {1, 2}, {4, 1}};
  std::uint64_t seed = 40;
  for (const auto& [p, q] : degrees) {
    const Surface s = bezier_patch(seed++, p, q, 3.0);
    const BernsteinVectorPatch N = normal_polynomial(p, q, net_of(s));
    ASSERT_EQ(N.du, 3 * p - 1);  // rational: weights differ
    ASSERT_EQ(N.dv, 3 * q - 1);
    expect_along_the_normals(s, N, seed);
  }
}

TEST(NormalCone, EqualWeightsGiveTheLowerDegreePolynomial) {
  const Surface s = testing::random_rational_surface(5, {.p = 3, .q = 2, .nu = 4, .nv = 3, .height = 40.0,
                                                         .weight_min = 1.0, .weight_max = 1.0});
  const BernsteinVectorPatch N = normal_polynomial(3, 2, net_of(s));
  ASSERT_EQ(N.du, 5);
  ASSERT_EQ(N.dv, 3);
  expect_along_the_normals(s, N, 4);
}

TEST(NormalCone, SplitPiecesAreTheRestrictions) {
  const Surface s = bezier_patch(8, 3, 3, 2.0);
  const BernsteinVectorPatch N = normal_polynomial(3, 3, net_of(s));
  for (const int direction : {0, 1}) {
    const auto pieces = split_patch(N, direction, 5);
    ASSERT_EQ(pieces.size(), 5u);
    for (int k = 0; k < 5; ++k) {
      const BernsteinVectorPatch R = direction == 0 ? restrict_patch(N, k / 5.0, (k + 1) / 5.0, 0.0, 1.0)
                                                    : restrict_patch(N, 0.0, 1.0, k / 5.0, (k + 1) / 5.0);
      for (std::size_t c = 0; c < R.c.size(); ++c) EXPECT_NEAR((pieces[k].c[c] - R.c[c]).norm(), 0.0, 1e-9 * R.c[c].norm() + 1e-12);
    }
  }
}

TEST(NormalCone, RestrictedPatchIsTheSamePolynomialOnTheSubBox) {
  const Surface s = bezier_patch(7, 3, 3, 2.0);
  const BernsteinVectorPatch N = normal_polynomial(3, 3, net_of(s));
  const BernsteinVectorPatch R = restrict_patch(N, 0.25, 0.625, 0.5, 0.75);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    const double a = t(rng), b = t(rng);
    const Vector3 expected = evaluate_patch(N, 0.25 + 0.375 * a, 0.5 + 0.25 * b);
    EXPECT_NEAR((evaluate_patch(R, a, b) - expected).norm(), 0.0, 1e-10 * expected.norm());
  }
}

// Every normal of a sub-patch lies within the cone, and the cone closes in as the sub-patch shrinks.
TEST(NormalCone, ConeHoldsEveryNormalOfTheSubPatch) {
  const Surface s = bezier_patch(11, 3, 3, 3.0);
  const BernsteinVectorPatch N = normal_polynomial(3, 3, net_of(s));
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  double previous_angle = M_PI;
  for (const double size : {0.5, 0.25, 0.125, 0.0625}) {
    const double u0 = 0.3, v0 = 0.4;
    const Vector3 axis = unit_normal(s, u0 + size / 2, v0 + size / 2).n;
    const double c = normal_cone_cosine(restrict_patch(N, u0, u0 + size, v0, v0 + size), axis);
    ASSERT_GT(c, 0.0) << size;
    for (int trial = 0; trial < 400; ++trial) {
      const double dv = t(rng), du = t(rng);  // in this order: the draws gcc made when they were the call's arguments
      const Vector3 n = unit_normal(s, u0 + size * du, v0 + size * dv).n;
      EXPECT_GE(n.dot(axis), c - 1e-12) << size;
    }
    const double angle = std::acos(c);
    EXPECT_LT(angle, previous_angle);
    previous_angle = angle;
  }
  EXPECT_LT(previous_angle, 0.2);  // radians: the cone of a small sub-patch is narrow
}

TEST(NormalCone, NoConeWhenTheNormalsTurnPastNinetyDegrees) {
  // A half cylinder (normals sweep 180°) about its middle normal.
  const std::vector<Point3> P = {{1, 0, 0}, {1, 0, 1}, {1, 1, 0}, {1, 1, 1}, {-1, 1, 0}, {-1, 1, 1}, {-1, 0, 0}, {-1, 0, 1}};
  // Rational quadratic in u would be exact; a cubic Bézier arc of the same sweep turns the normals just as far.
  const Surface s(KnotVector({0, 0, 0, 0, 1, 1, 1, 1}, 3), KnotVector({0, 0, 1, 1}, 1), P, {});
  const BernsteinVectorPatch N = normal_polynomial(3, 1, net_of(s));
  EXPECT_LE(normal_cone_cosine(N, unit_normal(s, 0.5, 0.5).n), 0.0);
}

}  // namespace
}  // namespace probecomp::nurbs
