#include "probecomp/nurbs/surface.hpp"

#include <gtest/gtest.h>

#include <iostream>
#include <random>

#include "support/test_surfaces.hpp"

namespace probecomp::nurbs {
namespace {

using testing::random_rational_surface;
using testing::RandomSurfaceSpec;

struct DegreeCase {
  int p, q, nu, nv;
};
const DegreeCase kDegreeCases[] = {{3, 3, 8, 7}, {2, 3, 6, 9}, {1, 2, 4, 5}, {4, 2, 9, 6}, {5, 5, 10, 9}};

// Central differences of the analytic first derivatives: an independent check of the second derivatives,
// and in particular of the mixed S_uv, which A4.4 implementations get wrong most often.
TEST(Surface, SecondDerivativesMatchCentralDifferences) {
  std::uint64_t seed = 100;
  for (const auto& dc : kDegreeCases) {
    const Surface s = random_rational_surface(seed++, {.p = dc.p, .q = dc.q, .nu = dc.nu, .nv = dc.nv});
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> t(0.01, 0.99);
    const double h = 1e-6;
    double worst_uv = 0.0;
    for (int k = 0; k < 200; ++k) {
      double u = t(rng), v = t(rng);
      // Keep the stencil inside one knot span in each direction (the surface is only C^{p-m} at knots).
      const int su = s.U().find_span(u), sv = s.V().find_span(v);
      u = std::clamp(u, s.U()[su] + 2 * h, s.U()[su + 1] - 2 * h);
      v = std::clamp(v, s.V()[sv] + 2 * h, s.V()[sv + 1] - 2 * h);
      const SurfaceD2 d = derivatives_d2(s, u, v);
      const SurfaceD1 up = derivatives_d1(s, u + h, v), um = derivatives_d1(s, u - h, v);
      const SurfaceD1 vp = derivatives_d1(s, u, v + h), vm = derivatives_d1(s, u, v - h);
      const double scale = 1.0 + d.Su.norm() + d.Sv.norm();
      EXPECT_LT((d.Su - (evaluate(s, u + h, v) - evaluate(s, u - h, v)) / (2 * h)).norm(), 1e-5 * scale);
      EXPECT_LT((d.Sv - (evaluate(s, u, v + h) - evaluate(s, u, v - h)) / (2 * h)).norm(), 1e-5 * scale);
      EXPECT_LT((d.Suu - (up.Su - um.Su) / (2 * h)).norm(), 1e-4 * (scale + d.Suu.norm()));
      EXPECT_LT((d.Svv - (vp.Sv - vm.Sv) / (2 * h)).norm(), 1e-4 * (scale + d.Svv.norm()));
      // S_uv two ways: ∂/∂v of S_u and ∂/∂u of S_v.
      const double e1 = (d.Suv - (vp.Su - vm.Su) / (2 * h)).norm() / (scale + d.Suv.norm());
      const double e2 = (d.Suv - (up.Sv - um.Sv) / (2 * h)).norm() / (scale + d.Suv.norm());
      worst_uv = std::max({worst_uv, e1, e2});
      EXPECT_LT((d.S - evaluate(s, u, v)).norm(), 1e-12);
    }
    EXPECT_LT(worst_uv, 1e-5) << "p=" << dc.p << " q=" << dc.q;
  }
}

// A caller that knows the knot spans (the closest-point search inside a cell) gets what the span search gives.
TEST(Surface, KnownKnotSpansGiveTheSameDerivatives) {
  const Surface s = random_rational_surface(31, {.p = 3, .q = 2, .nu = 9, .nv = 7});
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const double u = t(rng), v = t(rng);
    const KnotSpans spans{s.U().find_span(u), s.V().find_span(v)};
    const SurfaceD2 a = derivatives_d2(s, u, v), b = derivatives_d2(s, u, v, spans);
    EXPECT_EQ(a.S, b.S);
    EXPECT_EQ(a.Su, b.Su);
    EXPECT_EQ(a.Suv, b.Suv);
    EXPECT_EQ(a.Svv, b.Svv);
    EXPECT_EQ(evaluate(s, u, v), evaluate(s, u, v, spans));
  }
}

// Bicubic derivatives take 256-bit registers where the processor has AVX (half the operations). Each lane does the
// portable SSE2 form's multiplication and addition in the same order, so the two must agree to the last bit:
// results may not depend on the machine. Rational and non-rational, on knot span ends and inside.
TEST(Surface, BicubicDerivativesAreTheSameBitForBitWithAndWithoutAvx) {
  struct Restore {
    ~Restore() { detail::avx_evaluation = true; }
  } restore;
#if defined(__x86_64__)
  if (!__builtin_cpu_supports("avx")) std::cout << "[ note ] no AVX here: both runs take the portable form\n";
#endif
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  const Surface surfaces[] = {random_rational_surface(41, {.nu = 9, .nv = 8, .weight_min = 0.3, .weight_max = 3.0}),
                              random_rational_surface(42, {.nu = 6, .nv = 11, .weight_min = 1.0, .weight_max = 1.0}),
                              testing::freeform_panel(43, 12)};
  for (const Surface& s : surfaces) {
    ASSERT_EQ(s.p(), 3);
    ASSERT_EQ(s.q(), 3);
    std::vector<std::pair<double, double>> at;
    for (int k = 0; k < 300; ++k) {
      const double v = t(rng), u = t(rng);  // as gcc drew them as the call's arguments
      at.emplace_back(u, v);
    }
    for (double u : s.U().breakpoints())
      for (double v : s.V().breakpoints()) at.emplace_back(u, v);
    for (const auto& [u, v] : at) {
      const KnotSpans spans{s.U().find_span(u), s.V().find_span(v)};
      detail::avx_evaluation = true;
      const SurfaceD2 a = derivatives_d2(s, u, v), a_spans = derivatives_d2(s, u, v, spans);
      const SurfaceD1 a1 = derivatives_d1(s, u, v);
      const Point3 a0 = evaluate(s, u, v);
      detail::avx_evaluation = false;
      const SurfaceD2 b = derivatives_d2(s, u, v), b_spans = derivatives_d2(s, u, v, spans);
      const SurfaceD1 b1 = derivatives_d1(s, u, v);
      const Point3 b0 = evaluate(s, u, v);
      for (const auto& [x, y] : {std::pair{&a, &b}, std::pair{&a_spans, &b_spans}}) {
        EXPECT_EQ(x->S, y->S) << u << ' ' << v;
        EXPECT_EQ(x->Su, y->Su);
        EXPECT_EQ(x->Sv, y->Sv);
        EXPECT_EQ(x->Suu, y->Suu);
        EXPECT_EQ(x->Suv, y->Suv);
        EXPECT_EQ(x->Svv, y->Svv);
      }
      EXPECT_EQ(a1.S, b1.S);
      EXPECT_EQ(a1.Su, b1.Su);
      EXPECT_EQ(a1.Sv, b1.Sv);
      EXPECT_EQ(a0, b0);
    }
  }
}

TEST(Surface, KnotInsertionInUAndVLeavesTheShapeUnchanged) {
  const Surface s = random_rational_surface(7);
  Surface r = insert_knot_u(s, 0.37);
  r = insert_knot_u(r, 0.37, 2);  // up to multiplicity p = 3
  r = insert_knot_v(r, 0.81);
  r = insert_knot_v(r, 0.123, 2);
  EXPECT_EQ(r.num_u(), s.num_u() + 3);
  EXPECT_EQ(r.num_v(), s.num_v() + 3);
  EXPECT_EQ(r.U().multiplicity(0.37), 3);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  double worst = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const double u = k < 4 ? (k & 1) : t(rng);
    const double v = k < 4 ? (k >> 1) : t(rng);
    worst = std::max(worst, (evaluate(r, u, v) - evaluate(s, u, v)).norm());
  }
  EXPECT_LT(worst, 1e-12) << "mm";
  EXPECT_THROW((void)insert_knot_u(r, 0.37), InvalidGeometry);
  EXPECT_THROW((void)insert_knot_v(s, 0.0), InvalidGeometry);
}

