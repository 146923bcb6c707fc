// offset_surface against exact offsets (plane, cylinder: closed form) and against OpenCASCADE's
// Geom_OffsetSurface (free form), at random parameters that are neither the fit's samples nor its check grid.

#include "probecomp/fitting/offset.hpp"

#include <Geom_OffsetSurface.hxx>
#include <GeomLProp_SLProps.hxx>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "probecomp/nurbs/closest_point.hpp"
#include "probecomp/nurbs/constructors.hpp"
#include "probecomp/nurbs/degree_elevation.hpp"
#include "probecomp/occt/convert.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::fitting {
namespace {

using nurbs::Surface;

std::vector<std::pair<double, double>> random_parameters(const Surface& s, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const nurbs::Domain d = s.domain();
  std::uniform_real_distribution<double> u(d.u0, d.u1), v(d.v0, d.v1);
  std::vector<std::pair<double, double>> out;
  for (int k = 0; k < n; ++k) {
    const double b = v(rng), a = u(rng);  // as gcc drew them as the call's arguments
    out.emplace_back(a, b);
  }
  return out;
}

TEST(OffsetSurface, PlaneOffsetIsExact) {
  const Surface plane = nurbs::make_plane_patch({1, 2, 3}, {40, 5, 0}, {-3, 30, 2}, 3, 3, 4, 3);
  const Vector3 n = Vector3(40, 5, 0).cross(Vector3(-3, 30, 2)).normalized();
  const OffsetResult r = offset_surface(plane, 1.5);
  ASSERT_EQ(r.status, OffsetResult::Status::OK);
  EXPECT_EQ(r.rounds, 1);
  EXPECT_EQ(r.knots_inserted, 0);
  EXPECT_LE(r.deviation, 1e-12);
  EXPECT_GT(r.min_radius_towards_offset, 1e9);  // flat, to rounding
  for (const auto& [u, v] : random_parameters(plane, 1000, 1)) {
    EXPECT_LE((nurbs::evaluate(r.surface, u, v) - (nurbs::evaluate(plane, u, v) + 1.5 * n)).norm(), 1e-12);
  }
}

TEST(OffsetSurface, CylinderSectionOffsetIsACylinderOfRadiusRPlusD) {
  // 150° of a cylinder of radius 20 mm, 30 mm long, about an oblique axis; rational quadratic in u.
  const Point3 c(5, -3, 2);
  const Vector3 x = Vector3(1, 1, 0).normalized();
  const Vector3 y = Vector3(-1, 1, 1).normalized();
  const Vector3 axis = x.cross(y);
  const Surface cyl = nurbs::make_cylinder_section(c, x, y, 20.0, 0.2, 0.2 + 150.0 * std::numbers::pi / 180.0, 30.0);
  for (const double d : {1.0, -3.0}) {
    const OffsetResult r = offset_surface(cyl, d);
    ASSERT_EQ(r.status, OffsetResult::Status::OK) << d;
    EXPECT_LE(r.deviation, 1e-4);
    if (d > 0) {
      EXPECT_GT(r.min_radius_towards_offset, 1e9);  // the cylinder bends away from its outside
    } else {
      EXPECT_NEAR(r.min_radius_towards_offset, 20.0, 1e-9);
    }
    double worst = 0.0;
    for (const auto& [u, v] : random_parameters(cyl, 2000, 2)) {
      const Point3 o = nurbs::evaluate(r.surface, u, v);
      const Vector3 e = o - c;
      const double radius = (e - e.dot(axis) * axis).norm();
      worst = std::max(worst, std::abs(radius - (20.0 + d)));
      // The same parameter as on the cylinder: S + d·n, n radial.
      const Point3 s = nurbs::evaluate(cyl, u, v);
      const Vector3 radial = ((s - c) - (s - c).dot(axis) * axis).normalized();
      EXPECT_LE((o - (s + d * radial)).norm(), 1e-4);
    }
    EXPECT_LE(worst, 1e-4) << d;
  }
}

TEST(OffsetSurface, InwardOffsetBeyondTheCylinderRadiusFolds) {
  const Surface cyl = nurbs::make_cylinder_section({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 5.0, 0.0, 2.0, 10.0);
  const OffsetResult r = offset_surface(cyl, -6.0);
  EXPECT_EQ(r.status, OffsetResult::Status::FoldsOver);
  EXPECT_NEAR(r.min_radius_towards_offset, 5.0, 1e-9);
  EXPECT_EQ(offset_surface(cyl, -4.0).status, OffsetResult::Status::OK);
}

// The largest distance from OpenCASCADE's exact offset of `s` by d (Geom_OffsetSurface) at n random parameters to
// `fit`. The tolerance is on the shape: each true offset point's foot on the fit is found by Newton from the same
// parameters, which lie within micrometres of it. Infinite where Newton fails.
double worst_gap_to_exact_offset(const Surface& s, double d, const Surface& fit, int n, std::uint64_t seed) {
  const Handle(Geom_OffsetSurface) reference = new Geom_OffsetSurface(occt::to_occt(s), d);
  double worst = 0.0;
  for (const auto& [u, v] : random_parameters(s, n, seed)) {
    const gp_Pnt o = reference->Value(u, v);
    const nurbs::ClosestPointResult foot = nurbs::refine_closest_point(fit, Point3(o.X(), o.Y(), o.Z()), u, v);
    worst = std::max(worst, foot.ok() ? foot.distance : std::numeric_limits<double>::infinity());
  }
  return worst;
}

// The free-form surface of the other tests, and OpenCASCADE's exact offset of it.
class FreeFormOffset : public ::testing::TestWithParam<double> {};

TEST_P(FreeFormOffset, WithinTheToleranceOfOpenCascadesOffsetSurface) {
  const double d = GetParam();
  const Surface s = testing::random_rational_surface(21, {.nu = 9, .nv = 8, .height = 6.0});
  const OffsetResult r = offset_surface(s, d);
  ASSERT_EQ(r.status, OffsetResult::Status::OK) << to_string(r.status) << " deviation " << r.deviation
                                                << " radius " << r.min_radius_towards_offset;
  EXPECT_LE(r.deviation, 1e-4);
  const double worst = worst_gap_to_exact_offset(s, d, r.surface, 5000, 3);
  EXPECT_LE(worst, 1e-4);
  RecordProperty("worst_deviation_mm", std::to_string(worst));
}

// The surface's tightest curvature radius is 1.3 mm on the + side: 1 mm offsets need several refinements.
INSTANTIATE_TEST_SUITE_P(Distances, FreeFormOffset, ::testing::Values(1.0, -1.0, 0.5));

// Degree 5 with knots of multiplicity 3 and 4 before long spans (as on the impeller's blades): more basis functions
// live on the last span than a few samples per span determine. Against OpenCASCADE's exact offset.
TEST(OffsetSurface, HighDegreeWithMultipleKnotsBeforeALongSpan) {
  const Surface cubic = testing::random_rational_surface(23, {.nu = 4, .nv = 4, .height = 4.0});  // one span
  const nurbs::Domain d = cubic.domain();
  auto at = [&](double f) { return d.u0 + f * (d.u1 - d.u0); };
  // Short spans first (as a deformation's refinement makes them), then 0.25 three times and 0.5 four times: the
  // last span carries four basis functions of its own.
  const Surface s = nurbs::refine_knots_u(nurbs::elevate_degree_v(nurbs::elevate_degree_u(cubic, 2), 2),
                                          {at(0.05), at(0.1), at(0.15), at(0.2), at(0.25), at(0.25), at(0.25),
                                           at(0.5), at(0.5), at(0.5), at(0.5)});
  ASSERT_EQ(s.p(), 5);
  const OffsetResult r = offset_surface(s, 0.5);
  ASSERT_EQ(r.status, OffsetResult::Status::OK) << to_string(r.status) << " deviation " << r.deviation;
  EXPECT_LE(worst_gap_to_exact_offset(s, 0.5, r.surface, 2000, 4), 1e-4);
}

TEST(OffsetSurface, FreeFormFoldsExactlyWhenTheOffsetExceedsTheCurvatureRadiusOnItsSide) {
  const Surface s = testing::random_rational_surface(22, {.nu = 9, .nv = 8, .height = 15.0});
  // The smallest radius of curvature on the side of +n, by OpenCASCADE on a dense grid.
  const Handle(Geom_BSplineSurface) ref = occt::to_occt(s);
  GeomLProp_SLProps props(ref, 2, 1e-12);
  double max_k = 0.0;
  for (int a = 0; a <= 200; ++a) {
    for (int b = 0; b <= 200; ++b) {
      props.SetParameters(a / 200.0, b / 200.0);
      if (!props.IsCurvatureDefined()) continue;
      // OpenCASCADE's curvature is positive where the surface bends towards its normal, as ours.
      max_k = std::max({max_k, props.MaxCurvature(), props.MinCurvature()});
    }
  }
  ASSERT_GT(max_k, 0.0);
  const double radius = 1.0 / max_k;
  EXPECT_EQ(offset_surface(s, 2.0 * radius).status, OffsetResult::Status::FoldsOver);
  const OffsetResult safe = offset_surface(s, 0.5 * radius);
  EXPECT_NE(safe.status, OffsetResult::Status::FoldsOver);
  EXPECT_GE(safe.min_radius_towards_offset, 0.9 * radius);
}

}  // namespace
}  // namespace probecomp::fitting
