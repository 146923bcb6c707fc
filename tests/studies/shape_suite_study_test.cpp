// Cases of the shape suite (issue 48) end to end, against the simulator's truth: what a user must be able to rely
// on whatever the fit's accuracy on them.

#include "probecomp/studies/shape_suite_study.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace probecomp::studies {
namespace {

simulation::ShapeCase suite_case(const std::string& name) {
  for (const simulation::ShapeCase& c : simulation::shape_suite()) {
    if (c.name.rfind(name, 0) == 0) return c;
  }
  ADD_FAILURE() << name << " is not in the suite";
  return {};
}

// Scan lines 4 mm apart without noise, a dent and a windowed wave between them (S13): across the lines only the
// smoothing holds the fit, which swung there (contacts up to 0.56 mm off, u 0.1 µm). Whatever the fit does
// there, never silently: every row's error within 3 u, and a warning that says why.
TEST(ShapeSuite, ScanLinesWithoutNoiseStateTheirErrorInU) {
  simulation::ShapeCase c = suite_case("S13");
  c.points = 3000;
  const ShapeCaseResult r = run_shape_case(c);
  double worst = 0.0;
  int rows = 0;
  for (std::size_t k = 0; k < r.cad.points.size(); ++k) {
    if (r.cad.points[k].status != compensation::PointStatus::Ok || !std::isfinite(r.cad_error[k])) continue;
    ++rows;
    worst = std::max(worst, std::abs(r.cad_error[k]) / r.cad.points[k].uncertainty);
  }
  std::printf("S13 at 3 000 points: std %.2f um, largest %.1f um, worst error %.2f u, coverage %.1f %% (worst region "
              "%.1f %%)\n", r.cad_summary.std * 1e3, r.cad_summary.max_abs() * 1e3, worst, 100.0 * r.coverage_2u,
              100.0 * r.worst_region_coverage_2u);
  EXPECT_GT(rows, 2900);
  EXPECT_LE(worst, 3.0);
  EXPECT_TRUE(std::any_of(r.cad.warnings.begin(), r.cad.warnings.end(),
                          [](const std::string& w) { return w.find("lie along lines") != std::string::npos; }));
}

// Scan lines 4 mm apart at σ = 3 µm across a diagonal crease, a ripple and a saddle (S06). The smoothing chosen by
// leaving one point out followed each line and swung between them: std 18 µm, contacts up to 0.29 mm off. Chosen
// by leaving a span's points out (measured at 2 500 points: std 1.62 µm, largest 10.1 µm; 0.86 and 4.9 µm at the
// suite's 7 000) it is in the range of a grid's.
TEST(ShapeSuite, ScanLinesAtThreeMicrometresAreFollowed) {
  simulation::ShapeCase c = suite_case("S06");
  c.points = 2500;
  const ShapeCaseResult r = run_shape_case(c);
  std::printf("S06 at 2 500 points: std %.2f um, mean %.2f um, largest %.1f um, coverage %.1f %% (worst region %.1f %%)\n",
              r.cad_summary.std * 1e3, r.cad_summary.mean * 1e3, r.cad_summary.max_abs() * 1e3, 100.0 * r.coverage_2u,
              100.0 * r.worst_region_coverage_2u);
  EXPECT_LT(r.cad_summary.std, 0.002);
  EXPECT_LT(std::abs(r.cad_summary.mean), 0.0004);
  EXPECT_LT(r.cad_summary.max_abs(), 0.020);
  EXPECT_GE(r.coverage_2u, 0.92);
}

}  // namespace
}  // namespace probecomp::studies
