// Closest points against independent references: OpenCASCADE's GeomAPI_ProjectPointOnSurf on random rational
// surfaces, and a dense brute-force search on the two-turn spiral sheet.

#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <gtest/gtest.h>

#include <span>
#include <tbb/parallel_for.h>

#include "probecomp/fitting/offset.hpp"
#include "probecomp/nurbs/closest_point.hpp"
#include "probecomp/occt/convert.hpp"
#include "probecomp/simulation/freeform_case.hpp"
#include "support/light.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::nurbs {
namespace {

// Ours may not be farther than the reference by more than this (mm).
constexpr double kReferenceTolerance = 1e-9;

TEST(ClosestPointVsOpenCascade, NeverFartherOn10000RandomPoints) {
  const testing::RandomSurfaceSpec specs[] = {
      {.p = 3, .q = 3, .nu = 8, .nv = 7},
      {.p = 3, .q = 3, .nu = 20, .nv = 20},
      {.p = 2, .q = 3, .nu = 6, .nv = 9, .height = 30.0},
      {.p = 4, .q = 2, .nu = 9, .nv = 6, .weight_min = 0.3, .weight_max = 3.0},
  };
  int total = 0, ours_better = 0, occt_found_none = 0;
  double worst_excess = -1.0;
  std::uint64_t seed = 300;
  for (const auto& spec : test::kLight ? std::span(specs, 1) : std::span(specs)) {
    const Surface s = testing::random_rational_surface(seed++, spec);
    const ClosestPointSolver solver(s);
    const Handle(Geom_BSplineSurface) ref = occt::to_occt(s);
    const auto points = testing::random_points_near(s, 2500, 5.0, seed++);
    const auto ours = solver.closest_points(points);
    GeomAPI_ProjectPointOnSurf projector;
    projector.Init(ref, 0.0, 1.0, 0.0, 1.0);
    for (std::size_t i = 0; i < points.size(); ++i) {
      ++total;
      ASSERT_TRUE(ours[i].ok()) << to_string(ours[i].status) << " at point " << i;
      EXPECT_NEAR((evaluate(s, ours[i].u, ours[i].v) - points[i]).norm(), ours[i].distance, 1e-12);
      projector.Perform(gp_Pnt(points[i].x(), points[i].y(), points[i].z()));
      if (!projector.IsDone() || projector.NbPoints() == 0) {
        ++occt_found_none;
        continue;
      }
      const double theirs = projector.LowerDistance();
      const double excess = ours[i].distance - theirs;
      worst_excess = std::max(worst_excess, excess);
      EXPECT_LE(excess, kReferenceTolerance) << "point " << i << " ours " << ours[i].distance << " occt " << theirs;
      ours_better += excess < -1e-6;
    }
  }
  EXPECT_EQ(total, test::kLight ? 2500 : 10000);
  EXPECT_LT(occt_found_none, total / 100);
  RecordProperty("worst_excess_mm", std::to_string(worst_excess));
  std::cout << "closest point vs OpenCASCADE: " << total << " points, worst (ours - occt) = " << worst_excess
            << " mm, ours closer by > 1 um on " << ours_better << ", occt found none on " << occt_found_none << "\n";
}

// Brute force: the nearest of a dense parameter grid, refined by OpenCASCADE inside the neighbouring grid cells.
struct BruteForce {
  const Surface& s;
  Handle(Geom_BSplineSurface) ref;
  int nu, nv;
  std::vector<Point3> grid;

  BruteForce(const Surface& surface, int samples_u, int samples_v)
      : s(surface), ref(occt::to_occt(surface)), nu(samples_u), nv(samples_v), grid(std::size_t(nu) * nv) {
    for (int a = 0; a < nu; ++a)
      for (int b = 0; b < nv; ++b) grid[a * nv + b] = evaluate(s, par_u(a), par_v(b));
  }
  double par_u(int a) const { return s.domain().u0 + (s.domain().u1 - s.domain().u0) * a / (nu - 1); }
  double par_v(int b) const { return s.domain().v0 + (s.domain().v1 - s.domain().v0) * b / (nv - 1); }

  double distance(const Point3& q) const {
    std::size_t best = 0;
    double best_sq = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < grid.size(); ++k) {
      const double d = (grid[k] - q).squaredNorm();
      if (d < best_sq) best_sq = d, best = k;
    }
    const int a = static_cast<int>(best) / nv, b = static_cast<int>(best) % nv;
    GeomAPI_ProjectPointOnSurf local;
    local.Init(gp_Pnt(q.x(), q.y(), q.z()), ref, par_u(std::max(a - 1, 0)), par_u(std::min(a + 1, nu - 1)),
               par_v(std::max(b - 1, 0)), par_v(std::min(b + 1, nv - 1)));
    double d = std::sqrt(best_sq);
    if (local.IsDone() && local.NbPoints() > 0) d = std::min(d, local.LowerDistance());
    return d;
  }
};

TEST(ClosestPointVsBruteForce, SpiralSheetHasNoWrongAnswersOn10000Points) {
  const Surface s = testing::spiral_sheet();
  ASSERT_EQ(s.U().num_spans(), 64);
  const ClosestPointSolver solver(s);
  const auto points = testing::random_points_near(s, test::kLight ? 2500 : 10000, 5.0, 77);
  const auto ours = solver.closest_points(points);
  const BruteForce brute(s, 64 * 16 + 1, 31);
  std::vector<double> reference(points.size());
  tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) { reference[i] = brute.distance(points[i]); });
  int wrong = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    ASSERT_TRUE(ours[i].ok()) << to_string(ours[i].status) << " at point " << i;
    if (ours[i].distance > reference[i] + kReferenceTolerance) {
      ++wrong;
      ADD_FAILURE() << "point " << i << " (" << points[i].transpose() << "): ours " << ours[i].distance
                    << " brute force " << reference[i];
      if (wrong > 10) break;
    }
  }
  EXPECT_EQ(wrong, 0);
}

