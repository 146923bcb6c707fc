// The free-form study (the paper's §7.3 case and its variants) against issue 19's bars on the per-point
// uncertainty: the true error of each compensated point (its distance from the actual surface the simulator made,
// found by the CAD layer's closest points on that surface, not by the fit: studies::compare_methods) within ±2u
// for about 95 % of the points, over the whole panel and within each of a 4 × 4 grid of regions over it: a
// constant u, or one that misses the smoothing bias of a broad bulge, fails the regions.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include "probecomp/studies/freeform_study.hpp"
#include "support/light.hpp"

namespace {

using namespace probecomp;

struct Coverage {
  int inside = 0, counted = 0;
  std::array<int, 16> region_inside{}, region_counted{};
  [[nodiscard]] double overall() const { return static_cast<double>(inside) / std::max(counted, 1); }
  [[nodiscard]] double region(int g) const {
    return static_cast<double>(region_inside[static_cast<std::size_t>(g)]) /
           std::max(region_counted[static_cast<std::size_t>(g)], 1);
  }
};

// Adds one run's region counts (the study's: ok rows with |error| ≤ 2u by region of the panel, the error found
// on the actual surface the simulator made).
void add_run(const studies::FreeformStudyResult& r, Coverage& c) {
  for (std::size_t g = 0; g < 16; ++g) {
    c.inside += r.region_covered[g];
    c.counted += r.region_ok[g];
    c.region_inside[g] += r.region_covered[g];
    c.region_counted[g] += r.region_ok[g];
  }
}

// The bar is 85 % in every region of one run; pooled over seeds the region's coverage estimates its
// probability, which should be near the 95 % of ±2u: 90 % is asked. (Without the penalty's bias estimate in u,
// the worst pooled region read about 85 % on the steep dent and on the random points; with it, 94.7 and 94.1 %.)
// The sanitizer build runs one seed (support/light.hpp), held to the one run's bar.
void expect_covers(const Coverage& c, const std::string& what) {
  const double region_bar = test::kLight ? 0.85 : 0.90;
  EXPECT_GE(c.overall(), 0.90) << what;
  EXPECT_LE(c.overall(), 0.99) << what;
  for (int g = 0; g < 16; ++g) {
    EXPECT_GE(c.region(g), region_bar) << what << ", region " << g / 4 << "," << g % 4;
  }
  std::printf("%s: coverage of ±2u %.1f %%, worst region %.1f %%\n", what.c_str(), 100.0 * c.overall(),
              100.0 * [&] {
                double w = 1.0;
                for (int g = 0; g < 16; ++g) w = std::min(w, c.region(g));
                return w;
              }());
}

// Regions pooled over three noise seeds: the coverage u claims is a probability over the noise, which one run's
// few hundred points per region, sharing one fit's bias, estimate only roughly. (Measured over five seeds, the worst
// single run's worst region: 91 % on the grid, 87 % on 3 000 random points; bench/fit_cases.) The paper's own case
// (grid, σ = 4.5 µm) is held to the bars by the CLI test of `study freeform --noise` (tests/cli/studies.sh);
// the cases here are those where u without the penalty's bias estimate falls short.
// The variant `o` run with noise seeds 1–3, its regions pooled.
Coverage over_three_seeds(studies::FreeformStudyOptions o) {
  Coverage c;
  for (const std::uint64_t seed : test::cases<std::uint64_t>({1, 2, 3})) {
    o.seed = seed;
    add_run(studies::run_freeform_study(o), c);
  }
  return c;
}

TEST(FreeformStudy, UncertaintyCoversTheTrueErrorOnThePanelAndInEachRegion_RandomPointsLowNoise) {
  studies::FreeformStudyOptions o = studies::scattered_points(3000);
  o.noise_sigma = 0.0015;
  expect_covers(over_three_seeds(o), "3 000 random points, sigma 1.5 um");
}

TEST(FreeformStudy, UncertaintyCoversTheTrueErrorOnThePanelAndInEachRegion_SteepDentLowNoise) {
  studies::FreeformStudyOptions o;
  o.steep_dent = true;
  o.noise_sigma = 0.0015;
  expect_covers(over_three_seeds(o), "steep dent, sigma 1.5 um");
}

// Issue 20: 10 % of the paper's grid recorded twice as the same reading (a scanner's repeated sample). Counted twice,
// each copy was the other's nearest neighbour: the noise estimate read 3.4 µm instead of 4.5 in two seeds of three,
// the fit grew from 782 to 1 595 control points, the std of the errors rose from 0.88 to 1.14 µm and up to 3 rows
// were flagged (bench/fit_cases with REPEATS=0.1, 3 seeds). Each position is now fitted once.
TEST(FreeformStudy, AReadingRecordedTwiceIsFittedOnceAndBothRowsComeBackTheSame) {
  for (const std::uint64_t seed : test::cases<std::uint64_t>({1, 2})) {
    studies::FreeformStudyOptions o;
    o.seed = seed;
    o.repeated_fraction = 0.1;
    const studies::FreeformStudyResult r = studies::run_freeform_study(o);
    int repeats = 0;
    for (std::size_t k = 1; k < r.touches.size(); ++k) {
      if (r.touches[k].measured != r.touches[k - 1].measured) continue;
      ++repeats;
      const compensation::CompensatedPoint &a = r.cad.points[k - 1], &b = r.cad.points[k];
      EXPECT_EQ(a.status, b.status);
      EXPECT_EQ(a.contact, b.contact) << "row " << k;
      EXPECT_EQ(a.uncertainty, b.uncertainty) << "row " << k;
    }
    ASSERT_GT(repeats, 600);  // about 720 of 7 200
    const compensation::FaceReport& face = r.cad.faces.at(0);
    EXPECT_EQ(face.repeated, repeats);
    EXPECT_EQ(face.points, 7200 + repeats);
    EXPECT_NEAR(face.noise_sigma, 0.0045, 0.1 * 0.0045) << "seed " << seed;
    EXPECT_LE(face.control_points, 1000) << "seed " << seed;  // 782 without repeats
    EXPECT_LE(r.cad_summary.std, 0.001) << "seed " << seed;   // 0.88 µm without repeats
    EXPECT_EQ(r.flagged, 0) << "seed " << seed;
    ASSERT_EQ(r.cad.warnings.size(), 1u);
    EXPECT_NE(r.cad.warnings[0].find(std::to_string(repeats) + " points repeat"), std::string::npos) << r.cad.warnings[0];
  }
}

// A point measured again (a second touch with its own noise) is a new observation: not merged, and the noise
// estimate is unbiased by it.
TEST(FreeformStudy, APointMeasuredAgainIsANewObservation) {
  studies::FreeformStudyOptions o;
  o.repeated_fraction = 0.1;
  o.exact_repeats = false;
  const studies::FreeformStudyResult r = studies::run_freeform_study(o);
  const compensation::FaceReport& face = r.cad.faces.at(0);
  EXPECT_EQ(face.repeated, 0);
  EXPECT_GT(face.points, 7800);
  EXPECT_NEAR(face.noise_sigma, 0.0045, 0.1 * 0.0045);
  EXPECT_LE(r.cad_summary.std, 0.001);
  EXPECT_EQ(r.flagged, 0);
  EXPECT_TRUE(r.cad.warnings.empty());
}

}  // namespace
