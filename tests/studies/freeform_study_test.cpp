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
void expect_covers(const Coverage& c, const std::string& what) {
  EXPECT_GE(c.overall(), 0.90) << what;
  EXPECT_LE(c.overall(), 0.99) << what;
  for (int g = 0; g < 16; ++g) {
    EXPECT_GE(c.region(g), 0.90) << what << ", region " << g / 4 << "," << g % 4;
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
TEST(FreeformStudy, UncertaintyCoversTheTrueErrorOnThePanelAndInEachRegion_RandomPointsLowNoise) {
  Coverage c;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    studies::FreeformStudyOptions o;
    o.seed = seed;
    o.random_points = 3000;
    o.shuffle = true;
    o.approach_normals = false;
    o.noise_sigma = 0.0015;
    add_run(studies::run_freeform_study(o), c);
  }
  expect_covers(c, "3 000 random points, sigma 1.5 um");
}

TEST(FreeformStudy, UncertaintyCoversTheTrueErrorOnThePanelAndInEachRegion_SteepDentLowNoise) {
  Coverage c;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    studies::FreeformStudyOptions o;
    o.seed = seed;
    o.steep_dent = true;
    o.noise_sigma = 0.0015;
    add_run(studies::run_freeform_study(o), c);
  }
  expect_covers(c, "steep dent, sigma 1.5 um");
}

}  // namespace
