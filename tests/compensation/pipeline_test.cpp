// The whole method end to end on simulated measurements (the simulator is checked on its own in
// tests/simulation): errors are signed distances of the compensated points from the actual surface, which the
// simulator knows exactly.

#include "probecomp/compensation/pipeline.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/plan.hpp"
#include "probecomp/simulation/freeform_case.hpp"
#include "probecomp/simulation/measure.hpp"
#include "probecomp/studies/freeform_study.hpp"
#include "support/gross_errors.hpp"
#include "support/light.hpp"

namespace probecomp {
namespace {

using compensation::PointStatus;

// The bars for the free-form case: CAD-based std ≤ 2 µm, |mean| ≤ 1 µm, max |error| ≤ 10 µm, and std and
// max |error| each at least 3× better than the conventional method on the same data.
void expect_freeform_bars(const studies::FreeformStudyResult& r) {
  const studies::ErrorSummary& cad = r.cad_summary;
  const studies::ErrorSummary& conv = r.conventional_summary;
  EXPECT_EQ(r.cad.points.size(), r.plan.size());  // every row back
  EXPECT_EQ(cad.points, static_cast<int>(r.plan.size())) << "every point trusted";
  EXPECT_LE(cad.std, 0.002);
  EXPECT_LE(std::abs(cad.mean), 0.001);
  EXPECT_LE(cad.max_abs(), 0.010);
  EXPECT_GE(conv.std, 3.0 * cad.std);
  EXPECT_GE(conv.max_abs(), 3.0 * cad.max_abs());
  EXPECT_TRUE(r.cad.registration.converged()) << r.cad.registration.stop_reason;
  std::printf("cad std %.6f mean %.6f max %.6f | conventional std %.6f max %.6f\n", cad.std, cad.mean, cad.max_abs(),
              conv.std, conv.max_abs());
}

// The built-in free-form study's touches as raw centres, and the options that compensate them.
struct StudyRun {
  studies::FreeformStudyResult study;
  std::vector<Point3> raw;
  compensation::CompensateOptions options;
};
StudyRun freeform_run() {
  StudyRun r{studies::run_freeform_study(), {}, {}};
  for (const simulation::Touch& t : r.study.touches) r.raw.push_back(t.measured);
  r.options.probe_radius = r.study.freeform.probe_radius;
  return r;
}

// The same points, bit for bit: status, contact, normal, deviation and u.
void expect_same_points(const std::vector<compensation::CompensatedPoint>& a,
                        const std::vector<compensation::CompensatedPoint>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].status, b[k].status) << k;
    ASSERT_EQ(a[k].contact, b[k].contact) << k;
    ASSERT_EQ(a[k].normal, b[k].normal) << k;
    ASSERT_EQ(a[k].deviation, b[k].deviation) << k;
    ASSERT_EQ(a[k].uncertainty, b[k].uncertainty) << k;
  }
}

TEST(Pipeline, FreeformCaseOnTheGridMeetsTheBars) { expect_freeform_bars(studies::run_freeform_study()); }

TEST(Pipeline, FreeformCaseWithAnotherNoiseDrawMeetsTheBars) {
  studies::FreeformStudyOptions o;
  o.seed = 7;
  expect_freeform_bars(studies::run_freeform_study(o));
}

TEST(Pipeline, RandomShuffledPointsWithoutApproachNormalsMeetTheBars) {
  const studies::FreeformStudyResult r = studies::run_freeform_study(studies::scattered_points(6000));
  expect_freeform_bars(r);
  EXPECT_EQ(r.cad.material.at(0).source, cad::MaterialSource::Data);
}

TEST(Pipeline, SurfaceWhoseNormalPointsIntoTheMaterialMeetsTheBars) {
  studies::FreeformStudyOptions o;
  o.reversed = true;
  const studies::FreeformStudyResult r = studies::run_freeform_study(o);
  expect_freeform_bars(r);
  EXPECT_EQ(r.cad.faces.at(0).outward, -1);
  // The normals given out point away from the material (towards the probe): +z for this panel.
  for (const auto& p : r.cad.points) ASSERT_GT(p.normal.z(), 0.5);
}

TEST(Pipeline, NoiseFreeDataAreCompensatedToASmallFractionOfAMicrometre) {
  studies::FreeformStudyOptions o;
  o.noise_sigma = 0.0;
  const studies::FreeformStudyResult r = studies::run_freeform_study(o);
  EXPECT_EQ(r.cad.count(PointStatus::Ok), static_cast<int>(r.plan.size())) << "no outliers in noise-free data";
  EXPECT_LE(r.cad_summary.max_abs(), 1e-3);
}

// Issue 19's low-noise bars: the outlier test must never eat real shape. 3 000 random points at σ = 1.5 µm, and
// the steep dent (19° flanks) without noise: no row flagged, largest error (flagged rows included) within 5 and
// 2 µm (before the outlier test was decided against the fit: 46 µm with 68 rows flagged, 27 µm with 7).
void expect_low_noise_bars(const studies::FreeformStudyOptions& o, double max_error) {
  const studies::FreeformStudyResult r = studies::run_freeform_study(o);
  EXPECT_EQ(r.cad.count(PointStatus::Ok), static_cast<int>(r.plan.size())) << "real shape flagged";
  EXPECT_LE(r.cad_summary.max_abs(), max_error);
  for (const auto& p : r.cad.points) {
    ASSERT_TRUE(std::isfinite(p.uncertainty));
    ASSERT_GE(p.uncertainty, 0.0);
  }
}

