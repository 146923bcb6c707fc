// Gross outliers against their neighbours: spikes on a smooth, strongly curved residual field (a Gaussian dent
// three point spacings wide, plus noise) are all found, and hardly anything else, on a grid and on scattered
// points.

#include "probecomp/compensation/outliers.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using namespace probecomp;

void check(bool scattered) {
  std::mt19937_64 rng(scattered ? 2 : 1);
  std::normal_distribution<double> noise(0.0, 0.003);
  std::uniform_real_distribution<double> at(0.0, 40.0);
  std::vector<Point3> points;
  std::vector<double> residuals;
  std::vector<char> spike;
  for (int i = 0; i < 50; ++i) {
    for (int j = 0; j < 50; ++j) {
      const double x = scattered ? at(rng) : 0.8 * i, y = scattered ? at(rng) : 0.8 * j;
      // The field is the height of the points above the plane z = 0 and also their residual.
      const double dent = -0.5 * std::exp(-((x - 20) * (x - 20) + (y - 20) * (y - 20)) / (2.0 * 2.5 * 2.5));
      const bool is_spike = (i * 50 + j) % 97 == 0;
      const double r = dent + noise(rng) + (is_spike ? ((i + j) % 2 ? 0.3 : -0.4) : 0.0);
      points.emplace_back(x, y, r);
      residuals.push_back(r);
      spike.push_back(is_spike);
    }
  }
  const std::vector<Vector3> normals(points.size(), Vector3::UnitZ());
  const compensation::LocalOutliers found = compensation::local_outliers(points, residuals, normals);
  int missed = 0, wrong = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    missed += spike[k] && !found.outlier[k];
    wrong += !spike[k] && found.outlier[k];
  }
  EXPECT_EQ(missed, 0);
  // A good point is flagged only where an irregular neighbourhood cannot resolve the dent; the pipeline
  // re-checks every flagged point against the fit made without it (tests/compensation/pipeline_test.cpp).
  EXPECT_LE(wrong, static_cast<int>(points.size()) / 200);
  EXPECT_NEAR(found.scale, 0.003 * std::sqrt(1.0 + 6.0 / compensation::LocalOutlierOptions{}.neighbours), 0.0015)
      << "noise plus the prediction's own noise";
}

TEST(LocalOutliers, SpikesOnACurvedFieldOnAGrid) { check(false); }
TEST(LocalOutliers, SpikesOnACurvedFieldOnScatteredPoints) { check(true); }

TEST(LocalOutliers, TooFewPointsFlagNothing) {
  const std::vector<Point3> p(5, Point3::Zero());
  const std::vector<double> r{0, 0, 0, 0, 1};
  const std::vector<Vector3> n(5, Vector3::UnitZ());
  EXPECT_EQ(compensation::local_outliers(p, r, n).count, 0);
}

}  // namespace