// An offset surface searched with cells sized by its nominal surface's spans (shape_spans, as the radius-offset
// model's faces are), not by the many spans its fit added: against brute force on the offset itself, on the demo's
// panel, a smooth free-form panel and random rational surfaces, offset 1 and 3 mm to both sides (those that do not
// fold), with points up to 5 mm off. No answer may be farther than the reference. (The search with 2(p+1) cells a
// span of the offset is counted beside it; on these surfaces neither misses, down to one cell a span.)
TEST(ClosestPointVsBruteForce, OffsetSurfacesSearchedByTheirNominalsSpansHaveNoWrongAnswers) {
  const std::vector<Surface> nominals = {
      simulation::paper_freeform_case().nominal.faces.at(0).surface, testing::freeform_panel(1, 8, true),
      testing::random_rational_surface(410, {.p = 3, .q = 3, .nu = 8, .nv = 7, .height = 5.0}),
      testing::random_rational_surface(411, {.p = 3, .q = 3, .nu = 7, .nv = 7, .height = 8.0})};
  int exercised = 0, queries = 0, wrong = 0, wrong_dense = 0;
  double cell_share = 0.0;
  std::uint64_t seed = 500;
  for (const Surface& s : nominals) {
    for (const double d : test::cases({1.0, -1.0, 3.0, -3.0})) {
      const fitting::OffsetResult offset = fitting::offset_surface(s, d);
      if (!offset.ok()) continue;
      const Surface& o = offset.surface;
      ASSERT_TRUE(o.U().num_spans() > s.U().num_spans() || o.V().num_spans() > s.V().num_spans());
      ++exercised;
      const ClosestPointSolver solver(o, {.shape_spans_u = s.U().num_spans(), .shape_spans_v = s.V().num_spans()});
      const ClosestPointSolver dense(o);
      cell_share += static_cast<double>(solver.seed_count()) / static_cast<double>(dense.seed_count());
      const auto points = testing::random_points_near(o, 300, 5.0, seed++);
      const auto ours = solver.closest_points(points);
      const auto theirs = dense.closest_points(points);
      const BruteForce brute(o, 6 * o.U().num_spans() + 1, 6 * o.V().num_spans() + 1);
      std::vector<double> reference(points.size());
      tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) { reference[i] = brute.distance(points[i]); });
      for (std::size_t i = 0; i < points.size(); ++i) {
        ++queries;
        ASSERT_TRUE(ours[i].ok()) << to_string(ours[i].status) << " at point " << i;
        wrong_dense += theirs[i].ok() && theirs[i].distance > reference[i] + kReferenceTolerance;
        if (ours[i].distance > reference[i] + kReferenceTolerance) {
          ++wrong;
          ADD_FAILURE() << "offset " << d << " of surface " << &s - nominals.data() << ", point " << i << ": ours "
                        << ours[i].distance << " brute force " << reference[i] << " (2(p+1) cells a span: "
                        << theirs[i].distance << ")";
        }
      }
    }
  }
  EXPECT_GE(exercised, test::kLight ? 3 : 12);
  EXPECT_EQ(wrong, 0);
  std::cout << "offset surfaces searched by their nominals' spans: " << exercised << " offsets, " << queries
            << " points, " << wrong << " farther than brute force (" << wrong_dense << " with 2(p+1) cells a span of "
            << "the offset); " << cell_share / std::max(exercised, 1) << " of those cells on average\n";
}

// A hard case: a tall rational surface (one knot span covering 70 % of v) with points up to 10 mm off, where many
// queries lie near a centre of curvature and the distance has several minima close together. Against brute force
// (a dense grid refined by OpenCASCADE): no result reported ok is farther by more than 0.1 µm, and results flagged
// not-converged are rare. (Without the second search near centres of curvature, two answers here are 0.35 and
// 1.04 µm off, reported converged.)
TEST(ClosestPointVsBruteForce, NearCentresOfCurvatureNoTrustedAnswerIsWrong) {
  const Surface s = testing::random_rational_surface(2000, {.p = 2, .q = 3, .nu = 7, .nv = 9, .height = 40.0});
  const ClosestPointSolver solver(s);
  const auto points = testing::random_points_near(s, test::kLight ? 2500 : 10000, 10.0, 60);
  const auto ours = solver.closest_points(points);
  const BruteForce brute(s, 201, 201);
  std::vector<double> reference(points.size());
  tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) { reference[i] = brute.distance(points[i]); });
  int wrong = 0, flagged = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!ours[i].ok()) {
      ++flagged;
      continue;
    }
    if (ours[i].distance > reference[i] + 1e-4) {
      ++wrong;
      ADD_FAILURE() << "point " << i << ": ours " << ours[i].distance << " (" << to_string(ours[i].status)
                    << ") brute force " << reference[i];
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_LE(flagged, 5);
  std::cout << "near centres of curvature: " << points.size() << " points, trusted but wrong by > 0.1 um: " << wrong
            << ", flagged: " << flagged << "\n";
}

}  // namespace
}  // namespace probecomp::nurbs
