// normal_disagreement against closed forms: the angle between a fit's normal and the data's, where the fit is the
// exact surface (zero), tilted by a known angle (that angle), or where the data cannot tell (NaN).

#include "probecomp/compensation/normal_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "probecomp/nurbs/constructors.hpp"

namespace probecomp::compensation {
namespace {

// Points on an n × n grid over [0.1, 0.9]² of `s`'s parameters, with their parameters.
struct Grid {
  std::vector<Point3> points;
  std::vector<fitting::SurfaceParameter> params;
  Grid(const nurbs::Surface& s, int n) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double u = 0.1 + 0.8 * i / (n - 1), v = 0.1 + 0.8 * j / (n - 1);
        points.push_back(nurbs::evaluate(s, u, v));
        params.push_back({u, v});
      }
    }
  }
};

TEST(NormalSupport, NothingLeftOutChecksNothing) {
  const nurbs::Surface plane = nurbs::make_plane_patch({0, 0, 0}, {20, 0, 0}, {0, 20, 0});
  const Grid g(plane, 30);
  EXPECT_TRUE(normal_disagreement(plane, g.points, g.params, std::vector<double>(g.points.size(), 1.0)).angle.empty());
}

TEST(NormalSupport, OnTheExactCylinderTheNormalsAgree) {
  // Centres on a cylinder of radius 11.5 mm, 0.6 mm apart; 1 % left out and moved 0.1–5 mm off it (gross errors).
  const nurbs::Surface cylinder = nurbs::make_cylinder_section({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 11.5, 0.0, 1.5, 20.0);
  Grid g(cylinder, 40);
  std::vector<double> weights(g.points.size(), 1.0);
  int left_out = 0;
  for (std::size_t k = 37; k < g.points.size(); k += 101, ++left_out) {
    weights[k] = 0.0;
    const Point3 p = g.points[k];
    g.points[k] += (0.1 + 0.3 * left_out) * Vector3(p.x(), p.y(), 0.0).normalized();
  }
  const std::vector<double> angle = normal_disagreement(cylinder, g.points, g.params, weights).angle;
  ASSERT_EQ(angle.size(), g.points.size());
  for (std::size_t k = 0; k < angle.size(); ++k) {
    ASSERT_FALSE(std::isnan(angle[k])) << k;
    // The local quadric and cubic miss the cylinder's fourth-order terms over a neighbourhood of ±1.5 mm: a
    // thousandth of a radian makes r(1 − cos θ) half a nanometre for r = 1 mm.
    EXPECT_LT(angle[k], 1e-3) << k;
  }
}

TEST(NormalSupport, AFitTiltedByAKnownAngleDisagreesByThatAngleNearAGapAndNowhereElse) {
  // Data on the plane z = 0, 0.5 mm apart; the "fit" is that plane turned 10° about the x axis through the grid's
  // middle row (the same parameters give points on it near the data's).
  const double alpha = 10.0 * std::numbers::pi / 180.0;
  const nurbs::Surface plane = nurbs::make_plane_patch({0, 0, 0}, {25, 0, 0}, {0, 25, 0});
  const nurbs::Surface tilted =
      nurbs::make_plane_patch({0, 12.5 - 12.5 * std::cos(alpha), -12.5 * std::sin(alpha)}, {25, 0, 0},
                              {0, 25 * std::cos(alpha), 25 * std::sin(alpha)});
  const int n = 41;
  const Grid g(plane, n);
  std::vector<double> weights(g.points.size(), 1.0);
  const std::size_t gap = 5 * n + 5;  // one point left out, near a corner
  weights[gap] = 0.0;
  const double spacing = 0.8 * 25.0 / (n - 1);
  const double reach = NormalCheck{}.reach_spacings * spacing;
  const std::vector<double> angle = normal_disagreement(tilted, g.points, g.params, weights).angle;
  ASSERT_EQ(angle.size(), g.points.size());
  for (std::size_t k = 0; k < angle.size(); ++k) {
    const double d = (g.points[k] - g.points[gap]).norm();
    if (d <= reach - 0.1 * spacing) {
      EXPECT_NEAR(angle[k], alpha, 1e-9) << k;  // within reach of the gap, the gap itself included
    } else if (d >= reach + 0.1 * spacing) {
      EXPECT_EQ(angle[k], 0.0) << k;
    }
  }
}

TEST(NormalSupport, PointsAlongOneLineCannotTell) {
  // One scan line: no neighbours span a surface, whatever their number.
  const nurbs::Surface plane = nurbs::make_plane_patch({0, 0, 0}, {20, 0, 0}, {0, 20, 0});
  std::vector<Point3> points;
  std::vector<fitting::SurfaceParameter> params;
  for (int i = 0; i < 200; ++i) {
    const double u = 0.1 + 0.8 * i / 199.0;
    points.push_back(nurbs::evaluate(plane, u, 0.5));
    params.push_back({u, 0.5});
  }
  std::vector<double> weights(points.size(), 1.0);
  weights[100] = 0.0;
  const NormalDisagreement check = normal_disagreement(plane, points, params, weights);
  ASSERT_EQ(check.angle.size(), points.size());
  // Sampled along a line: every point is checked, and none can be told.
  EXPECT_TRUE(check.along_lines);
  for (const double a : check.angle) EXPECT_TRUE(std::isnan(a));
}

// Scan lines on the plane z = 0: `lines` lines `gap` mm apart along y, a point every 0.2 mm along x.
struct Lines {
  std::vector<Point3> points;
  std::vector<fitting::SurfaceParameter> params;
  Lines(const nurbs::Surface& plane, int lines, double gap) {
    for (int l = 0; l < lines; ++l) {
      for (int i = 0; i <= 100; ++i) {
        const double u = (2.0 + 0.2 * i) / 25.0, v = (2.0 + gap * l) / 25.0;
        points.push_back(nurbs::evaluate(plane, u, v));
        params.push_back({u, v});
      }
    }
  }
};

TEST(NormalSupport, AlongScanLinesEveryPointIsCheckedAgainstTheNeighbouringLines) {
  // Five lines 4 mm apart, nothing left out. The exact plane agrees with them; a plane turned 10° about x (the
  // lines' direction) disagrees by 10° at every point, though it passes through each line's middle row of points
  // as closely as the exact one passes through all: what a fit swinging between the lines looks like to them.
  const nurbs::Surface plane = nurbs::make_plane_patch({0, 0, 0}, {25, 0, 0}, {0, 25, 0});
  const Lines g(plane, 5, 4.0);
  const std::vector<double> weights(g.points.size(), 1.0);
  const NormalDisagreement exact = normal_disagreement(plane, g.points, g.params, weights);
  EXPECT_TRUE(exact.along_lines);
  ASSERT_EQ(exact.angle.size(), g.points.size());
  for (std::size_t k = 0; k < g.points.size(); ++k) EXPECT_LT(exact.angle[k], 1e-9) << k;

  const double alpha = 10.0 * std::numbers::pi / 180.0;
  const nurbs::Surface tilted =
      nurbs::make_plane_patch({0, 12.5 - 12.5 * std::cos(alpha), -12.5 * std::sin(alpha)}, {25, 0, 0},
                              {0, 25 * std::cos(alpha), 25 * std::sin(alpha)});
  const NormalDisagreement swung = normal_disagreement(tilted, g.points, g.params, weights);
  ASSERT_EQ(swung.angle.size(), g.points.size());
  for (std::size_t k = 0; k < g.points.size(); ++k) EXPECT_NEAR(swung.angle[k], alpha, 1e-9) << k;
  // Checking one point in ten (as on a million points), the others take a checked neighbour's angle.
  NormalCheck few;
  few.max_line_checks = g.points.size() / 10;
  const NormalDisagreement sampled = normal_disagreement(tilted, g.points, g.params, weights, few);
  ASSERT_EQ(sampled.angle.size(), g.points.size());
  for (std::size_t k = 0; k < g.points.size(); ++k) EXPECT_NEAR(sampled.angle[k], alpha, 1e-9) << k;
}

TEST(NormalSupport, OnThreeNoisyLinesTheCubicIsNotTakenFromTheLinesWaviness) {
  // Three lines 4 mm apart on the plane z = 0, each wavy across by 20 µm and with 5 µm of noise along z; the "fit"
  // is the exact plane. Through three lines a cubic's t³ is fixed only by their waviness (its normal equations
  // pass a pivot test at 1e-6 there), and the noise it then amplifies put its normal 10–66° off on the shape suite;
  // the quadric through them is what the data fix: σ over millimetres, hundredths of a degree.
  const nurbs::Surface plane = nurbs::make_plane_patch({0, 0, 0}, {25, 0, 0}, {0, 25, 0});
  std::vector<Point3> points;
  std::vector<fitting::SurfaceParameter> params;
  std::mt19937_64 rng(20261130);
  std::normal_distribution<double> noise(0.0, 5e-3);
  for (int l = 0; l < 3; ++l) {
    for (int i = 0; i <= 100; ++i) {
      const double x = 2.0 + 0.2 * i, y = 8.0 + 4.0 * l + 0.02 * std::sin(0.7 * x + l);
      points.emplace_back(x, y, noise(rng));
      params.push_back({x / 25.0, y / 25.0});
    }
  }
  const NormalDisagreement check = normal_disagreement(plane, points, params, std::vector<double>(points.size(), 1.0));
  EXPECT_TRUE(check.along_lines);
  ASSERT_EQ(check.angle.size(), points.size());
  for (std::size_t k = 0; k < points.size(); ++k) {
    ASSERT_FALSE(std::isnan(check.angle[k])) << k;
    EXPECT_LT(check.angle[k], 0.5 * std::numbers::pi / 180.0) << k;
  }
}

TEST(NormalSupport, AGridOrRandomPointsAreNotLines) {
  const nurbs::Surface plane = nurbs::make_plane_patch({0, 0, 0}, {20, 0, 0}, {0, 20, 0});
  const Grid g(plane, 30);
  std::vector<double> weights(g.points.size(), 1.0);
  weights[300] = 0.0;
  EXPECT_FALSE(normal_disagreement(plane, g.points, g.params, weights).along_lines);
}

}  // namespace
}  // namespace probecomp::compensation