TEST(Pipeline, ThreeThousandRandomPointsAtLowNoiseKeepEveryRow) {
  studies::FreeformStudyOptions o = studies::scattered_points(3000);
  o.noise_sigma = 0.0015;
  expect_low_noise_bars(o, 0.005);
}

TEST(Pipeline, ASteepDentWithoutNoiseKeepsEveryRow) {
  studies::FreeformStudyOptions o;
  o.steep_dent = true;
  o.noise_sigma = 0.0;
  // The sanitizer build takes this path with TwoStyliWithoutNoiseAreExactOnASteepDent, the same dent and grid at a
  // quarter of the time (86 s here, the longest test there).
  if (test::kLight) GTEST_SKIP() << "light build: TwoStyliWithoutNoiseAreExactOnASteepDent runs the same path";
  expect_low_noise_bars(o, 0.002);
}

// Issue 21: two styli on one face (1 mm on the half of smaller x, 0.5 mm on the rest), each point with its own
// radius, no single --probe-radius: the same bars as with one tip. Without noise the contact points are exact to
// a fraction of a micrometre, on the steep dent's 19° flanks too (where the nominal normal the larger tips' centres
// are first moved along is farthest off the actual one).
TEST(Pipeline, TwoStyliOnOneFaceMeetTheBars) {
  studies::FreeformStudyOptions o;
  o.second_probe_radius = 0.5;
  const studies::FreeformStudyResult r = studies::run_freeform_study(o);
  expect_freeform_bars(r);
  int small = 0;
  for (const auto& p : r.cad.points) small += p.radius == 0.5;
  EXPECT_GT(small, 1000);
  EXPECT_LT(small, static_cast<int>(r.plan.size()) - 1000);
  EXPECT_DOUBLE_EQ(r.cad.centre_radius, 0.5);
}

TEST(Pipeline, TwoStyliWithoutNoiseAreExactOnASteepDent) {
  studies::FreeformStudyOptions o;
  o.second_probe_radius = 0.5;
  o.steep_dent = true;
  o.noise_sigma = 0.0;
  expect_low_noise_bars(o, 0.002);
}

TEST(Pipeline, TipRadiiThatAreNotPositiveOrDoNotMatchThePointsAreRefused) {
  const simulation::FreeformCase c = simulation::paper_freeform_case();
  const std::vector<Point3> raw{Point3(0, 0, 1), Point3(10, 0, 1), Point3(0, 10, 1)};
  compensation::CompensateOptions o;
  o.probe_radii = {1.0, 0.0, 1.0};
  try {
    (void)compensation::compensate(c.nominal, raw, std::nullopt, o);
    ADD_FAILURE() << "a zero radius was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("point 2"), std::string::npos) << e.what();
  }
  o.probe_radii = {1.0, 1.0};
  EXPECT_THROW((void)compensation::compensate(c.nominal, raw, std::nullopt, o), InputError);
}

// compensate() is the composition of the named steps: called one by one they give the same points, and the
// statistics and face reports say what the points say.
TEST(Pipeline, TheStepsComposeToCompensate) {
  const StudyRun run = freeform_run();
  const studies::FreeformStudyResult& study = run.study;
  const std::vector<Point3>& raw = run.raw;
  const compensation::CompensateOptions& o = run.options;
  const compensation::CompensationResult whole = compensation::compensate(study.freeform.nominal, raw, std::nullopt, o);

  const compensation::PreparedModel prepared =
      compensation::prepare_model(study.freeform.nominal, o.probe_radius, raw, std::nullopt);
  const registration::RegistrationResult reg = compensation::register_centres(prepared, raw);
  const compensation::FitResult fits = compensation::fit_faces(prepared, raw, reg);
  expect_same_points(compensation::compensate_points(prepared, raw, reg, fits), whole.points);
  ASSERT_EQ(fits.faces.size(), 1u);
  const compensation::FaceReport& face = fits.faces[0].report;
  EXPECT_TRUE(face.fitted) << face.stop_reason;
  EXPECT_FALSE(face.stop_reason.empty());
  // The dent needs refinement: the fit has more control points than the (degree-raised) offset face, so its
  // rounds over all fits are at least one, and every fit counts.
  EXPECT_GE(face.fits, 1);
  EXPECT_GE(face.rounds, 1);
  EXPECT_GT(face.control_points, prepared.offset->model.faces[0].surface.num_u() * prepared.offset->model.faces[0].surface.num_v());
  EXPECT_EQ(face.material, cad::MaterialSource::Data);  // no approach normals given: decided from the centres

  // The statistics, recomputed here from the points.
  const compensation::Statistics& st = whole.statistics;
  double sum = 0.0, lo = 1e9, hi = -1e9;
  int ok = 0;
  for (const auto& p : whole.points) {
    if (p.status != PointStatus::Ok) continue;
    ++ok;
    sum += p.deviation;
    lo = std::min(lo, p.deviation);
    hi = std::max(hi, p.deviation);
  }
  const double mean = sum / ok;
  double ss = 0.0;
  for (const auto& p : whole.points) {
    if (p.status == PointStatus::Ok) ss += (p.deviation - mean) * (p.deviation - mean);
  }
  EXPECT_EQ(st.total, static_cast<int>(raw.size()));
  EXPECT_EQ(st.count(PointStatus::Ok), ok);
  EXPECT_NEAR(st.deviation_mean, mean, 1e-12);
  EXPECT_NEAR(st.deviation_std, std::sqrt(ss / ok), 1e-12);
  EXPECT_EQ(st.deviation_min, lo);
  EXPECT_EQ(st.deviation_max, hi);
}

