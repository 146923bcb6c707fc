// Values and derivatives of random rational surfaces against OpenCASCADE's Geom_BSplineSurface.

#include <gtest/gtest.h>

#include <random>

#include "probecomp/nurbs/surface.hpp"
#include "probecomp/occt/convert.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::nurbs {
namespace {

Vector3 v3(const gp_Vec& v) { return {v.X(), v.Y(), v.Z()}; }
Vector3 v3(const gp_Pnt& p) { return {p.X(), p.Y(), p.Z()}; }

// Relative difference, scaled by the larger magnitude (and 1 mm, so tiny vectors compare absolutely).
double rel(const Vector3& a, const Vector3& b) { return (a - b).norm() / std::max({1.0, a.norm(), b.norm()}); }

TEST(SurfaceVsOpenCascade, ValuesAndDerivativesAgreeTo1e9Relative) {
  const testing::RandomSurfaceSpec specs[] = {
      {.p = 3, .q = 3, .nu = 8, .nv = 7},  {.p = 2, .q = 3, .nu = 6, .nv = 9},
      {.p = 1, .q = 2, .nu = 4, .nv = 5},  {.p = 5, .q = 4, .nu = 10, .nv = 8},
      {.p = 3, .q = 2, .nu = 20, .nv = 20, .weight_min = 0.2, .weight_max = 5.0},
  };
  std::uint64_t seed = 1;
  for (const auto& spec : specs) {
    const Surface s = testing::random_rational_surface(seed++, spec);
    ASSERT_TRUE(s.is_rational());
    const Handle(Geom_BSplineSurface) ref = occt::to_occt(s);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> t(0.0, 1.0);
    double worst[6] = {0, 0, 0, 0, 0, 0};
    for (int k = 0; k < 1000; ++k) {
      const double u = t(rng), v = t(rng);
      gp_Pnt P;
      gp_Vec Du, Dv, Duu, Dvv, Duv;
      ref->D2(u, v, P, Du, Dv, Duu, Dvv, Duv);
      const SurfaceD2 d = derivatives_d2(s, u, v);
      const double e[6] = {rel(d.S, v3(P)),    rel(d.Su, v3(Du)),   rel(d.Sv, v3(Dv)),
                           rel(d.Suu, v3(Duu)), rel(d.Suv, v3(Duv)), rel(d.Svv, v3(Dvv))};
      for (int m = 0; m < 6; ++m) worst[m] = std::max(worst[m], e[m]);
      EXPECT_LT(rel(evaluate(s, u, v), v3(P)), 1e-9);
      const SurfaceD1 d1 = derivatives_d1(s, u, v);
      EXPECT_LT(rel(d1.Su, v3(Du)), 1e-9);
      EXPECT_LT(rel(d1.Sv, v3(Dv)), 1e-9);
    }
    const char* names[6] = {"S", "Su", "Sv", "Suu", "Suv", "Svv"};
    for (int m = 0; m < 6; ++m) EXPECT_LT(worst[m], 1e-9) << names[m] << " p=" << spec.p << " q=" << spec.q;
  }
}

TEST(SurfaceVsOpenCascade, RoundTripThroughOpenCascadeKeepsTheSurface) {
  const Surface s = testing::random_rational_surface(42);
  const Surface back = occt::from_occt(occt::to_occt(s));
  ASSERT_EQ(back.num_u(), s.num_u());
  ASSERT_EQ(back.num_v(), s.num_v());
  for (int i = 0; i < s.num_u(); ++i)
    for (int j = 0; j < s.num_v(); ++j) EXPECT_LT((back.homogeneous(i, j) - s.homogeneous(i, j)).norm(), 1e-12);
  EXPECT_TRUE(std::equal(back.U().knots().begin(), back.U().knots().end(), s.U().knots().begin()));
}

}  // namespace
}  // namespace probecomp::nurbs
