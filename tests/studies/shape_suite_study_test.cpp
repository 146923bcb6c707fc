// Cases of the shape suite (issue 48) end to end, against the simulator's truth: what a user must be able to rely
// on whatever the fit's accuracy on them.

#include "probecomp/studies/shape_suite_study.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "probecomp/cad/locator.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/error.hpp"
#include "probecomp/simulation/measure.hpp"
#include "probecomp/simulation/random.hpp"
#include "support/gross_errors.hpp"
#include "support/light.hpp"

namespace probecomp::studies {
namespace {

simulation::ShapeCase suite_case(const std::string& name) {
  for (const simulation::ShapeCase& c : simulation::shape_suite()) {
    if (c.name.rfind(name, 0) == 0) return c;
  }
  ADD_FAILURE() << name << " is not in the suite";
  return {};
}

// A case run on one draw of its noise (ShapeCase::noise_draw), its figures printed.
ShapeCaseResult run_noise_draw(simulation::ShapeCase c, std::uint64_t draw) {
  c.noise_draw = draw;
  ShapeCaseResult r = run_shape_case(c);
  std::printf("%s, noise draw %d: std %.2f um, largest %.1f um, fitted centres %.2f um rms, mean u %.2f um, "
              "coverage %.1f %%\n", c.name.c_str(), static_cast<int>(draw), r.cad_summary.std * 1e3,
              r.cad_summary.max_abs() * 1e3, r.fit_rms * 1e3, r.mean_uncertainty * 1e3, 100.0 * r.coverage_2u);
  return r;
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
  // Its dent between the lines: the normal there is not measured, and the user is told (compensation/scan_lines.hpp).
  EXPECT_TRUE(std::any_of(r.cad.warnings.begin(), r.cad.warnings.end(), [](const std::string& w) {
    return w.find("across the lines, where nothing was measured") != std::string::npos;
  }));
  for (const std::string& w : r.cad.warnings) std::printf("warning: %s\n", w.c_str());
}

// The same lines at the suite's 7 000 points (S13; S29 across a 0.3 mm crease). Exact data leave every knot span the
// fit misses by a tenth of a micrometre unexplained, and the spans' penalty had gone down to a millionth: between the
// lines nothing held the fit, it rang there, and the contacts, offset along normals that come from across the lines,
// were off by S13 std 4.65 µm (largest 142 µm), S29 49.4 µm (550 µm). The penalty of a span on lines without noise
// is now kept from a hundredth (compensation/face_fits.cpp): measured 0.33 µm (9.2) and 2.35 µm (45.6). S29's
// worst row is 4.2 u before and 4.4 u after (its crease: 0.3 mm over 1 mm between lines 4 mm apart): not yet
// within 3 u.
TEST(ShapeSuite, ScanLinesWithoutNoiseDoNotRingBetweenTheLines) {
  if (test::kLight) GTEST_SKIP() << "ScanLinesWithoutNoiseStateTheirErrorInU runs the same code at 3 000 points";
  for (const auto& [name, std_bound, max_bound, u_bound] :
       {std::tuple{"S13", 0.001, 0.020, 3.0}, std::tuple{"S29", 0.005, 0.100, 3.0}}) {
    SCOPED_TRACE(name);
    const ShapeCaseResult r = run_shape_case(suite_case(name));
    double worst = 0.0;
    for (std::size_t k = 0; k < r.cad.points.size(); ++k) {
      if (r.cad.points[k].status != compensation::PointStatus::Ok || !std::isfinite(r.cad_error[k])) continue;
      ASSERT_TRUE(std::isfinite(r.cad.points[k].uncertainty) && r.cad.points[k].uncertainty > 0.0) << k;
      worst = std::max(worst, std::abs(r.cad_error[k]) / r.cad.points[k].uncertainty);
    }
    std::printf("%s: std %.2f um, largest %.1f um, worst error %.2f u, worst region's ±2u coverage %.1f %%\n", name,
                r.cad_summary.std * 1e3, r.cad_summary.max_abs() * 1e3, worst, 100.0 * r.worst_region_coverage_2u);
    EXPECT_LT(r.cad_summary.std, std_bound);
    EXPECT_LT(r.cad_summary.max_abs(), max_bound);
    EXPECT_LE(worst, u_bound);
    // Issue 48's bar in every region: S29's normals across the lines, 2–4° off about the crease, are within the
    // unseen turn taken over a spacing along each line (compensation/scan_lines.hpp; 79.1 % with the point's own).
    EXPECT_GE(r.worst_region_coverage_2u, 0.88);
  }
}

// ShapeCase::noise_draw replicates a case: the same part, the same programmed points and the same true contacts,
// the noise drawn afresh (independent of the case's own, of the same σ), so that a figure can be told apart from
// what one draw of the noise happened to do.
TEST(ShapeSuite, ANoiseDrawKeepsThePartAndThePointsAndDrawsTheNoiseAfresh) {
  simulation::ShapeCase c = suite_case("S02");
  c.points = 1500;
  const SimulatedMeasurement own_case = shape_case_measurement(c);
  c.noise_draw = 1;
  const SimulatedMeasurement again_case = shape_case_measurement(c);
  // The touches run_shape_case compensates (compare_methods), without compensating them.
  const std::vector<simulation::Touch> own = simulate_measurement(own_case), again = simulate_measurement(again_case);
  ASSERT_EQ(own.size(), again.size());
  ASSERT_EQ(own_case.plan.size(), own.size());
  double squared = 0.0, cross = 0.0, own_squared = 0.0, again_squared = 0.0;
  for (std::size_t k = 0; k < own.size(); ++k) {
    ASSERT_EQ(own_case.plan[k].point, again_case.plan[k].point) << k;
    ASSERT_EQ(own[k].contact, again[k].contact) << k;
    ASSERT_EQ(own[k].centre, again[k].centre) << k;
    const Vector3 e0 = own[k].measured - own[k].centre;
    const Vector3 e1 = again[k].measured - again[k].centre;
    squared += (e0 - e1).squaredNorm();
    cross += e0.dot(e1);
    own_squared += e0.squaredNorm();
    again_squared += e1.squaredNorm();
  }
  const double n = static_cast<double>(own.size());
  // Independent draws of σ per coordinate: E|e0 − e1|² = 6σ² (standard error of the mean about 2 % here), and
  // their correlation 0 within a standard error of 1/√(3n) = 0.015.
  EXPECT_NEAR(squared / (6.0 * n * c.noise_sigma * c.noise_sigma), 1.0, 0.1);
  EXPECT_LT(std::abs(cross) / std::sqrt(own_squared * again_squared), 0.06);
}

// ±2u's coverage in each of 6 × 6 regions of the face, averaged over 8 draws of the noise: what u promises a region
// (one draw's coverage of a region swings with the few independent errors it holds, even for a u that knows each
// point's true rms error: docs/accuracy.md). S09 (a twist and two dents on the hood, random points) and S12 (a
// crease and a band wave at σ = 10 µm): their lowest regions held 87.8 and 83.8 % on average, and one of S12's draws
// 82.5 % overall, before the smoothing-bias estimate took eight passes and the thin-misfit trial its bound from
// the fit's own null draws (2f46744); 92.1 and 92.5 % after, every draw 93.9 % or more overall.
TEST(ShapeSuite, EveryRegionsCoverageAveragedOverDrawsOfTheNoiseIsAtLeast88Percent) {
  if (test::kLight) GTEST_SKIP() << "16 runs of the pipeline, which AMisfitThinOverTheFace... runs (run_shape_case) here";
  constexpr int kDraws = 8;
  for (const char* name : {"S09", "S12"}) {
    SCOPED_TRACE(name);
    const ReplicatedShapeCase r = replicate_shape_case(suite_case(name), kDraws);
    ASSERT_EQ(r.coverages.size(), static_cast<std::size_t>(kDraws));
    // Above 99 % by more than a draw's sampling error (6 000 rows at 99 %: a binomial standard error of 0.13
    // points) u would be needlessly wide; within it the draw cannot tell. The bound is checked on 16 draws (two
    // cases, eight each), so each at z = 2.73, the one-sided 5 % point shared among the 16 (Bonferroni): at two
    // standard errors a u that covers exactly 99 % would fail one of them about a third of the time. With the
    // anisotropy chosen on each net S12's draws 0 and 7 cover 99.28 % (99.2 % before): its u is generous at
    // σ = 10 µm (2.34 µm rms against errors of 1.73 µm std on draw 7).
    constexpr double kRows = 6000.0;
    constexpr double kFamilyZ = 2.73;
    const double above = kFamilyZ * std::sqrt(0.99 * 0.01 / kRows);
    for (int d = 0; d < kDraws; ++d) {
      EXPECT_GE(r.coverages[static_cast<std::size_t>(d)], 0.92) << "draw " << d;
      EXPECT_LE(r.coverages[static_cast<std::size_t>(d)], 0.99 + above) << "draw " << d;
    }
    std::printf("%s: lowest region's coverage averaged over %d draws %.1f %%\n", name, kDraws,
                100.0 * r.lowest_region_mean);
    EXPECT_GE(r.lowest_region_mean, 0.88);
  }
}

// A misfit spread thin over a face inflates the residuals' spread, which every span is then measured against, so
// no span stands out and the refinement stopped with the shape half followed and u blind to it. Two cases drawn
// from the suite's families (draw_shape_case, seeds 207 and 410; σ = 4.5 µm, random points): a bulge 0.34 mm high
// and 14 mm wide on the cylinder, no i,j,k (std 1.28 µm, ±2u held 59.6 % of the errors) and a 53 µm wave 17 mm long
// in a band on the panel (1.87 µm, 72.5 %). Refined on trial where the residuals exceed σ on average, each trial kept
// only if it predicts left-out points better (fitting/adaptive.cpp): 0.69 µm (88.0 %) and 1.19 µm (93.9 %).
TEST(ShapeSuite, AMisfitThinOverTheFaceIsFollowedNotTakenForNoise) {
  for (const auto& [seed, std_bound, coverage_bound] : {std::tuple{207, 0.0009, 0.85}, std::tuple{410, 0.0014, 0.90}}) {
    const simulation::ShapeCase c = simulation::draw_shape_case(static_cast<std::uint64_t>(seed), 0.0045);
    SCOPED_TRACE(c.name);
    const ShapeCaseResult r = run_shape_case(c);
    std::printf("draw %d: std %.2f um, largest %.1f um, coverage %.1f %% (worst region %.1f %%)\n", seed,
                r.cad_summary.std * 1e3, r.cad_summary.max_abs() * 1e3, 100.0 * r.coverage_2u,
                100.0 * r.worst_region_coverage_2u);
    EXPECT_LT(r.cad_summary.std, std_bound);
    EXPECT_GE(r.coverage_2u, coverage_bound);
  }
}

// A crease 0.3 mm high over 1 mm on the hood's grid, σ = 1.5 µm (S11): the fit, out of refinement rounds, does not
// follow its sharpest part, and readings there are left out as outliers although none is a gross error (the
// simulator makes none): 50 of S11's 7 031 points; on 1 500, 2 500 and 3 500 points at σ = 1.5 and 0.5 µm, 27 to
// 138 (found, not mended: the refits' local spread is of the points the fit follows). They lie along the crease,
// side by side, which gross errors seldom do, and the user is told so, with where. Here on 1 500 points (S11 itself
// takes a minute).
TEST(ShapeSuite, OutliersSideBySideAreToldAsPossiblyShape) {
  simulation::ShapeCase c = suite_case("S11");
  c.points = 1500;
  const ShapeCaseResult r = run_shape_case(c);
  int outliers = 0;
  for (const compensation::CompensatedPoint& p : r.cad.points) outliers += p.status == compensation::PointStatus::Outlier;
  const auto told = std::find_if(r.cad.warnings.begin(), r.cad.warnings.end(), [](const std::string& w) {
    return w.find("lie side by side") != std::string::npos;
  });
  std::printf("S11: %d outliers; %s\n", outliers, told == r.cad.warnings.end() ? "not told" : told->c_str());
  ASSERT_GT(outliers, 0);
  EXPECT_NE(told, r.cad.warnings.end());
}

// Gross errors on scan lines: 1 % of S03's centres (the panel's lines, σ = 4.5 µm, here on 3 000 points) moved
// 0.1–5 mm along their programmed normal, in and out (a stuck probe, a chip under the tip; testing::move_one_percent,
// as the pipeline's outlier tests). Every moved point is flagged and no other, and the other points' contacts are as
// near the true part as without the moved points: the first fit leaves out those that stand out alone
// (compensation/face_fits.cpp), on scan lines too. Measured: contacts rms 1.514 µm against 1.597 without the moved
// points (every hundredth point moved instead, 1.636 against 1.588; and the same with that first fit made with
// them, in twice the time).
TEST(ShapeSuite, GrossErrorsOnScanLinesAreFlaggedAndSpoilNothingElse) {
  simulation::ShapeCase c = suite_case("S03");
  c.points = 3000;
  const SimulatedMeasurement m = shape_case_measurement(c);
  const std::vector<simulation::Touch> touches = simulate_measurement(m);
  const cad::Model actual = simulation::actual_model(m.nominal, m.deformation, m.placement);
  const cad::ModelLocator part(actual);
  compensation::CompensateOptions o;
  o.probe_radius = m.probe_radius;
  o.accept_doubtful_registration = true;
  std::vector<Point3> raw, moved_raw;
  for (const simulation::Touch& t : touches) raw.push_back(t.measured);
  moved_raw = raw;
  const std::vector<char> moved = testing::move_one_percent(moved_raw, m.plan, 5);
  const compensation::CompensationResult clean = compensation::compensate(m.nominal, raw, std::nullopt, o);
  const compensation::CompensationResult dirty = compensation::compensate(m.nominal, moved_raw, std::nullopt, o);
  const std::vector<double> e_clean = errors_against(part, clean), e_dirty = errors_against(part, dirty);
  int missed = 0, good_flagged = 0, n = 0;
  double ss_clean = 0.0, ss_dirty = 0.0;
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const bool flagged = dirty.points[k].status == compensation::PointStatus::Outlier;
    if (moved[k]) {
      missed += !flagged;
      continue;
    }
    good_flagged += flagged;
    if (std::isnan(e_clean[k]) || std::isnan(e_dirty[k])) continue;
    ss_clean += e_clean[k] * e_clean[k];
    ss_dirty += e_dirty[k] * e_dirty[k];
    ++n;
  }
  const double rms_clean = std::sqrt(ss_clean / n), rms_dirty = std::sqrt(ss_dirty / n);
  std::printf("S03 on 3 000 points, 1 %% moved: %d moved missed, %d good points flagged; other contacts rms %.3f um "
              "(%.3f without the moved points), %d of them\n",
              missed, good_flagged, rms_dirty * 1e3, rms_clean * 1e3, n);
  EXPECT_EQ(missed, 0);
  EXPECT_EQ(good_flagged, 0);
  EXPECT_GT(n, 2900);
  EXPECT_LE(rms_dirty, 1.05 * rms_clean);
}

// With the balanced penalty (fitting::AdaptiveFitOptions::SpatialPenalty::Balance, the default) the same bulge on the
// cylinder (draw 207) is fitted on the coarse knots, and the fit misses part of it unseen by any estimate of its own
// bias: ±2u held 94.7 % overall and 43.4 % in the worst region. The fit from the finer start followed it, and
// cross-validation can hardly tell the two apart (scores 21.28 and 21.31 µm²); where they disagree u now holds the
// difference (fitting::fit_surface): 97.8 and 69.7 %. With the roughness rule, the finer start's fit is kept: 99.8
// and 93.2 %.
TEST(ShapeSuite, UHoldsWhatTwoFitsCrossValidationCannotTellApartDisagreeOn) {
  const simulation::ShapeCase c = simulation::draw_shape_case(207, 0.0045);
  const ShapeCaseResult r = run_shape_case(c);
  std::printf("draw 207: std %.2f um, coverage %.1f %% (worst region %.1f %%)\n", r.cad_summary.std * 1e3,
              100.0 * r.coverage_2u, 100.0 * r.worst_region_coverage_2u);
  EXPECT_GE(r.coverage_2u, 0.96);
  EXPECT_GE(r.worst_region_coverage_2u, 0.6);
}

// Scan lines 4 mm apart on a cylinder section, across creases (draw_shape_case, seeds 608 and 706; σ = 4.5 µm): a
// span holding one line was split between lines, into spans no point holds, and the fit rang there; the contacts,
// offset along its normals (up to 23° off), were std 18.1 and 6.9 µm off, largest 235 and 113 µm. A span is now split
// in a direction only where points lie on both sides of its middle (fitting/adaptive.cpp): 1.64 and 1.41 µm.
TEST(ShapeSuite, ScanLinesOnACylinderAreNotSplitBetweenTheLines) {
  for (const auto seed : test::cases<std::uint64_t>({608, 706})) {
    const simulation::ShapeCase c = simulation::draw_shape_case(seed, 0.0045);
    SCOPED_TRACE(c.name);
    ASSERT_EQ(c.sampling, simulation::Sampling::ScanLines);
    const ShapeCaseResult r = run_shape_case(c);
    std::printf("draw %llu: std %.2f um, largest %.1f um, coverage %.1f %%\n", static_cast<unsigned long long>(seed),
                r.cad_summary.std * 1e3, r.cad_summary.max_abs() * 1e3, 100.0 * r.coverage_2u);
    EXPECT_LT(r.cad_summary.std, 0.002);
    EXPECT_LT(r.cad_summary.max_abs(), 0.020);
    EXPECT_GE(r.coverage_2u, 0.92);
  }
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

// Scan lines 4.6 mm apart at σ = 4.5 µm over a dent and two waves (the drawn case D500). Leave-span-out scores are
// flat over decades of λ there, and on some draws of the noise the λ of the best score drifted round by round to
// where the fit swings between the lines: std 1.73, 21.4, 1.71, 7.16, 5.42, 2.00 µm over draws 0–5 (largest
// 7.6 to 189 µm), the fitted centres within 1.3–1.9 µm rms on every draw: the contacts' normals swung. With the
// smoothest λ within one standard error of the best score: 1.72, 1.48, 1.71, 1.75, 1.50, 2.02 µm, largest 5.7–8.1 µm.
// And u states that error, neither less nor many times more: a degenerate local cubic in the normal check had held
// it at a mean of 31 µm here (±2u covering 96 %); with the check sound, the bias along the lines and the normal across
// them that no data show (compensation/scan_lines.hpp), ±2u covers 93.6–95.8 % over draws 0–5 at a mean u of
// 1.54–1.84 µm, about the error's std. With a refinement tried on every net that reaches the noise (not only on
// saturated ones; fitting/refinement_tests.hpp) the six draws reach 1.30–1.50 µm (1.48–2.01 before), ±2u covering
// 95.3–98.1 %, largest 5.7–13.5 µm: the 13.5 µm row (draw 0) is stated with a u of 12.8 µm, while draw 3's largest,
// 10.4 µm at the face's edge, has a u of 2.3 µm (before: 7.2 µm).
TEST(ShapeSuite, ScanLinesAreFollowedOnEveryDrawOfTheNoise) {
  const simulation::ShapeCase drawn = simulation::draw_shape_case(500, 0.0045);
  ASSERT_EQ(drawn.sampling, simulation::Sampling::ScanLines);
  for (const std::uint64_t draw : test::kLight ? std::vector<std::uint64_t>{1} : std::vector<std::uint64_t>{0, 1, 2, 3, 4, 5}) {
    SCOPED_TRACE(draw);
    const ShapeCaseResult r = run_noise_draw(drawn, draw);
    EXPECT_LT(r.cad_summary.std, 0.0017);
    EXPECT_LT(r.cad_summary.max_abs(), 0.015);
    EXPECT_GE(r.coverage_2u, 0.94);
    EXPECT_LE(r.coverage_2u, 0.99);
    EXPECT_LT(r.mean_uncertainty, 1.5 * r.cad_summary.std);
  }
}

// A smooth shape the nominal's coarse net cannot follow, scanned along lines (D805: a 275 µm saddle on a cylinder,
// σ = 4.5 µm): its misfit, a fourth of σ, hid in the residuals' spread, no span stood out, and the fit stayed on the
// nominal's 20 control points with no penalty at work (contacts 1.13–1.15 µm std on four draws, the reference
// smoother 0.51 µm). A refinement is now tried once the noise is reached and kept on an F test
// (fitting/refinement_tests.hpp; the net saturated, no more is asked): 0.33–0.47 µm on the first three draws. Not on
// exact data.
TEST(ShapeSuite, ASmoothShapeTheNominalsNetCannotFollowIsFollowedAlongScanLines) {
  const simulation::ShapeCase drawn = simulation::draw_shape_case(805, 0.0045);
  ASSERT_EQ(drawn.sampling, simulation::Sampling::ScanLines);
  for (const std::uint64_t draw : test::kLight ? std::vector<std::uint64_t>{0} : std::vector<std::uint64_t>{0, 1, 2}) {
    SCOPED_TRACE(draw);
    const ShapeCaseResult r = run_noise_draw(drawn, draw);
    EXPECT_LT(r.cad_summary.std, 0.0007);
    EXPECT_LT(r.cad_summary.max_abs(), 0.004);
    EXPECT_GE(r.coverage_2u, 0.95);
  }
}

// Broad shapes on a net whose penalty still works (not saturated), scanned along lines: no span stands out, and a
// refinement was tried on saturated nets only, so they stayed on the nominal's net (D915, a 92 µm crease over 2.2 mm
// and a long wave: 1.165 µm std; D911, a bulge and a 17 mm wave on the hood: 1.314; D712, a bulge: 0.876; the
// reference smoother 0.857, 0.878, 0.691). Tried on every net that reaches the noise and kept only if it also lowers
// the expected prediction error (fitting/refinement_tests.hpp): 0.808, 0.980, 0.712 µm. And a narrow dent among lines
// (D1006, 139 µm of σ 0.9 mm), which a refinement over the whole face would follow only at the cost of the noise
// everywhere (0.416 µm with the prediction test at Mallows' 2σ² a degree of freedom), stays where it was: 0.349 µm.
TEST(ShapeSuite, ABroadShapeAlongScanLinesIsRefinedForAndANarrowDentIsNot) {
  for (const auto& [seed, std_bound] : test::cases<std::pair<std::uint64_t, double>>(
           {{915, 0.00095}, {1006, 0.00038}, {911, 0.0011}, {712, 0.00080}})) {
    const simulation::ShapeCase c = simulation::draw_shape_case(seed, 0.0045);
    SCOPED_TRACE(c.name);
    ASSERT_EQ(c.sampling, simulation::Sampling::ScanLines);
    const ShapeCaseResult r = run_shape_case(c);
    std::printf("%s: std %.3f um, largest %.1f um, +-2u %.1f %%\n", c.name.c_str(), r.cad_summary.std * 1e3,
                r.cad_summary.max_abs() * 1e3, 100.0 * r.coverage_2u);
    EXPECT_LT(r.cad_summary.std, std_bound);
    EXPECT_LT(r.cad_summary.max_abs(), 0.010);
    EXPECT_GE(r.coverage_2u, 0.95);
  }
}

// On scan lines the energy was kept isotropic, for the ringing an anisotropic one gave between the lines without
// noise. With noise an anisotropic fit is tried too (compensation/face_fits.cpp): on D409 (a 54 µm wave 13 mm long
// at 76° across lines on a cylinder) it follows the wave, std 1.234 -> 0.782 µm against the reference smoother's
// 0.771; on S16 (a twist and a 25 mm wave) θ chosen by leave-span-out alone rang between the lines, std 0.772 ->
// 3.024 µm, and the lines left out refused it (predicted 5.7 µm rms against 4.7 isotropic); the θ of its last net
// held from the first predicts them within 4.5 µm, and is taken: std 0.638 µm against the reference's 0.615. On S06
// (a crease, a ripple and a saddle on a panel) the lines left out refuse it (14 µm rms against 10.8).
TEST(ShapeSuite, AnAnisotropicEnergyOnScanLinesFollowsAWaveAcrossThemWithoutRingingBetweenThem) {
  for (const auto& [c, std_bound, told] :
       {std::tuple{simulation::draw_shape_case(409, 0.0045), 0.0009, "; anisotropic (log10 theta"},
        std::tuple{suite_case("S16"), 0.0007, ", held from the first net): interior lines left out"},
        std::tuple{suite_case("S06"), 0.0009, ") refused: interior lines left out"}}) {
    SCOPED_TRACE(c.name);
    ASSERT_EQ(c.sampling, simulation::Sampling::ScanLines);
    const ShapeCaseResult r = run_shape_case(c);
    ASSERT_EQ(r.cad.faces.size(), 1u);
    const std::string& why = r.cad.faces.front().stop_reason;
    std::printf("%s: std %.3f um, largest %.1f um; %s\n", c.name.c_str(), r.cad_summary.std * 1e3,
                r.cad_summary.max_abs() * 1e3, why.c_str());
    EXPECT_LT(r.cad_summary.std, std_bound);
    EXPECT_NE(why.find(told), std::string::npos);
    EXPECT_GE(r.coverage_2u, 0.92);
  }
}

// Issue 49: a face whose material side only the raw centres can tell (no i,j,k, no closed solid), the part up to
// 3° and 1 mm off its CAD frame. The centres' side of the nominal then decides nothing (1.2° over a 100 mm panel
// is 2 mm, twice r), and registered to the wrong side every contact came back 2r off and `ok`. Grids and scan
// lines on the panel and the hood, a broad bulge on each, two poses each: the mean error a fraction of a
// micrometre, never ±2r. The hood is gently curved and its bulge (0.15 mm) is in both sides' residuals: there the
// two may fit too alike to tell (measured: 19.1 against 22.0 µm), and then the run is refused, never guessed.
TEST(ShapeSuite, TheMaterialSideWithoutApproachNormalsDoesNotFlipWithThePose) {
  std::mt19937_64 rng(49);
  std::uniform_real_distribution<double> angle(-3.0, 3.0), shift(-0.55, 0.55);
  int runs = 0, refused = 0;
  for (const simulation::BaseSurface base : {simulation::BaseSurface::Panel, simulation::BaseSurface::Hood}) {
    for (const simulation::Sampling sampling : {simulation::Sampling::Grid, simulation::Sampling::ScanLines}) {
      for (int pose = 0; pose < (test::kLight ? 1 : 2); ++pose) {
        simulation::ShapeCase c;
        c.name = "side";
        c.base = base;
        c.sampling = sampling;
        c.points = 1500;
        c.approach_normals = false;
        c.noise_sigma = 0.003;
        c.features = {{.kind = simulation::FeatureSpec::Kind::Bump, .u = 0.4, .v = 0.6, .amplitude = 0.15, .size = 12.0}};
        c.rx = angle(rng);
        c.ry = angle(rng);
        c.rz = angle(rng);
        c.t = simulation::draw_vector(shift, rng);
        c.seed = static_cast<std::uint64_t>(10 + runs);
        ++runs;
        const char* what = simulation::to_string(base);
        try {
          const ShapeCaseResult r = run_shape_case(c);
          std::printf("%s %s, turned %.2f, %.2f, %.2f deg: mean %.3f um, std %.2f um; %s\n", what,
                      simulation::to_string(sampling), c.rx, c.ry, c.rz, r.cad_summary.mean * 1e3,
                      r.cad_summary.std * 1e3, r.cad.registration.notes.empty() ? "" : r.cad.registration.notes.back().c_str());
          EXPECT_LT(std::abs(r.cad_summary.mean), 0.0005) << what << " pose " << pose;
          EXPECT_LT(r.cad_summary.std, 0.004);
        } catch (const RegistrationError& e) {
          std::printf("%s %s refused: %s\n", what, simulation::to_string(sampling), e.what());
          EXPECT_NE(std::string(e.what()).find("cannot tell the material side"), std::string::npos) << e.what();
          // The panel's curvature shows the side through its bulge (measured: 17.7–18.8 against 33.2–34.8 µm).
          EXPECT_EQ(base, simulation::BaseSurface::Hood) << e.what();
          ++refused;
        }
      }
    }
  }
  EXPECT_LE(refused, 4);
}

// A flat plate: its two offset sides are the same plane 2r apart, which a translation takes up exactly, so only
// where the centres lie before registration can tell the material side. Turned 4° about a line across its middle,
// a quarter of them lie on the wrong side of the nominal: refused, with the reason, not guessed.
TEST(ShapeSuite, AFaceWhoseMaterialSideCannotBeToldIsRefused) {
  const nurbs::KnotVector U = nurbs::KnotVector::uniform(1, 1), V = nurbs::KnotVector::uniform(1, 1);
  cad::Model model;
  model.faces.push_back(cad::Face{
      .surface = nurbs::Surface(U, V, std::vector<Point3>{Point3(0, 0, 0), Point3(0, 40, 0), Point3(60, 0, 0), Point3(60, 40, 0)})});
  const geometry::RigidTransform pose = geometry::RigidTransform(
      Eigen::Translation3d(30.0, 20.0, 0.3) * Eigen::AngleAxisd(4.0 * std::numbers::pi / 180.0, Vector3(0.2, 1, 0).normalized()) *
      Eigen::Translation3d(-30.0, -20.0, 0.0));
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.003);
  std::vector<Point3> centres;
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 25; ++j) centres.push_back(pose * Point3(1.5 * i + 0.5, 1.5 * j + 1.0, 1.0 + noise(rng)));
  }
  compensation::CompensateOptions options;
  options.probe_radius = 1.0;
  try {
    (void)compensation::compensate(model, centres, std::nullopt, options);
    ADD_FAILURE() << "a plate's material side was guessed";
  } catch (const RegistrationError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot tell the material side"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace probecomp::studies