TEST(Pipeline, SameResultWithOneAndTwoThreads) {
  // Every parallel step sums or searches in an order fixed by the data, not by the threads: the same bits.
  const StudyRun run = freeform_run();
  std::vector<compensation::CompensationResult> results;
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    results.push_back(compensation::compensate(run.study.freeform.nominal, run.raw, std::nullopt, run.options));
  }
  const compensation::CompensationResult& one = results[0];
  const compensation::CompensationResult& two = results[1];
  EXPECT_EQ(one.registration.transform.matrix(), two.registration.transform.matrix());
  EXPECT_EQ(one.registration.iterations, two.registration.iterations);
  EXPECT_EQ(one.registration.searches, two.registration.searches);
  expect_same_points(one.points, two.points);
}

TEST(Pipeline, RegistrationThatCannotRunIsARegistrationError) {
  const simulation::FreeformCase c = simulation::paper_freeform_case();
  // Three points cannot fix six motions.
  const std::vector<Point3> raw{Point3(10, 10, 1), Point3(20, 10, 1), Point3(10, 20, 1)};
  compensation::CompensateOptions o;
  o.probe_radius = 1.0;
  EXPECT_THROW((void)compensation::compensate(c.nominal, raw, std::nullopt, o), RegistrationError);
}

// Point sets that fix nothing are refused with the reason, before registration (issue 20): identical points
// (before: 500 of them came back "ok" with u = 0.1 µm) and points on one line (two points, a straight scan).
TEST(Pipeline, IdenticalOrCollinearPointsAreRefusedWithTheReason) {
  const simulation::FreeformCase c = simulation::paper_freeform_case();
  compensation::CompensateOptions o;
  o.probe_radius = 1.0;
  auto message = [&](const std::vector<Point3>& raw) -> std::string {
    try {
      (void)compensation::compensate(c.nominal, raw, std::nullopt, o);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no InputError";
  };
  EXPECT_NE(message(std::vector<Point3>(500, Point3(10, 5, 3.2))).find("all 500 points are at one position"),
            std::string::npos);
  // Identical to within 1e-10 mm is the same position.
  std::vector<Point3> nearly(50, Point3(10, 5, 3.2));
  for (std::size_t k = 0; k < nearly.size(); ++k) nearly[k].x() += 1e-10 * static_cast<double>(k % 2);
  EXPECT_NE(message(nearly).find("at one position"), std::string::npos);
  std::vector<Point3> line;
  for (int k = 0; k < 200; ++k) line.emplace_back(-40.0 + 0.4 * k, 0.1 * k - 10.0, 3.0);
  EXPECT_NE(message(line).find("lie on one line"), std::string::npos) << message(line);
  EXPECT_NE(message({Point3(10, 10, 1), Point3(20, 10, 1)}).find("lie on one line"), std::string::npos);
  // A non-finite row does not hide that the rest are one point.
  std::vector<Point3> with_nan(20, Point3(1, 2, 3));
  with_nan.push_back(Point3(std::nan(""), 0, 0));
  EXPECT_NE(message(with_nan).find("all 20 points"), std::string::npos) << message(with_nan);
}

TEST(Pipeline, ConventionalMethodWithoutApproachNormalsSaysWhy) {
  const simulation::FreeformCase c = simulation::paper_freeform_case();
  const std::vector<Point3> raw{Point3(0, 0, 1)};
  compensation::CompensateOptions o;
  o.method = compensation::Method::Conventional;
  o.probe_radius = 1.0;
  try {
    (void)compensation::compensate(c.nominal, raw, std::nullopt, o);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("i,j,k"), std::string::npos) << e.what();
    // The library speaks of the method, never of a command-line option.
    EXPECT_EQ(std::string(e.what()).find("--"), std::string::npos) << e.what();
  }
}

TEST(Pipeline, PointsFarFromTheModelAreAnError) {
  const simulation::FreeformCase c = simulation::paper_freeform_case();
  std::vector<Point3> raw;
  for (int k = 0; k < 100; ++k) raw.emplace_back(1000.0 + k, 0.0, 500.0);
  compensation::CompensateOptions o;
  o.probe_radius = 1.0;
  EXPECT_THROW((void)compensation::compensate(c.nominal, raw, std::nullopt, o), InputError);
}

