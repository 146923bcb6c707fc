// scan_line_doubts against closed forms: a fit bent along the lines by a known curvature (the angle its normal may
// be off across them), residuals of a known mean on one line (the bias), and the lines' spacing.

#include "compensation/scan_lines.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "probecomp/nurbs/constructors.hpp"

namespace probecomp::compensation::detail {
namespace {

constexpr double kSide = 25.0;  // mm

// `lines` lines `gap` mm apart along x on the square [0, 25]² (parameters x/25, y/25), a point every 0.2 mm (101
// a line; `along` gives each point's number on its line).
struct PlaneLines {
  std::vector<Point3> points;
  std::vector<fitting::SurfaceParameter> params;
  std::vector<int> line, along;
  PlaneLines(const nurbs::Surface& s, int lines, double gap) {
    for (int l = 0; l < lines; ++l) {
      for (int i = 0; i <= 100; ++i) {
        const double u = (2.0 + 0.2 * i) / kSide, v = (2.0 + gap * l) / kSide;
        points.push_back(nurbs::evaluate(s, u, v));
        params.push_back({u, v});
        line.push_back(l);
        along.push_back(i);
      }
    }
  }
};

// The bicubic plane z = 0 over the square, and the same net moved to z = c·x² (Bernstein coefficients of u² in
// degree 3: 0, 0, 1/3, 1) or z = c·x³ (of u³: 0, 0, 0, 1).
nurbs::Surface flat() { return nurbs::make_plane_patch({0, 0, 0}, {kSide, 0, 0}, {0, kSide, 0}, 3, 3); }
nurbs::Surface moved_by(const double (&bernstein)[4], double scale) {
  const nurbs::Surface s = flat();
  std::vector<HomogeneousPoint> Pw = s.homogeneous();
  for (int i = 0; i < s.num_u(); ++i) {
    for (int j = 0; j < s.num_v(); ++j) Pw[static_cast<std::size_t>(i * s.num_v() + j)].z() = scale * bernstein[i];
  }
  return nurbs::Surface(s.U(), s.V(), std::move(Pw));
}
nurbs::Surface bent(double c) {
  constexpr double kBernsteinOfUSquared[4] = {0.0, 0.0, 1.0 / 3.0, 1.0};
  return moved_by(kBernsteinOfUSquared, c * kSide * kSide);
}
nurbs::Surface bent_cubically(double c) {
  constexpr double kBernsteinOfUCubed[4] = {0.0, 0.0, 0.0, 1.0};
  return moved_by(kBernsteinOfUCubed, c * kSide * kSide * kSide);
}

TEST(ScanLineDoubts, TheNormalMayTurnAcrossTheLinesAsMuchAsTheDeformationTurnsAlongThemOverHalfTheirSpacing) {
  // The fit z = c·x² against the flat start: the deformation's curvature along the lines (x) is 2c, measured along
  // the fit's normal 2c·n_z; over half the 4 mm spacing its slope turns by that times 2 mm. (To first order in the
  // fit's slope, here up to 0.09: per unit of arc length rather than of x, the curvature is a per cent lower.)
  const double c = 2e-3;
  const nurbs::Surface start = flat(), fit = bent(c);
  const PlaneLines g(fit, 5, 4.0);
  const std::vector<double> residuals(g.points.size(), 0.0), weights(g.points.size(), 1.0);
  const ScanLineDoubts d = scan_line_doubts(fit, start, g.points, g.params, residuals, weights, 4.5e-3, 1e-2, false);
  EXPECT_NEAR(d.line_spacing, 4.0, 1e-6);
  ASSERT_EQ(d.normal_angle.size(), g.points.size());
  for (std::size_t k = 0; k < g.points.size(); ++k) {
    const double x = g.points[k].x(), n_z = 1.0 / std::hypot(1.0, 2.0 * c * x);
    const double expected = std::atan(2.0 * c * n_z * 2.0);
    EXPECT_NEAR(d.normal_angle[k], expected, 1e-2 * expected) << k;
    EXPECT_EQ(d.bias[k], 0.0) << k;
  }
  // The start itself: no deformation, nothing unseen.
  const ScanLineDoubts none = scan_line_doubts(start, start, g.points, g.params, residuals, weights, 4.5e-3, 1e-2, false);
  for (const double a : none.normal_angle) EXPECT_EQ(a, 0.0);
}

TEST(ScanLineDoubts, OnExactDataTheNormalMayTurnAsMuchAsTheDeformationTurnsAnywhereWithinASpacingAlongTheLine) {
  // The fit z = c·x³: its curvature along the lines, 6c·x·n_z, grows along them. On exact data each point takes the
  // largest over its line's points within one spacing (4.1 mm: the points 0.2 mm apart within it lie up to 4.0 mm
  // on, up to the line's end at x = 22); on noisy data the point's own.
  const double c = 5e-5;
  const nurbs::Surface start = flat(), fit = bent_cubically(c);
  const PlaneLines g(fit, 5, 4.1);
  const std::vector<double> residuals(g.points.size(), 0.0), weights(g.points.size(), 1.0);
  const auto turn = [&](double x) {
    const double n_z = 1.0 / std::hypot(1.0, 3.0 * c * x * x);
    return std::atan(6.0 * c * x * n_z * 4.1 / 2.0);
  };
  const ScanLineDoubts exact = scan_line_doubts(fit, start, g.points, g.params, residuals, weights, 0.0, 1e-2, true);
  const ScanLineDoubts noisy = scan_line_doubts(fit, start, g.points, g.params, residuals, weights, 4.5e-3, 1e-2, false);
  EXPECT_NEAR(exact.line_spacing, 4.1, 1e-6);
  for (std::size_t k = 0; k < g.points.size(); ++k) {
    const double x = g.points[k].x();
    EXPECT_NEAR(noisy.normal_angle[k], turn(x), 1e-2 * turn(x)) << k;
    EXPECT_NEAR(exact.normal_angle[k], turn(std::min(x + 4.0, 22.0)), 1e-2 * turn(x + 0.2)) << k;
  }
}

TEST(ScanLineDoubts, AResidualMeanAlongALineIsItsBiasLessTheMeansNoise) {
  // Three lines 8 mm apart; residuals of 6 µm on the middle one, nothing elsewhere, σ = 4.5 µm: the mean of twelve
  // residuals on that line is 6 µm, whose noise is σ²/12, and so is the level of those estimates over a point's 64
  // nearest, all on its own line (12.8 mm of it) from the 25th point of a line to the 75th.
  const nurbs::Surface s = flat();
  const PlaneLines g(s, 3, 8.0);
  const double sigma = 4.5e-3, mean = 6e-3;
  std::vector<double> residuals(g.points.size(), 0.0);
  for (std::size_t k = 0; k < g.points.size(); ++k) residuals[k] = g.line[k] == 1 ? mean : 0.0;
  std::vector<double> weights(g.points.size(), 1.0);
  weights[101 + 50] = 0.0;  // a point left out gets the bias of the in-fit points around it
  const ScanLineDoubts d = scan_line_doubts(s, s, g.points, g.params, residuals, weights, sigma, 1e-2, false);
  for (std::size_t k = 0; k < g.points.size(); ++k) {
    if (g.along[k] < 25 || g.along[k] > 75) continue;
    EXPECT_NEAR(d.bias[k], g.line[k] == 1 ? std::sqrt(mean * mean - sigma * sigma / 12.0) : 0.0, 1e-12) << k;
  }
  // A residual mean within its own noise is no bias.
  for (double& r : residuals) r = r > 0.0 ? 1e-3 : 0.0;
  for (const double b : scan_line_doubts(s, s, g.points, g.params, residuals, weights, sigma, 1e-2, false).bias) EXPECT_EQ(b, 0.0);
}

TEST(ScanLineDoubts, AGridIsNotLines) {
  const nurbs::Surface start = flat(), fit = bent(2e-3);
  std::vector<Point3> points;
  std::vector<fitting::SurfaceParameter> params;
  for (int i = 0; i <= 50; ++i) {
    for (int j = 0; j <= 50; ++j) {
      const double u = 0.1 + 0.8 * i / 50.0, v = 0.1 + 0.8 * j / 50.0;
      points.push_back(nurbs::evaluate(fit, u, v));
      params.push_back({u, v});
    }
  }
  const std::vector<double> residuals(points.size(), 5e-3), weights(points.size(), 1.0);
  const ScanLineDoubts d = scan_line_doubts(fit, start, points, params, residuals, weights, 4.5e-3, 1e-2, false);
  for (std::size_t k = 0; k < points.size(); ++k) {
    EXPECT_EQ(d.bias[k], 0.0) << k;
    EXPECT_EQ(d.normal_angle[k], 0.0) << k;
  }
}

TEST(ScanLineNumbers, EachLineInTurnIsNumbered) {
  const PlaneLines g(flat(), 9, 2.5);
  const std::vector<int> numbers = scan_line_numbers(g.points, 8);
  ASSERT_EQ(numbers.size(), g.points.size());
  for (std::size_t k = 0; k < g.points.size(); ++k) EXPECT_EQ(numbers[k], g.line[k]) << k;
  // Lines scanned back and forth: the step between them is still the jump across.
  std::vector<Point3> zigzag;
  for (int l = 0; l < 9; ++l) {
    for (int i = 0; i <= 100; ++i) zigzag.push_back(g.points[static_cast<std::size_t>(l * 101 + (l % 2 ? 100 - i : i))]);
  }
  const std::vector<int> back_and_forth = scan_line_numbers(zigzag, 8);
  ASSERT_EQ(back_and_forth.size(), zigzag.size());
  for (std::size_t k = 0; k < zigzag.size(); ++k) EXPECT_EQ(back_and_forth[k], static_cast<int>(k / 101)) << k;
}

TEST(ScanLineNumbers, PointsListedInAnotherOrderOrTooFewLinesAreNotNumbered) {
  const PlaneLines g(flat(), 9, 2.5);
  // Every 37th point in turn (37 and 909 share no factor): consecutive points lie on different lines.
  std::vector<Point3> shuffled;
  for (std::size_t k = 0; k < g.points.size(); ++k) shuffled.push_back(g.points[(37 * k) % g.points.size()]);
  EXPECT_TRUE(scan_line_numbers(shuffled, 2).empty());
  EXPECT_TRUE(scan_line_numbers(PlaneLines(flat(), 5, 4.0).points, 8).empty());
  EXPECT_EQ(scan_line_numbers(PlaneLines(flat(), 5, 4.0).points, 5).size(), 505u);
}

}  // namespace
}  // namespace probecomp::compensation::detail
