// fit_control_points against exact answers: the points are sampled from a known surface (the truth), so the
// fitted surface is compared with the truth itself, at parameters other than the data's.

#include "probecomp/fitting/least_squares.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>

#include "support/test_surfaces.hpp"

namespace probecomp::fitting {
namespace {

using nurbs::Surface;

using testing::perturbed;

using Samples = testing::SurfaceSamples;

// n points at uniform random parameters with u in the first `u_fraction` of the domain, moved along the normal by
// Gaussian noise of standard deviation sigma.
Samples sample(const Surface& s, std::size_t n, double sigma, std::uint64_t seed, double u_fraction = 1.0) {
  return testing::sample_surface(s, n, sigma, seed, testing::Noise::AlongNormal, u_fraction);
}

// |fit − truth| on a 101 × 101 grid over u ≤ u_max (as a fraction of the domain).
testing::SurfaceDeviation deviation(const Surface& fit, const Surface& truth, double u_fraction = 1.0) {
  return testing::surface_deviation(fit, truth, 101, u_fraction);
}

TEST(FitControlPoints, RecoversANoiseFreeRationalSurfaceFromAPerturbedStart) {
  const Surface truth = testing::random_rational_surface(11, {.nu = 10, .nv = 9});
  const Surface start = perturbed(truth, 1.0, 5);
  const Samples data = sample(truth, 5000, 0.0, 3);
  const FitResult fit = fit_control_points(start, data.points, data.params);
  ASSERT_TRUE(fit.ok());
  const testing::SurfaceDeviation e = deviation(fit.surface, truth);
  EXPECT_LE(e.max, 1e-9) << "iterations " << fit.iterations;
  EXPECT_LE(fit.max_residual, 1e-9);
  EXPECT_EQ(fit.surface.num_u(), truth.num_u());
  for (int i = 0; i < truth.num_u(); ++i)
    for (int j = 0; j < truth.num_v(); ++j) EXPECT_EQ(fit.surface.weight(i, j), truth.weight(i, j));
}

TEST(FitControlPoints, FiveMicronNoiseOnTenThousandPointsGivesUnderOneMicronRmsFromTheTruth) {
  const Surface truth = testing::random_rational_surface(12, {.nu = 10, .nv = 10});  // 100 control points
  const Surface start = perturbed(truth, 0.5, 6);
  constexpr double sigma = 0.005;
  const Samples data = sample(truth, 10'000, sigma, 4);
  const FitResult fit = fit_control_points(start, data.points, data.params);
  ASSERT_TRUE(fit.ok());
  const testing::SurfaceDeviation e = deviation(fit.surface, truth);
  EXPECT_LE(e.rms, 0.001);
  // The residuals are the noise, less the part the 300 unknowns absorb.
  EXPECT_NEAR(fit.rms, sigma * std::sqrt(1.0 - 300.0 / 10'000.0), 0.1 * sigma);
}

TEST(FitControlPoints, DataOnHalfTheSurfaceFitThatHalfAndLeaveTheRestBounded) {
  const Surface truth = testing::random_rational_surface(13, {.nu = 10, .nv = 9});
  const Surface start = perturbed(truth, 0.3, 7);
  for (const double sigma : {0.0, 0.005}) {
    const Samples data = sample(truth, 5000, sigma, 8, 0.5);
    const FitResult fit = fit_control_points(start, data.points, data.params);
    ASSERT_TRUE(fit.ok());
    const testing::SurfaceDeviation covered = deviation(fit.surface, truth, 0.5);
    if (sigma == 0.0) {
      EXPECT_LE(covered.max, 1e-9);
    } else {
      EXPECT_LE(covered.rms, 0.001);
    }
    // Where there are no data the fit stays near the start: no control point runs away.
    for (int i = 0; i < truth.num_u(); ++i) {
      for (int j = 0; j < truth.num_v(); ++j) {
        EXPECT_LE((fit.surface.control_point(i, j) - start.control_point(i, j)).norm(), 2.0) << i << "," << j;
      }
    }
  }
}

TEST(FitControlPoints, PointWeightsLeaveOutliersOut) {
  const Surface truth = testing::random_rational_surface(14, {.nu = 8, .nv = 8});
  Samples data = sample(truth, 3000, 0.0, 9);
  std::vector<double> weights(data.points.size(), 1.0);
  for (std::size_t k = 0; k < data.points.size(); k += 100) {
    data.points[k].z() += 1.0;
    weights[k] = 0.0;
  }
  const FitResult fit = fit_control_points(perturbed(truth, 0.2, 1), data.points, data.params, weights);
  ASSERT_TRUE(fit.ok());
  EXPECT_LE(deviation(fit.surface, truth).max, 1e-9);
}

TEST(FitControlPoints, SameResultWithOneAndTwoThreads) {
  const Surface truth = testing::random_rational_surface(15, {.nu = 12, .nv = 12});
  const Samples data = sample(truth, 40'000, 0.005, 10);  // several assembly chunks
  const Surface start = perturbed(truth, 0.1, 2);
  auto run = [&](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    return fit_control_points(start, data.points, data.params);
  };
  const FitResult one = run(1);
  const FitResult two = run(2);
  ASSERT_TRUE(one.ok() && two.ok());
  EXPECT_EQ(one.surface.homogeneous(), two.surface.homogeneous());
  EXPECT_EQ(one.rms, two.rms);
}

TEST(FitControlPoints, BadInputIsNotDone) {
  const Surface s = testing::random_rational_surface(16);
  const Samples data = sample(s, 100, 0.0, 1);
  EXPECT_EQ(fit_control_points(s, {}, {}).status, FitResult::Status::NotDone);
  EXPECT_EQ(fit_control_points(s, data.points, std::span(data.params).first(50)).status, FitResult::Status::NotDone);
  Samples outside = data;
  outside.params[3].u = 1.5;
  EXPECT_EQ(fit_control_points(s, outside.points, outside.params).status, FitResult::Status::NotDone);
  Samples nan = data;
  nan.points[4].x() = std::nan("");
  EXPECT_EQ(fit_control_points(s, nan.points, nan.params).status, FitResult::Status::NotDone);
  const std::vector<double> negative(100, -1.0);
  EXPECT_EQ(fit_control_points(s, data.points, data.params, negative).status, FitResult::Status::NotDone);
}

}  // namespace
}  // namespace probecomp::fitting