// A multi-face part from a real STEP file: the top (a bicubic B-spline) and two trimmed side planes of
// 1 % gross errors (0.3 to 1.1 mm out or in, as a stuck probe or a chip under the tip gives) in the free-form
// grid: every one is flagged, almost no good point is, and the trusted points still meet the bars.
TEST(Pipeline, GrossOutliersAreFlaggedAndDoNotSpoilTheirNeighbours) {
  const simulation::FreeformCase c = simulation::paper_freeform_case();
  const cad::Model actual = simulation::actual_model(c.nominal, c.deformation, c.placement);
  const cad::ModelLocator actual_locator(actual);
  const auto plan = simulation::grid_plan(c.nominal.faces.front(), c.grid_u, c.grid_v);
  auto touches = simulation::simulate_touches(actual_locator, plan,
                                              {.probe_radius = c.probe_radius, .noise_sigma = c.noise_sigma, .seed = 4});
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> size(0.3, 1.1);
  std::vector<char> gross(plan.size(), 0);
  std::vector<Point3> raw;
  std::vector<Vector3> normals;
  for (std::size_t k = 0; k < plan.size(); ++k) {
    Point3 x = touches[k].measured;
    if (rng() % 100 == 0) {
      gross[k] = 1;
      x += (rng() % 2 ? 1.0 : -1.0) * size(rng) * plan[k].normal;
    }
    raw.push_back(x);
    normals.push_back(plan[k].normal);
  }
  compensation::CompensateOptions o;
  o.probe_radius = c.probe_radius;
  const auto r = compensation::compensate(c.nominal, raw, std::span<const Vector3>(normals), o);
  int planted = 0, caught = 0, good_flagged = 0;
  std::vector<double> errors;
  for (std::size_t k = 0; k < plan.size(); ++k) {
    planted += gross[k];
    const bool flagged = r.points[k].status == PointStatus::Outlier;
    if (gross[k]) {
      caught += flagged;
      EXPECT_TRUE(flagged) << "gross error at point " << k << " trusted";
    } else {
      good_flagged += flagged;
      if (r.points[k].status == PointStatus::Ok) errors.push_back(actual_locator.closest_point(r.points[k].contact).distance);
    }
  }
  const studies::ErrorSummary e = studies::summarise(errors);
  std::printf("gross outliers: %d planted, %d caught, %d good points flagged; trusted std %.6f mean %.6f max %.6f\n",
              planted, caught, good_flagged, e.std, e.mean, e.max_abs());
  EXPECT_GT(planted, 40);
  EXPECT_LE(good_flagged, static_cast<int>(0.002 * static_cast<double>(plan.size())));
  EXPECT_LE(e.std, 0.002);
  EXPECT_LE(std::abs(e.mean), 0.001);
  EXPECT_LE(e.max_abs(), 0.010);
}

// AnalysisSitus's wavy cube (1 mm), probe radius 0.1 mm, misaligned by 5 µm and 0.3°, σ = 0.5 µm.
TEST(Pipeline, MultiFaceStepPartLandsEveryPointOnItsFace) {
  const cad::Model nominal = cad::read_model(std::filesystem::path(PROBECOMP_TEST_CAD_DIR) / "asitus_wavy-cube.stp");
  const std::vector<cad::PlannedPoint> planned = cad::plan_points(nominal, 0.025, {2, 3, 5});
  std::vector<simulation::ProgrammedPoint> plan;
  for (const auto& p : planned) plan.push_back({p.point, p.normal, p.face});
  const geometry::RigidTransform placement =
      geometry::from_pose({.rx = 0.3, .ry = -0.2, .rz = 0.1, .t = Vector3(0.005, -0.003, 0.004)});
  const cad::Model actual = simulation::actual_model(nominal, {}, placement);
  const cad::ModelLocator actual_locator(actual);
  const double sigma = 0.0005;
  const auto touches = simulation::simulate_touches(actual_locator, plan, {.probe_radius = 0.1, .noise_sigma = sigma, .seed = 2});
  std::vector<Point3> raw;
  std::vector<Vector3> normals;
  for (std::size_t k = 0; k < touches.size(); ++k) {
    raw.push_back(touches[k].measured);
    normals.push_back(plan[k].normal);
  }
  compensation::CompensateOptions o;
  o.probe_radius = 0.1;
  const auto r = compensation::compensate(nominal, raw, std::span<const Vector3>(normals), o);
  ASSERT_EQ(r.points.size(), raw.size());
  int compared = 0, wrong_face = 0;
  std::vector<double> errors;
  for (std::size_t k = 0; k < raw.size(); ++k) {
    if (touches[k].status != simulation::Touch::Status::OK) continue;
    if (r.points[k].status == PointStatus::Edge) continue;  // the tip reached past an edge: reported, not judged
    ++compared;
    wrong_face += r.points[k].face != touches[k].face;
    ASSERT_EQ(r.points[k].status, PointStatus::Ok) << k;
    errors.push_back(actual_locator.closest_point(r.points[k].contact).distance);
  }
  EXPECT_EQ(wrong_face, 0);
  EXPECT_GE(compared, static_cast<int>(0.8 * static_cast<double>(raw.size())));
  const studies::ErrorSummary e = studies::summarise(errors);
  std::printf("multi-face: %d points compared, error std %.2e mean %.2e max %.2e (sigma %.1e)\n", compared, e.std,
              e.mean, e.max_abs(), sigma);
  EXPECT_LT(e.std, sigma);  // smoothing removes noise
  EXPECT_LT(e.max_abs(), 3.0 * sigma);
  int fitted = 0;
  for (const auto& f : r.faces) fitted += f.fitted;
  EXPECT_GE(fitted, 2);
}

}  // namespace
}  // namespace probecomp

