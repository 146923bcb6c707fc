// The osculating paraboloid against closed forms: distances, normals and feet of points near a sphere and a torus,
// and of the spheres and tori a tip radius out from them.

#include "probecomp/nurbs/osculating_patch.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "probecomp/nurbs/constructors.hpp"

namespace probecomp::nurbs {
namespace {

struct Foot {
  double u, v;
  Point3 p;
  Vector3 n;
  Vector3 e1, e2;  // unit tangents along S_u and orthogonal to it
};

Foot foot_at(const nurbs::Surface& s, double u, double v) {
  const nurbs::SurfaceD2 d = nurbs::derivatives_d2(s, u, v);
  Foot f{u, v, d.S, d.Su.cross(d.Sv).normalized(), d.Su.normalized(), Vector3::Zero()};
  f.e2 = f.n.cross(f.e1);
  return f;
}

// A sphere of radius R about the origin: the distance of x from the sphere of radius R + e is |x| − R − e, its
// gradient x/|x|, its foot (R + e) x/|x|, on the original sphere R x/|x|.
TEST(OsculatingPatch, NearASphereDistanceNormalAndFootAreRightToThirdOrder) {
  const double R = 10.0;
  const nurbs::Surface s = nurbs::make_sphere({0, 0, 0}, {0, 0, 1}, R);
  for (const double e : {0.0, 2.0, -3.0}) {
    const Foot f = foot_at(s, 0.3, 0.4);
    const OsculatingPatch patch = OsculatingPatch::at(nurbs::derivatives_d2(s, f.u, f.v), f.n, e);
    ASSERT_TRUE(patch.valid());
    const Point3 foot = f.p + e * f.n;
    const double Re = R + e;
    double previous = 0.0;
    for (const double t : {0.4, 0.2, 0.1}) {
      for (const double h : {0.0, 0.005, -0.005}) {
        const Vector3 dir = (0.6 * f.e1 + 0.8 * f.e2).normalized();
        const Point3 x = foot + t * dir + h * f.n;
        const OsculatingPatch::Prediction p = patch.predict(foot, f.n, x);
        const double exact = x.norm() - Re;
        // Error: t⁴/(8 R³) from the sphere's next term, t² h / (2 R²) from x's own offset, and the floats'.
        EXPECT_NEAR(p.distance, exact, std::pow(t, 4) / (4 * std::pow(Re, 3)) + t * t * std::abs(h) / (Re * Re) + 1e-9)
            << "e " << e << " t " << t << " h " << h;
        EXPECT_LT((p.gradient - x.normalized()).norm(), t * t / (Re * Re) + 1e-6) << "e " << e << " t " << t;
        // The foot on the original sphere at the predicted parameters, against the exact one: second order in t.
        const Point3 predicted = nurbs::evaluate(s, f.u + p.du, f.v + p.dv);
        EXPECT_LT((predicted - R * x.normalized()).norm(), t * t * R / (Re * Re)) << "e " << e << " t " << t;
        if (h == 0.0) {
          // Third order: a tangent plane would be out by t²/(2R), 8e-3 mm at t = 0.4.
          if (previous > 0.0) {
            EXPECT_LT(std::abs(p.distance - exact), 0.2 * previous) << "e " << e << " t " << t;
          }
          previous = std::abs(p.distance - exact);
        }
      }
    }
  }
}

// A torus about z, radii a (centre circle) and b (tube): the distance of x is √((ρ − a)² + z²) − b, ρ = √(x² + y²).
// Its two curvatures differ and its principal directions are not its parameter lines' bisectors, so this checks the
// forms' orientation and the mixed terms.
TEST(OsculatingPatch, NearATorusWithUnequalCurvaturesTheDistanceIsRightToThirdOrder) {
  const double a = 20.0, b = 5.0;
  const nurbs::Surface s = nurbs::make_torus({0, 0, 0}, {0, 0, 1}, a, b);
  auto distance = [&](const Point3& x, double e) { return std::hypot(std::hypot(x.x(), x.y()) - a, x.z()) - b - e; };
  for (const double e : {0.0, 1.5}) {
    for (const auto& [u, v] : {std::pair{0.1, 0.2}, std::pair{0.37, 0.61}, std::pair{0.8, 0.45}}) {
      const Foot f = foot_at(s, u, v);
      ASSERT_LT(std::abs(distance(f.p, 0.0)), 1e-9);
      const OsculatingPatch patch = OsculatingPatch::at(nurbs::derivatives_d2(s, u, v), f.n, e);
      ASSERT_TRUE(patch.valid());
      const Point3 foot = f.p + e * f.n;
      double plane_error = 0.0, patch_error = 0.0;
      for (const double angle : {0.0, 0.7, 1.9}) {
        const Vector3 dir = std::cos(angle) * f.e1 + std::sin(angle) * f.e2;
        for (const double t : {0.2, 0.1}) {
          const Point3 x = foot + t * dir;
          const OsculatingPatch::Prediction p = patch.predict(foot, f.n, x);
          const double exact = distance(x, e);
          // Third order in t over the smaller radius (b + e here): the plane's error t²/(2(b + e)) is 1000 times more.
          EXPECT_NEAR(p.distance, exact, std::pow(t, 3) / std::pow(b + e, 2)) << u << " " << v << " " << angle;
          plane_error += std::abs(x.dot(f.n) - foot.dot(f.n) - exact);
          patch_error += std::abs(p.distance - exact);
        }
      }
      // Summed over directions: in one near an asymptotic direction (κ_n ≈ 0 where the torus is saddle-shaped) the
      // plane is good too.
      EXPECT_GT(plane_error, 30 * patch_error) << u << " " << v;
    }
  }
}

TEST(OsculatingPatch, AtAPoleWhereTheTangentsVanishItIsInvalid) {
  const nurbs::Surface s = nurbs::make_sphere({0, 0, 0}, {0, 0, 1}, 10.0);
  // The profile, from pole to pole, is the v direction; S_u vanishes at its ends (to rounding: 3e-15).
  const nurbs::SurfaceD2 d = nurbs::derivatives_d2(s, 0.3, s.domain().v0);
  ASSERT_LT((d.S - Point3(0, 0, -10)).norm(), 1e-12);
  EXPECT_FALSE(OsculatingPatch::at(d, Vector3(0, 0, -1)).valid());
}

}  // namespace
}  // namespace probecomp::nurbs
