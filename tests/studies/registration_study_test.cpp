// The paper's registration Monte Carlo: with no noise the proposed route is exact (the bar is 1e-5°
// and 1e-5 mm), and the conventional route carries its compensation error.

#include "probecomp/studies/registration_study.hpp"

#include <gtest/gtest.h>

namespace probecomp::studies {
namespace {

TEST(RegistrationStudy, CubeCornerWithoutNoiseTheProposedRouteIsExact) {
  const RegistrationStudyResult r = run_registration_study();
  EXPECT_EQ(r.points, 900);
  EXPECT_EQ(r.proposed.converged, 30);
  EXPECT_EQ(r.conventional.converged, 30);
  ASSERT_EQ(r.proposed.errors.size(), 30u);
  for (std::size_t c = 0; c < 6; ++c) {
    EXPECT_LE(r.proposed.stats.std[c], 1e-5) << kPoseComponents[c];
    EXPECT_LE(std::abs(r.proposed.stats.mean[c]), 1e-5) << kPoseComponents[c];
  }
  // Conventional compensation with unperturbed normals leaves r·(1 − cos θ) ≈ 0.1–0.5 µm along each plane's
  // normal: the translations are off by that, the rotations (planes) are not.
  for (std::size_t c = 3; c < 6; ++c) {
    EXPECT_GT(r.conventional.stats.std[c], 1e-5) << kPoseComponents[c];
    EXPECT_LT(r.conventional.stats.std[c], 1e-3) << kPoseComponents[c];
  }
}

TEST(RegistrationStudy, StatisticsAreTheSampleStandardDeviationMeanAndTInterval) {
  std::vector<PoseError> e;
  for (int k = 0; k < 10; ++k) e.push_back({double(k), 0, 0, 0, 0, 2.0});
  const ErrorStatistics s = error_statistics(e);
  EXPECT_DOUBLE_EQ(s.mean[0], 4.5);
  EXPECT_NEAR(s.std[0], 3.0276503540974917, 1e-15);  // sqrt(82.5 / 9)
  EXPECT_NEAR(s.ci95[0], 2.2621571628 * 3.0276503540974917 / std::sqrt(10.0), 2e-3);  // t(0.975, 9)
  EXPECT_EQ(s.std[5], 0.0);
}

}  // namespace
}  // namespace probecomp::studies