namespace probecomp {
namespace {

using testing::move_one_percent;

// The paper's free-form case measured on an nu × nv grid, with the true part to score the results against.
struct PaperPanel {
  simulation::FreeformCase c = simulation::paper_freeform_case();
  cad::Model actual = simulation::actual_model(c.nominal, c.deformation, c.placement);
  cad::ModelLocator locator{actual};
  std::vector<simulation::ProgrammedPoint> plan;
  compensation::CompensateOptions options;
  PaperPanel(int nu, int nv) : plan(simulation::grid_plan(c.nominal.faces.front(), nu, nv)) {
    options.probe_radius = c.probe_radius;
  }
  // The probe centres the machine reports for the plan, noise σ (mm) drawn with `seed`; every touch must land.
  [[nodiscard]] std::vector<Point3> centres(double sigma, std::uint64_t seed) const {
    std::vector<Point3> out;
    for (const simulation::Touch& t :
         simulation::simulate_touches(locator, plan, {.probe_radius = c.probe_radius, .noise_sigma = sigma, .seed = seed})) {
      EXPECT_EQ(t.status, simulation::Touch::Status::OK);
      out.push_back(t.measured);
    }
    return out;
  }
};

// The run with gross errors against the run without those points: every moved point flagged, every other point of
// the same status; returns how far the others' results moved (contact point or deviation, the larger), mm.
double others_moved(const compensation::CompensationResult& with_errors, const compensation::CompensationResult& alone,
                    const std::vector<char>& moved) {
  double largest = 0.0;
  for (std::size_t i = 0, j = 0; i < moved.size(); ++i) {
    if (moved[i]) {
      EXPECT_EQ(with_errors.points[i].status, compensation::PointStatus::Outlier) << i;
      continue;
    }
    const compensation::CompensatedPoint& p = with_errors.points[i];
    EXPECT_EQ(p.status, alone.points[j].status) << i;
    largest = std::max({largest, (p.contact - alone.points[j].contact).norm(), std::abs(p.deviation - alone.points[j].deviation)});
    ++j;
  }
  return largest;
}

// A few gross errors (3 of 7 200 points moved 5 mm, under pipeline.cpp's kMaxSkippedShare) pull on the
// registration by less than ICP's own tolerance (to first order, H⁺ Σ w r J: 0.015 and 0.007 µm against 0.042): the
// registration is not made again for them (the result's left_out is 0; 3 when it is),
// and the other points' results still stay within the 0.5 µm of the run without them (measured 0.022 and
// 0.016 µm). Moved 0.1–5 mm instead, the same three pull by 0.045 and 0.18 µm, and the registration is made again.
// Two seeds, 120 × 60 points.
TEST(Pipeline, AFewGrossOutliersAreLeftOutWithoutRegisteringAgain) {
  const PaperPanel panel(120, 60);
  const compensation::CompensateOptions& o = panel.options;
  const simulation::FreeformCase& c = panel.c;
  for (const std::uint64_t seed : test::cases<std::uint64_t>({1u, 2u})) {
    SCOPED_TRACE(seed);
    const std::vector<Point3> clean = panel.centres(c.noise_sigma, seed);
    ASSERT_FALSE(HasFailure());
    std::vector<Point3> contaminated = clean;
    std::mt19937_64 rng(seed);
    std::vector<char> moved(clean.size(), 0);
    for (int k = 0; k < 3; ++k) {
      const std::size_t i = rng() % clean.size();
      moved[i] = 1;
      contaminated[i] += (rng() % 2 ? 1.0 : -1.0) * 5.0 * panel.plan[i].normal;
    }
    std::vector<Point3> without;
    for (std::size_t i = 0; i < clean.size(); ++i) {
      if (!moved[i]) without.push_back(clean[i]);
    }
    const auto with_errors = compensation::compensate(c.nominal, contaminated, std::nullopt, o);
    const auto alone = compensation::compensate(c.nominal, without, std::nullopt, o);
    const double largest = others_moved(with_errors, alone, moved);
    std::cout << "seed " << seed << ": others moved " << largest * 1e3 << " um from the run without the 3 outliers; "
              << with_errors.registration.searches << " closest-point searches (without them: "
              << alone.registration.searches << ")\n";
    EXPECT_LE(largest, 0.0005);
    EXPECT_EQ(with_errors.registration.left_out, 0);
  }
}

// Issue 25: 1 % of the points moved 0.1–5 mm (gross errors: a dirty tip, a vibration) are all flagged, and move no
// other point's result (contact point and deviation) by more than 0.5 µm from what it is without them (measured:
// 0.053, 0.033, 0.021 µm; the deviations moved up to 0.52 µm before the registration was made again without the
// flagged points, compensation/pipeline.cpp register_without_outliers). Three
// seeds on the paper's free-form case, 60 × 30 points. Against the run where those points kept their true
// positions, the others differ by what losing 1 % of the data costs: their deviations by 6.7, 6.1 and 0.9 µm, under
// 2 stated uncertainties (bounded here at 3). Their contact points can slide further along the surface (14.7, 30.3,
// 1.2 µm) on the dent's flanks, which this grid barely resolves: the fitted normal there follows which points the
// fit has (printed, not bounded; the distance from the true surface stays within the points' u). The same with
// the balanced penalty (AdaptiveFitOptions::SpatialPenalty::Balance), whose first fit, had it been balanced, let a
// good point be flagged beside the gross errors (compensation/face_fits.cpp).
TEST(Pipeline, GrossOutliersMoveNoOtherPoint) {
  const PaperPanel panel(60, 30);
  const simulation::FreeformCase& c = panel.c;
  using Penalty = fitting::AdaptiveFitOptions::SpatialPenalty;
  using Case = std::pair<Penalty, std::uint64_t>;
  // (The balance, the default, first: the sanitizer build runs that case alone, through a rough first fit and the
  // balanced refits, for Pipeline.TheBalancedFitIsMadeAlone... and GrossOutliersAtLowAndHighNoise..., too slow there.)
  for (const auto& [penalty, seed] :
       test::cases<Case>({{Penalty::Balance, 1}, {Penalty::Balance, 2}, {Penalty::Balance, 3},
                          {Penalty::Roughness, 1}, {Penalty::Roughness, 2}, {Penalty::Roughness, 3}})) {
    compensation::CompensateOptions o = panel.options;
    o.fit.surface.spatial_penalty = penalty;
    SCOPED_TRACE(::testing::Message() << (penalty == Penalty::Balance ? "balance" : "roughness") << " seed " << seed);
    const std::vector<Point3> clean = panel.centres(c.noise_sigma, seed);
    ASSERT_FALSE(HasFailure());
    std::vector<Point3> contaminated = clean;
    const std::vector<char> moved = move_one_percent(contaminated, panel.plan, seed);
    std::vector<Point3> without;
    for (std::size_t i = 0; i < clean.size(); ++i) {
      if (!moved[i]) without.push_back(clean[i]);
    }
    const auto with_errors = compensation::compensate(c.nominal, contaminated, std::nullopt, o);
    const auto alone = compensation::compensate(c.nominal, without, std::nullopt, o);
    const auto reference = compensation::compensate(c.nominal, clean, std::nullopt, o);
    const double largest = others_moved(with_errors, alone, moved);
    ASSERT_FALSE(HasFailure());
    // 1 % flagged, above pipeline.cpp's kMaxSkippedShare: registered again without them.
    EXPECT_GT(with_errors.registration.left_out, 0);
    double largest_vs_clean = 0.0, dev_vs_clean = 0.0, dev_in_u = 0.0;
    for (std::size_t i = 0; i < clean.size(); ++i) {
      if (moved[i]) continue;
      const compensation::CompensatedPoint& p = with_errors.points[i];
      const double vs_clean = (p.contact - reference.points[i].contact).norm();
      dev_vs_clean = std::max(dev_vs_clean, std::abs(p.deviation - reference.points[i].deviation));
      dev_in_u = std::max(dev_in_u, std::abs(p.deviation - reference.points[i].deviation) / reference.points[i].uncertainty);
      largest_vs_clean = std::max(largest_vs_clean, vs_clean);
    }
    std::cout << (penalty == Penalty::Balance ? "balance" : "roughness") << " seed " << seed << ": others moved "
              << largest * 1e3 << " um from the run without the outliers; "
              << dev_vs_clean * 1e3 << " um in deviation (" << dev_in_u << " u) and " << largest_vs_clean * 1e3
              << " um in contact point from the run with them unmoved\n";
    EXPECT_LE(largest, 0.0005);
    EXPECT_LE(dev_in_u, 3.0);
  }
}

}  // namespace
}  // namespace probecomp

