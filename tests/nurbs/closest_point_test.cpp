// Closest points with exact answers: planes, cylinders, edges and corners, degenerate queries, determinism.

#include "probecomp/nurbs/closest_point.hpp"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <numbers>
#include <random>

#include "probecomp/nurbs/constructors.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::nurbs {
namespace {

TEST(ClosestPoint, PlaneInteriorIsTheOrthogonalProjection) {
  const Point3 o(1, 2, 3);
  const Vector3 a(50, 0, 0), b(0, 30, 0);
  const ClosestPointSolver solver(make_plane_patch(o, a, b, 3, 3, 4, 4));
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> t(0.0, 1.0), h(-5.0, 5.0);
  for (int k = 0; k < 2000; ++k) {
    const double u = t(rng), v = t(rng), z = h(rng);
    const Point3 q = o + u * a + v * b + Vector3(0, 0, z);
    const ClosestPointResult r = solver.closest_point(q);
    ASSERT_TRUE(r.ok());
    EXPECT_NEAR(r.distance, std::abs(z), 1e-10);
    EXPECT_NEAR(r.u, u, 1e-10);
    EXPECT_NEAR(r.v, v, 1e-10);
    EXPECT_LT((r.point - (o + u * a + v * b)).norm(), 1e-10);
  }
}

TEST(ClosestPoint, PlaneOutsideIsTheClampedProjectionOnAnEdgeOrCorner) {
  const Point3 o(0, 0, 0);
  const Vector3 a(20, 0, 0), b(0, 10, 0);
  const ClosestPointSolver solver(make_plane_patch(o, a, b, 2, 3, 3, 2));
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> x(-10.0, 30.0), y(-10.0, 20.0), z(-3.0, 3.0);
  int on_edges = 0;
  for (int k = 0; k < 2000; ++k) {
    const double qz = z(rng), qy = y(rng), qx = x(rng);  // as gcc drew them as the constructor's arguments
    const Point3 q(qx, qy, qz);
    const Point3 expected(std::clamp(q.x(), 0.0, 20.0), std::clamp(q.y(), 0.0, 10.0), 0.0);
    const ClosestPointResult r = solver.closest_point(q);
    const bool outside = q.x() < 0 || q.x() > 20 || q.y() < 0 || q.y() > 10;
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.status, outside ? ClosestPointStatus::OnBoundary : ClosestPointStatus::Converged) << q.transpose();
    EXPECT_LT((r.point - expected).norm(), 1e-10) << q.transpose();
    EXPECT_NEAR(r.distance, (q - expected).norm(), 1e-10);
    on_edges += outside;
  }
  EXPECT_GT(on_edges, 1000);  // the sample really exercised edges and corners
}

TEST(ClosestPoint, CylinderInsideAndOutsideIsTheRadialProjection) {
  const Point3 c(0, 0, 0);
  const double R = 10.0;
  const ClosestPointSolver solver(make_cylinder_section(c, {1, 0, 0}, {0, 1, 0}, R, 0.0, 2.5, 20.0));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ang(0.01, 2.49), rho(5.5, 14.0), z(0.0, 20.0);
  for (int k = 0; k < 2000; ++k) {
    const double th = ang(rng), rr = rho(rng), zz = z(rng);
    const Point3 q(rr * std::cos(th), rr * std::sin(th), zz);
    const ClosestPointResult r = solver.closest_point(q);
    ASSERT_EQ(r.status, ClosestPointStatus::Converged);
    EXPECT_NEAR(r.distance, std::abs(rr - R), 1e-10);
    EXPECT_LT((r.point - Point3(R * std::cos(th), R * std::sin(th), zz)).norm(), 1e-10);
  }
}

TEST(ClosestPoint, PointOnTheSurfaceHasZeroDistance) {
  const Surface s = testing::random_rational_surface(5);
  const ClosestPointSolver solver(s);
  for (double u : {0.0, 0.13, 0.5, 0.91, 1.0}) {
    for (double v : {0.0, 0.27, 0.66, 1.0}) {
      const ClosestPointResult r = solver.closest_point(evaluate(s, u, v));
      ASSERT_TRUE(r.ok());
      EXPECT_LT(r.distance, 1e-10);
    }
  }
}

TEST(ClosestPoint, NonFiniteQueryIsANumericalErrorNotAnAnswer) {
  const ClosestPointSolver solver(testing::random_rational_surface(5));
  const ClosestPointResult r = solver.closest_point(Point3(std::nan(""), 0, 0));
  EXPECT_EQ(r.status, ClosestPointStatus::NumericalError);
  EXPECT_FALSE(r.ok());
  EXPECT_STREQ(to_string(r.status), "numerical-error");
}

