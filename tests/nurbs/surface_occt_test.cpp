// Values and derivatives of random rational surfaces against OpenCASCADE's Geom_BSplineSurface.

#include <gtest/gtest.h>

#include <random>

#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>

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

// An unclamped surface (uniform knots, end multiplicity 1, as a file's uniform B-spline or OpenCASCADE's conversion
// of a surface of revolution gives it: NIST STC-06) and a periodic one come back clamped, with the same values at
// the same (u, v) over OpenCASCADE's parameter range.
TEST(SurfaceVsOpenCascade, UnclampedAndPeriodicSurfacesComeBackClampedAndTheSame) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3), weight(0.7, 1.4);
  for (const bool periodic : {false, true}) {
    SCOPED_TRACE(periodic ? "periodic in u" : "unclamped in u and v");
    constexpr int p = 2, q = 3, nu = 7, nv = 6;
    TColgp_Array2OfPnt poles(1, nu, 1, nv);
    TColStd_Array2OfReal weights(1, nu, 1, nv);
    for (int i = 1; i <= nu; ++i) {
      for (int j = 1; j <= nv; ++j) {
        const double a = 2.0 * M_PI * (i - 1) / nu;
        poles.SetValue(i, j, periodic ? gp_Pnt(20.0 * std::cos(a), 20.0 * std::sin(a), 4.0 * j + jitter(rng))
                                      : gp_Pnt(5.0 * i, 4.0 * j, jitter(rng)));
        weights.SetValue(i, j, weight(rng));
      }
    }
    // Unclamped: every knot simple (n + p + 1 of them in u, m + q + 1 in v). Periodic in u: nu + 1 simple knots,
    // and v clamped with two simple interior knots.
    const int ku = periodic ? nu + 1 : nu + p + 1, kv = periodic ? 4 : nv + q + 1;
    TColStd_Array1OfReal uk(1, ku), vk(1, kv);
    TColStd_Array1OfInteger um(1, ku), vm(1, kv);
    for (int i = 1; i <= ku; ++i) {
      uk.SetValue(i, i - 1.0);
      um.SetValue(i, 1);
    }
    for (int j = 1; j <= kv; ++j) {
      vk.SetValue(j, periodic ? j - 1.0 : 0.5 * (j - 1));
      vm.SetValue(j, periodic && (j == 1 || j == kv) ? q + 1 : 1);
    }
    const Handle(Geom_BSplineSurface) ref = new Geom_BSplineSurface(poles, weights, uk, vk, um, vm, p, q, periodic, false);
    const Surface s = occt::from_occt(ref);
    EXPECT_EQ(s.U().multiplicity(s.U().front()), p + 1);
    EXPECT_EQ(s.V().multiplicity(s.V().front()), q + 1);
    double u0 = 0.0, u1 = 0.0, v0 = 0.0, v1 = 0.0;
    ref->Bounds(u0, u1, v0, v1);
    const Domain d = s.domain();
    EXPECT_DOUBLE_EQ(d.u0, u0);
    EXPECT_DOUBLE_EQ(d.u1, u1);
    EXPECT_DOUBLE_EQ(d.v0, v0);
    EXPECT_DOUBLE_EQ(d.v1, v1);
    std::uniform_real_distribution<double> t(0.0, 1.0);
    double worst = 0.0;
    for (int k = 0; k < 1000; ++k) {
      const double u = u0 + (u1 - u0) * t(rng), v = v0 + (v1 - v0) * t(rng);
      worst = std::max(worst, (evaluate(s, u, v) - v3(ref->Value(u, v))).norm());
    }
    EXPECT_LT(worst, 1e-12);
  }
}

}  // namespace
}  // namespace probecomp::nurbs