namespace probecomp {
namespace {

using testing::move_one_percent;

// The distance of each point's contact from the true (actual) part, against its stated uncertainty, for the points
// not moved; and whether each moved point was flagged.
struct AgainstTruth {
  double worst = 0.0;          // mm
  double worst_in_u = 0.0;     // largest error / u
  int good_flagged = 0;        // points not moved but flagged as outliers
  int moved_missed = 0;        // moved points not flagged
};
AgainstTruth against_truth(const compensation::CompensationResult& r, const cad::ModelLocator& actual,
                           const std::vector<char>& moved) {
  AgainstTruth t;
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    const bool flagged = r.points[i].status == compensation::PointStatus::Outlier;
    if (moved[i]) {
      t.moved_missed += !flagged;
      continue;
    }
    t.good_flagged += flagged;
    const double e = std::abs(actual.closest_point(r.points[i].contact).distance);
    t.worst = std::max(t.worst, e);
    t.worst_in_u = std::max(t.worst_in_u, e / r.points[i].uncertainty);
  }
  return t;
}

// Issue 25 at every noise level: on the paper's grid (120 × 60) with 1 % of the points moved 0.1–5 mm, at σ = 0.5,
// 1.5, 2.5 and 4.5 µm, three seeds: every moved point is flagged, no other point is, and every other point's contact is
// within 5 stated uncertainties of the true part. It guards the first fit's verdict against the face's noise
// (compensation/outliers.hpp): judged against the spread around each point like the refits, the first fit's pull
// towards a cluster of errors hid a 0.674 mm error among them (σ = 4.5 µm, seed 1), which the refits then
// followed (a contact 114 µm from the true part). The same with the balanced penalty (AdaptiveFitOptions::
// SpatialPenalty::Balance), which lets a fit follow gross errors and must not be used for the first verdict
// (compensation/face_fits.cpp): used there, σ = 0.5 µm gave contacts 9.0 and 84.7 µm off (against 1.4 and 1.2
// µm) and three good points flagged. Here the worst error is also bounded at 3 µm + 3σ: the balance's contacts
// within 5 u were 85 µm off. At σ = 2.5 µm, seed 3, a point on the dent's rim was 5.95 µm off at 5.9 u, with or
// without the gross errors: a bias of the net (fitting/representation_bias.hpp), now in its u (4.5 u; 4.8 u with
// the balance). Nor are the moved points, 72 at random, told as outliers side by side that may be shape.
// (One test per penalty, so that the two run side by side: together they take longer than a test may.)
void gross_outliers_at_low_and_high_noise(fitting::AdaptiveFitOptions::SpatialPenalty penalty) {
  const PaperPanel panel(120, 60);
  using Penalty = fitting::AdaptiveFitOptions::SpatialPenalty;
  compensation::CompensateOptions options = panel.options;
  options.fit.surface.spatial_penalty = penalty;
  for (const double sigma : test::cases({0.0005, 0.0015, 0.0025, 0.0045})) {
    for (const std::uint64_t seed : test::cases<std::uint64_t>({1u, 2u, 3u})) {
      SCOPED_TRACE(::testing::Message() << (penalty == Penalty::Balance ? "balance" : "roughness") << " sigma "
                                        << sigma << " seed " << seed);
      std::vector<Point3> points = panel.centres(sigma, seed);
      const std::vector<char> moved = move_one_percent(points, panel.plan, seed);
      const compensation::CompensationResult r = compensation::compensate(panel.c.nominal, points, std::nullopt, options);
      const AgainstTruth t = against_truth(r, panel.locator, moved);
      // Random gross errors are not told as a group of outliers that may be shape (compensation/warnings.hpp).
      for (const std::string& w : r.warnings) EXPECT_EQ(w.find("lie side by side"), std::string::npos) << w;
      std::printf("%s sigma %.1f um seed %d: worst error %.2f um (%.2f u); %d good points flagged, %d moved missed\n",
                  penalty == Penalty::Balance ? "balance" : "roughness", sigma * 1e3, static_cast<int>(seed),
                  t.worst * 1e3, t.worst_in_u, t.good_flagged, t.moved_missed);
      EXPECT_EQ(t.moved_missed, 0);
      EXPECT_EQ(t.good_flagged, 0);
      EXPECT_LE(t.worst_in_u, 5.0);
      EXPECT_LE(t.worst, 0.003 + 3.0 * sigma);
    }
  }
}

TEST(Pipeline, GrossOutliersAtLowAndHighNoise) {
  gross_outliers_at_low_and_high_noise(fitting::AdaptiveFitOptions::SpatialPenalty::Roughness);
}

TEST(Pipeline, GrossOutliersAtLowAndHighNoiseWithTheBalancedPenalty) {
  gross_outliers_at_low_and_high_noise(fitting::AdaptiveFitOptions::SpatialPenalty::Balance);
}

// With the balance (the default), a face with no centre standing out from what its neighbours predict is fitted once,
// balanced (compensation/face_fits.cpp); with 1 % of its points moved 0.1–5 mm it is first fitted with the roughness
// rule, then refitted balanced without them. Both against the true part: the paper's case at σ = 4.5 µm on 10 000
// random points (the benchmark's) and on its 120 × 60 grid, whose dent's rim stands out from the local quadratic at
// σ = 1.5 µm and takes the two fits there too.
TEST(Pipeline, TheBalancedFitIsMadeAloneWhereNoGrossErrorCanBe) {
  const PaperPanel grid(120, 60);
  PaperPanel random(1, 1);
  random.plan = simulation::random_plan(random.c.nominal.faces.front(), 10'000, 11);
  ASSERT_EQ(grid.options.fit.surface.spatial_penalty, fitting::AdaptiveFitOptions::SpatialPenalty::Balance);
  struct Run {
    const PaperPanel* panel;
    double sigma;
    bool contaminated;
    int fits_at_least, fits_at_most;
  };
  for (const Run& run : test::cases<Run>({Run{&random, 0.0045, true, 2, 5}, Run{&random, 0.0045, false, 1, 1},
                                          Run{&grid, 0.0045, false, 1, 1}, Run{&grid, 0.0015, false, 2, 2}})) {
    SCOPED_TRACE(::testing::Message() << run.panel->plan.size() << " points, sigma " << run.sigma
                                      << (run.contaminated ? ", 1 % moved" : ""));
    std::vector<Point3> points = run.panel->centres(run.sigma, 1);
    std::vector<char> moved(points.size(), 0);
    if (run.contaminated) moved = move_one_percent(points, run.panel->plan, 1);
    const compensation::CompensationResult r = compensation::compensate(run.panel->c.nominal, points, std::nullopt, run.panel->options);
    ASSERT_EQ(r.faces.size(), 1u);
    const AgainstTruth t = against_truth(r, run.panel->locator, moved);
    std::printf("%zu points, sigma %.1f um%s: %d fits; worst error %.2f um (%.2f u), %d good flagged, %d moved missed\n",
                points.size(), run.sigma * 1e3, run.contaminated ? ", 1 % moved" : "", r.faces[0].fits, t.worst * 1e3,
                t.worst_in_u, t.good_flagged, t.moved_missed);
    EXPECT_GE(r.faces[0].fits, run.fits_at_least);
    EXPECT_LE(r.faces[0].fits, run.fits_at_most);
    EXPECT_EQ(t.moved_missed, 0);
    EXPECT_EQ(t.good_flagged, 0);
    EXPECT_LE(t.worst_in_u, 5.0);
    EXPECT_LE(t.worst, 0.003 + 3.0 * run.sigma);
  }
}

// At low noise on a grid too coarse for the dent (60 × 30, σ = 0.5 µm), the fit cannot follow it and its residuals
// there are tens of micrometres, far beyond 5σ: judged against the face's noise alone at every fit, the dent's points
// were left out as outliers, the refits without them swung through the hole they left (a contact 1.06 mm from the
// true part, seed 1), and the next verdicts left out more. Against the spread around each point, they stay in: the
// largest error is the dent's own misfit, 45 µm, and within its stated u (0.98 u). The few still flagged stand out
// from their neighbours and are off by 7–16 µm; their u covers their residual, since which of the reading and the
// fit is right is not known (compensation/pipeline.cpp), and every point is within 5 u: 3.31, 3.43, 3.34 u (8.6–10.3
// u before, at the flagged points, whose u was the fit's alone: 1.4–1.7 µm).
TEST(Pipeline, UnfollowedShapeAtLowNoiseIsNotPeeledOff) {
  const PaperPanel panel(60, 30);
  for (const std::uint64_t seed : test::cases<std::uint64_t>({1u, 2u, 3u})) {
    SCOPED_TRACE(seed);
    const std::vector<Point3> points = panel.centres(0.0005, seed);
    const AgainstTruth t = against_truth(compensation::compensate(panel.c.nominal, points, std::nullopt, panel.options),
                                         panel.locator, std::vector<char>(points.size(), 0));
    std::printf("seed %d: worst error %.2f um (%.2f u); %d points flagged\n", static_cast<int>(seed), t.worst * 1e3,
                t.worst_in_u, t.good_flagged);
    EXPECT_LE(t.worst, 0.060);
    EXPECT_LE(t.good_flagged, 10);
    EXPECT_LE(t.worst_in_u, 5.0);
  }
}

// Without noise, the gross errors' first fit (the stiffest λ: it cannot follow the dent) pushes good points beside
// them out too, and the refits swing across the gap they leave: the positions they fit at its rim stay right, but
// their normals tilted 23° and 54° (120 × 60, seeds 1 and 2), and the contacts, offset along them, were 81 and 436 µm
// off with a u of 0.1 µm. Next to points left out, u now holds r(1 − cos θ) for the angle θ between the fit's normal
// and what the centres around the point show (compensation/normal_support.hpp), and a point the last fit did not use
// holds its residual (a prediction error). Measured: 1.93, 2.34, 2.51 u (60 × 30) and 1.28, 1.39, 0.99 u (120 × 60);
// 17.2 u, and 814 and 4 358 u, before. Since the first fit is made without the points that stand out alone from
// their neighbours by more than 0.05 mm (compensation/face_fits.cpp, kPeelFloor), on the 120 × 60 grid it pushes no
// good point out and nothing swings: 0.17–0.18 µm, no point flagged but the moved ones, no warning (before: 34, 23
// and 4 good points flagged, contacts 78–993 µm off). On the 60 × 30 grid, 2 mm apart, the dent's own points stand
// out from the local quadratic by more than that too: 9, 12 and 12 good points are left out (23, 10 and 13 before),
// contacts 106–175 µm off at 1.77–1.89 u where the normals are 8–11° off, and told.
TEST(Pipeline, NoiseFreeDataWithGrossOutliersStateEveryErrorWithinItsU) {
  for (const int nu : test::cases({60, 120})) {
    const PaperPanel panel(nu, nu / 2);
    for (const std::uint64_t seed : test::cases<std::uint64_t>({1u, 2u, 3u})) {
      SCOPED_TRACE(::testing::Message() << nu << " x " << nu / 2 << " seed " << seed);
      std::vector<Point3> points = panel.centres(0.0, seed);
      const std::vector<char> moved = move_one_percent(points, panel.plan, seed);
      const compensation::CompensationResult r = compensation::compensate(panel.c.nominal, points, std::nullopt, panel.options);
      const AgainstTruth t = against_truth(r, panel.locator, moved);
      // Where the gap's normal is tens of degrees off, the user is told so, not only by the rows' u.
      const auto said = std::find_if(r.warnings.begin(), r.warnings.end(), [](const std::string& w) {
        return w.find("the fitted normal is up to") != std::string::npos;
      });
      if (said != r.warnings.end()) std::printf("  %s\n", said->c_str());
      if (nu == 60) {
        EXPECT_NE(said, r.warnings.end());
        EXPECT_LE(t.good_flagged, 15);
      } else {
        EXPECT_EQ(t.good_flagged, 0);
        EXPECT_LE(t.worst, 0.001);
      }
      std::printf("%d x %d seed %d: worst error %.2f um (%.2f u); %d good points flagged, %d moved missed\n", nu,
                  nu / 2, static_cast<int>(seed), t.worst * 1e3, t.worst_in_u, t.good_flagged, t.moved_missed);
      EXPECT_EQ(t.moved_missed, 0);
      EXPECT_LE(t.worst_in_u, 5.0);
    }
  }
}

}  // namespace
}  // namespace probecomp