TEST(Surface, BoundingBoxContainsTheSurface) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const Surface s = random_rational_surface(seed);
    const BoundingBox box = bounding_box(s);
    for (int a = 0; a <= 60; ++a)
      for (int b = 0; b <= 60; ++b) EXPECT_TRUE(box.contains(evaluate(s, a / 60.0, b / 60.0), 1e-12));
  }
}

TEST(Surface, UnitNormalIsUnitAndOrthogonalToTheTangents) {
  const Surface s = random_rational_surface(21);
  for (int a = 0; a <= 20; ++a) {
    for (int b = 0; b <= 20; ++b) {
      const double u = a / 20.0, v = b / 20.0;
      const UnitNormal n = unit_normal(s, u, v);
      ASSERT_EQ(n.status, UnitNormal::Status::OK);
      const SurfaceD1 d = derivatives_d1(s, u, v);
      EXPECT_NEAR(n.n.norm(), 1.0, 1e-15);
      EXPECT_NEAR(n.n.dot(d.Su.normalized()), 0.0, 1e-14);
      EXPECT_NEAR(n.n.dot(d.Sv.normalized()), 0.0, 1e-14);
      EXPECT_GT(n.n.dot(d.Su.cross(d.Sv)), 0.0);
    }
  }
}

TEST(Surface, NormalAtAPoleIsTheLimitFromInside) {
  // A cone-like patch: the whole edge v = 0 collapses to the apex (0,0,1); elsewhere the patch is the flat
  // triangle-ish sheet z = 1 - x/2 so the limit normal is known exactly.
  std::vector<Point3> P;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double x = j * 1.0;
      const double y = (i - 1.0) * j * 0.5;
      P.emplace_back(x, y, 1.0 - 0.5 * x);
    }
  }
  const Surface s(KnotVector::uniform(2, 1), KnotVector::uniform(2, 1), P);
  const UnitNormal n = unit_normal(s, 0.5, 0.0);
  ASSERT_EQ(n.status, UnitNormal::Status::FromNeighbourhood);
  // The sheet is flat, so the limit equals the normal anywhere inside, sign included.
  const UnitNormal inside = unit_normal(s, 0.5, 0.3);
  ASSERT_EQ(inside.status, UnitNormal::Status::OK);
  EXPECT_LT((inside.n.cwiseAbs() - Vector3(0.5, 0.0, 1.0).normalized()).norm(), 1e-14);
  EXPECT_LT((n.n - inside.n).norm(), 1e-14);
}