TEST(ClosestPoint, RefineFindsTheLocalFootFromAnyStart) {
  const Surface s = make_cylinder_section({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 10.0, 0.0, 1.0, 5.0);
  const Point3 q(12 * std::cos(0.5), 12 * std::sin(0.5), 2.5);
  const ClosestPointResult r = refine_closest_point(s, q, 0.0, 0.0);
  ASSERT_EQ(r.status, ClosestPointStatus::Converged);
  EXPECT_NEAR(r.distance, 2.0, 1e-12);
  EXPECT_GT(r.iterations, 0);
}

// At an interior foot point S − P is normal to the surface: its components along S_u and S_v (the foot's
// tangential error, mm) must be at rounding level, whatever shortcut the iteration takes to finish.
TEST(ClosestPoint, InteriorFootIsOrthogonalToTheTangentsToRounding) {
  const Surface surfaces[] = {
      testing::freeform_panel(2024, 20),
      testing::random_rational_surface(1000, {.nu = 10, .nv = 9, .height = 30.0, .weight_min = 0.3, .weight_max = 3.0})};
  for (const Surface& s : surfaces) {
    const ClosestPointSolver solver(s);
    const auto points = testing::random_points_near(s, 5000, 5.0, 5);
    const auto results = solver.closest_points(points);
    int interior = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (results[i].status != ClosestPointStatus::Converged) continue;
      ++interior;
      const SurfaceD1 d = derivatives_d1(s, results[i].u, results[i].v);
      const Vector3 e = points[i] - d.S;
      EXPECT_LT(std::abs(e.dot(d.Su)) / d.Su.norm(), 1e-9) << i;
      EXPECT_LT(std::abs(e.dot(d.Sv)) / d.Sv.norm(), 1e-9) << i;
    }
    EXPECT_GT(interior, 4500);
  }
}

TEST(ClosestPoint, BatchIsIdenticalWhateverTheThreadCount) {
  const Surface s = testing::random_rational_surface(9, {.nu = 20, .nv = 20});
  const ClosestPointSolver solver(s);
  const auto points = testing::random_points_near(s, 20000, 2.0, 4);
  std::vector<ClosestPointResult> one, two;
  tbb::task_arena(1).execute([&] { one = solver.closest_points(points); });
  tbb::task_arena(2).execute([&] { two = solver.closest_points(points); });
  ASSERT_EQ(one.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ(one[i].u, two[i].u) << i;  // bit for bit
    ASSERT_EQ(one[i].v, two[i].v) << i;
    ASSERT_EQ(one[i].distance, two[i].distance) << i;
    ASSERT_EQ(one[i].status, two[i].status) << i;
    ASSERT_EQ(one[i].distance, solver.closest_point(points[i]).distance);
  }
}

// The search keeps its cells' boxes in floats, whose spacing 2 m from the origin is 1.2e-4 mm: rounded inwards they
// would hide a foot nearer than that from its own cell. Points 1e-6 mm off a part far from the origin, and a bound
// (a known point) 3e-6 mm away: every search must find the point's own foot, never return the bound. The plane lies
// at a height no float holds (800.00003 mm, between floats 6.1e-5 apart), so that its boxes, one float thick, are
// rounded at both sides.
TEST(ClosestPoint, CellBoundsInFloatsHideNoFootOfAPartFarFromTheOrigin) {
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translate(Vector3(2000.0, -1500.0, 800.0));
  const Surface parts[] = {make_plane_patch({2000.0, -1500.0, 800.00003}, {100, 0, 0}, {0, 80, 0}, 3, 3, 6, 5),
                           transformed(testing::freeform_panel(7, 12), far)};
  for (const Surface& s : parts) {
    const ClosestPointSolver solver(s);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> t(0.02, 0.98);
    int hidden = 0;
    for (int k = 0; k < 2000; ++k) {
      const double u = t(rng), v = t(rng);
      const UnitNormal n = unit_normal(s, u, v);
      ASSERT_EQ(n.status, UnitNormal::Status::OK);
      const Point3 on = evaluate(s, u, v);
      const Point3 query = on + 1e-6 * n.n;
      ClosestPointResult bound;
      bound.status = ClosestPointStatus::Converged;
      bound.distance = 3e-6;
      const ClosestPointResult r = solver.closest_point(query, bound);
      hidden += r.distance >= 3e-6;
      EXPECT_LT((r.point - on).norm(), 1e-6) << "point " << k;
    }
    EXPECT_EQ(hidden, 0);
  }
}

}  // namespace
}  // namespace probecomp::nurbs
