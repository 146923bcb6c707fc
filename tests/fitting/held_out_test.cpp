// held_out_errors against closed forms: a plane the penalty does not resist is refitted exactly without any group,
// so a line moved off it by d is predicted d away from where it was measured.

#include "probecomp/fitting/held_out.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "probecomp/nurbs/constructors.hpp"

namespace probecomp::fitting {
namespace {

// Lines along x, 4 mm apart, a point every 0.25 mm, on the bicubic plane z = 0 over [0, 40]², its net 8 × 8; the
// points on the plane z = 0.01·x + 0.02·y (a displacement the thin-plate energy does not penalise), except line
// `moved`, lifted by d more.
struct TiltedLines {
  nurbs::Surface start = nurbs::make_plane_patch({0, 0, 0}, {40, 0, 0}, {0, 40, 0}, 3, 3);
  std::vector<Point3> points;
  std::vector<SurfaceParameter> params;
  std::vector<int> line;
  TiltedLines(int moved, double d) {
    start = nurbs::refine_knots_u(start, {0.2, 0.4, 0.6, 0.8});
    start = nurbs::refine_knots_v(start, {0.2, 0.4, 0.6, 0.8});
    for (int l = 0; l < 9; ++l) {
      for (int i = 0; i <= 144; ++i) {
        const double x = 2.0 + 0.25 * i, y = 4.0 + 4.0 * l;
        points.emplace_back(x, y, 0.01 * x + 0.02 * y + (l == moved ? d : 0.0));
        params.push_back({x / 40.0, y / 40.0});
        line.push_back(l);
      }
    }
  }
};

TEST(HeldOutErrors, ALineMovedOffAPlaneIsPredictedByTheRestAsThePlane) {
  constexpr double d = 0.01;  // mm
  // The refit is the plane but for the ridge that keeps its normal equations regular, which pulls it towards the
  // start by a few nanometres here (PenalizedFitOptions::ridge).
  constexpr double kRidge = 1e-5;  // mm
  const TiltedLines g(4, d);
  AdaptiveFitOptions options;
  options.fit.cross_validation = CrossValidation::LeaveSpanOut;
  const AdaptiveFitResult fit = fit_surface(g.start, g.points, g.params, {}, options);
  ASSERT_TRUE(fit.fitted());
  ASSERT_FALSE(fit.span_weight.empty());
  // The moved line alone left out, every other line in every refit: the refit is the plane.
  std::vector<int> groups(g.points.size());
  for (std::size_t k = 0; k < groups.size(); ++k) groups[k] = g.line[k] == 4 ? 0 : -1;
  const std::vector<double> alone = held_out_errors(fit, g.start, g.points, {}, groups, 1, options.fit);
  ASSERT_EQ(alone.size(), g.points.size());
  for (std::size_t k = 0; k < alone.size(); ++k) {
    if (g.line[k] == 4) {
      EXPECT_NEAR(std::sqrt(alone[k]), d, kRidge) << k;
    } else {
      EXPECT_TRUE(std::isnan(alone[k])) << k;
    }
  }
  // Every third line in turn: left out with lines 1 and 7 (group 1), the moved line no longer bends the refit, which
  // is the plane again; the other lines are predicted by refits bent towards it.
  for (std::size_t k = 0; k < groups.size(); ++k) groups[k] = g.line[k] % 3;
  std::vector<double> w(g.points.size(), 1.0);
  w[5] = 0.0;  // on line 0: left out of every fit, scored in none
  const std::vector<double> turns = held_out_errors(fit, g.start, g.points, w, groups, 3, options.fit);
  ASSERT_EQ(turns.size(), g.points.size());
  double bent = 0.0;
  for (std::size_t k = 0; k < turns.size(); ++k) {
    if (k == 5) {
      EXPECT_TRUE(std::isnan(turns[k]));
    } else if (g.line[k] == 4) {
      EXPECT_NEAR(std::sqrt(turns[k]), d, kRidge) << k;
    } else if (g.line[k] % 3 == 1) {
      EXPECT_NEAR(std::sqrt(turns[k]), 0.0, kRidge) << k;
    } else {
      bent = std::max(bent, turns[k]);
    }
  }
  EXPECT_GT(bent, 1e-4 * d * d);
}

TEST(HeldOutErrors, NoneWithoutAFitOrWithGroupsOfAnotherSize) {
  const TiltedLines g(-1, 0.0);
  const AdaptiveFitResult none{.status = AdaptiveFitResult::Status::NotDone, .surface = g.start};
  const std::vector<int> groups(g.points.size(), 0);
  EXPECT_TRUE(held_out_errors(none, g.start, g.points, {}, groups, 1, {}).empty());
  AdaptiveFitOptions options;
  options.fit.cross_validation = CrossValidation::LeaveSpanOut;
  const AdaptiveFitResult fit = fit_surface(g.start, g.points, g.params, {}, options);
  ASSERT_TRUE(fit.fitted());
  std::vector<int> thirds(g.points.size());
  for (std::size_t k = 0; k < thirds.size(); ++k) thirds[k] = g.line[k] % 3;
  EXPECT_EQ(held_out_errors(fit, g.start, g.points, {}, thirds, 3, options.fit).size(), g.points.size());
  EXPECT_TRUE(held_out_errors(fit, g.start, g.points, {}, std::vector<int>(3, 0), 1, options.fit).empty());
}

}  // namespace
}  // namespace probecomp::fitting