TEST(Surface, TransposeSwapsTheParameters) {
  const Surface s = random_rational_surface(8, {.p = 2, .q = 3, .nu = 5, .nv = 6});
  const Surface t = transposed(s);
  EXPECT_EQ(t.p(), 3);
  EXPECT_EQ(t.q(), 2);
  for (double u : {0.0, 0.3, 0.77, 1.0})
    for (double v : {0.0, 0.5, 0.9}) EXPECT_LT((evaluate(t, v, u) - evaluate(s, u, v)).norm(), 1e-13);
}

TEST(Surface, RejectsInconsistentNets) {
  const KnotVector U = KnotVector::uniform(1, 1);
  EXPECT_THROW(Surface(U, U, std::vector<Point3>(3, Point3::Zero())), InvalidGeometry);
  EXPECT_THROW(Surface(U, U, std::vector<Point3>(4, Point3::Zero()), {1, 1, -1, 1}), InvalidGeometry);
}

}  // namespace
}  // namespace probecomp::nurbs

namespace {

// The grid evaluator is the point evaluator, summed in another order: equal to rounding.
TEST(GridRows, EqualThePointwiseDerivativesOnARationalSurface) {
  using namespace probecomp;
  const nurbs::Surface s = probecomp::testing::random_rational_surface(5, {.p = 3, .q = 2, .nu = 9, .nv = 7});
  std::vector<double> tu, tv;
  for (int a = 0; a <= 40; ++a) tu.push_back(a / 40.0);
  for (int b = 0; b <= 33; ++b) tv.push_back(b / 33.0);
  const nurbs::GridRows rows(s, tv), first_rows(s, tv, 1);
  std::vector<nurbs::SurfaceD2> grid(tu.size() * tv.size()), first(grid.size());
  for (std::size_t a = 0; a < tu.size(); ++a) {
    rows.row(tu[a], std::span<nurbs::SurfaceD2>(grid).subspan(a * tv.size(), tv.size()));
    first_rows.row(tu[a], std::span<nurbs::SurfaceD2>(first).subspan(a * tv.size(), tv.size()));
  }
  double worst = 0.0;
  for (std::size_t a = 0; a < tu.size(); ++a) {
    for (std::size_t b = 0; b < tv.size(); ++b) {
      const nurbs::SurfaceD2 d = nurbs::derivatives_d2(s, tu[a], tv[b]);
      const nurbs::SurfaceD2& g = grid[a * tv.size() + b];
      const double size = 1.0 + d.S.norm() + d.Su.norm() + d.Sv.norm() + d.Suu.norm() + d.Suv.norm() + d.Svv.norm();
      for (const auto& [x, y] : {std::pair{d.S, g.S}, {d.Su, g.Su}, {d.Sv, g.Sv}, {d.Suu, g.Suu}, {d.Suv, g.Suv}, {d.Svv, g.Svv}}) {
        worst = std::max(worst, (x - y).norm() / size);
      }
      EXPECT_EQ(first[a * tv.size() + b].Suu, Vector3::Zero());
      EXPECT_LT((first[a * tv.size() + b].Su - d.Su).norm() / size, 1e-13);
    }
  }
  EXPECT_LT(worst, 1e-13);
}

}  // namespace
