// The two cross-validations of fit_penalized against exact answers: leaving out a span that holds one point is
// leaving out that point (the block deletion identity reduces to h_k's), and on a scanning probe's lines the fit
// chosen by leaving spans out keeps its normals between the lines near the truth's.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "probecomp/fitting/adaptive.hpp"
#include "probecomp/fitting/offset.hpp"
#include "probecomp/fitting/penalized.hpp"
#include "probecomp/nurbs/closest_point.hpp"
#include "probecomp/nurbs/knot_insertion.hpp"
#include "probecomp/simulation/random.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::fitting {
namespace {

using nurbs::Surface;

TEST(CrossValidation, LeavingOutASpanOfOnePointIsLeavingOutThePoint) {
  // 12 × 10 spans, one noisy point at the middle of each: the two scores are the same number.
  Surface s = testing::random_rational_surface(4, {.nu = 6, .nv = 6, .repeated_knots = false});
  std::vector<double> xu, xv;
  for (int k = 1; k < 12; ++k) xu.push_back(k / 12.0);
  for (int k = 1; k < 10; ++k) xv.push_back(k / 10.0);
  s = nurbs::refine_knots_v(nurbs::refine_knots_u(s, xu), xv);
  const std::vector<double> bu = s.U().breakpoints(), bv = s.V().breakpoints();
  std::vector<Point3> points;
  std::vector<SurfaceParameter> params;
  for (std::size_t a = 0; a + 1 < bu.size(); ++a) {
    for (std::size_t b = 0; b + 1 < bv.size(); ++b) {
      const double u = 0.5 * (bu[a] + bu[a + 1]), v = 0.5 * (bv[b] + bv[b + 1]);
      const double wobble = 0.01 * std::sin(37.0 * u + 11.0 * v);
      points.push_back(nurbs::evaluate(s, u, v) + Vector3(wobble, -wobble, 2.0 * wobble));
      params.push_back({u, v});
    }
  }
  PenalizedFitOptions o;
  o.log10_smoothing = -2.0;
  const PenalizedFitResult one = fit_penalized(s, points, params, {}, o);
  o.cross_validation = CrossValidation::LeaveSpanOut;
  const PenalizedFitResult span = fit_penalized(s, points, params, {}, o);
  ASSERT_TRUE(one.ok() && span.ok());
  EXPECT_GT(one.cv_score, 0.0);
  EXPECT_NEAR(span.cv_score, one.cv_score, 1e-9 * one.cv_score);
}

// A smooth panel displaced along its normal by a dent 0.3 mm deep (σ 6 mm) and a crossing wave of 40 µm: the
// truth (displaced_surface to 1e-6 mm). Scan lines of it, each point given its foot on the undisplaced panel (as
// registration gives the pipeline's points theirs).
TEST(CrossValidation, OnScanLinesLeavingSpansOutKeepsTheNormalsBetweenTheLines) {
  const Surface start = testing::freeform_panel(3, 10, true);
  auto d = [](const Point3& x) {
    return -0.3 * std::exp(-((x.x() - 20.0) * (x.x() - 20.0) + (x.y() - 10.0) * (x.y() - 10.0)) / (2.0 * 36.0)) +
           0.04 * std::sin(2.0 * std::numbers::pi * (x.x() + 0.5 * x.y()) / 40.0);
  };
  const OffsetResult truth = displaced_surface(start, d, {.tolerance = 1e-6});
  ASSERT_EQ(truth.status, OffsetResult::Status::OK);
  std::vector<Point3> points;
  std::vector<SurfaceParameter> params;
  const nurbs::ClosestPointSolver on_start(start), on_truth(truth.surface);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.003);
  for (int l = 0; l < 21; ++l) {  // 21 lines 4.5 mm apart over 90 mm of the 200 mm panel, a point every 0.4 mm
    for (int k = 0; k < 225; ++k) {
      const double u = 0.35 + 0.45 * k / 224.0, v = 0.35 + 0.45 * l / 20.0;
      const Point3 x = nurbs::evaluate(truth.surface, u, v) + simulation::draw_vector(noise, rng);
      const nurbs::ClosestPointResult foot = on_start.closest_point(x);
      points.push_back(x);
      params.push_back({foot.u, foot.v});
    }
  }
  auto worst_normal_degrees = [&](CrossValidation cv) {
    AdaptiveFitOptions o;
    o.parameter_corrections = 0;
    o.fit.cross_validation = cv;
    const AdaptiveFitResult fit = fit_surface(start, points, params, {}, o);
    EXPECT_TRUE(fit.fitted());
    double worst = 0.0;
    for (std::size_t k = 0; k < points.size(); ++k) {
      const nurbs::ClosestPointResult t = on_truth.closest_point(points[k]);
      const Vector3 a = nurbs::unit_normal(fit.surface, fit.params[k].u, fit.params[k].v).n;
      const Vector3 b = nurbs::unit_normal(truth.surface, t.u, t.v).n;
      worst = std::max(worst, std::acos(std::min(1.0, std::abs(a.dot(b)))) * 180.0 / std::numbers::pi);
    }
    return worst;
  };
  const double by_spans = worst_normal_degrees(CrossValidation::LeaveSpanOut);
  const double by_points = worst_normal_degrees(CrossValidation::LeaveOneOut);
  std::printf("scan lines 4.5 mm apart, sigma 3 um: worst normal error %.3f deg leaving spans out, %.3f deg leaving "
              "points out\n", by_spans, by_points);
  // The dent's flanks slope up to 0.3/6·e^(−1/2) = 1.7°: the fit follows them between the lines to a small part of
  // that (measured 0.18°, and 0.45° leaving points out; on the shape suite's lines leaving points out swings far
  // more: ShapeSuite.ScanLinesAtThreeMicrometresAreFollowed). 0.5° makes r(1 − cos θ) 38 nm for r = 1 mm.
  EXPECT_LT(by_spans, 0.5);
}

}  // namespace
}  // namespace probecomp::fitting
