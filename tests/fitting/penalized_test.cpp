// fit_penalized against answers it does not compute itself: exact data from a known surface (the truth), the
// hat diagonal against the fit's own response to a nudged data point (finite differences, no selected
// inversion), and the noise the fit leaves against the noise put in.

#include "probecomp/fitting/penalized.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "support/test_surfaces.hpp"

namespace probecomp::fitting {
namespace {

using nurbs::Surface;

using testing::perturbed;

using Samples = testing::SurfaceSamples;

// n points at uniform random parameters, moved by Gaussian noise of standard deviation sigma in each coordinate.
Samples sample(const Surface& s, std::size_t n, double sigma, std::uint64_t seed) {
  return testing::sample_surface(s, n, sigma, seed, testing::Noise::Isotropic);
}

// Largest |a − b| on a 61 × 61 grid over b's domain.
double worst_gap(const Surface& a, const Surface& b) { return testing::surface_deviation(a, b, 61).max; }

TEST(FitPenalized, ExactDataFromASurfaceWithTheSameKnotsAreFollowedToASmallFractionOfAMicrometre) {
  const Surface truth = testing::random_rational_surface(3, {.nu = 8, .nv = 7});
  const Surface start = perturbed(truth, 0.5, 4);
  const Samples data = sample(truth, 3000, 0.0, 5);
  const PenalizedFitResult fit = fit_penalized(start, data.points, data.params);
  ASSERT_TRUE(fit.ok());
  // Cross-validation on exact data wants almost no smoothing.
  EXPECT_LE(fit.log10_smoothing, -5.0);
  EXPECT_LE(worst_gap(fit.surface, truth), 1e-4);
}

TEST(FitPenalized, TheHatDiagonalIsTheFitsResponseToItsOwnDataPoint) {
  const Surface truth = testing::random_rational_surface(7, {.nu = 7, .nv = 6});
  Samples data = sample(truth, 400, 0.01, 8);
  PenalizedFitOptions o;
  o.log10_smoothing = -3.0;  // one fixed λ: the fit is then linear in the data
  const PenalizedFitResult base = fit_penalized(truth, data.points, data.params, {}, o);
  ASSERT_TRUE(base.ok());
  double trace = 0.0;
  for (std::size_t k : {0u, 17u, 123u, 399u}) {
    Samples nudged = data;
    constexpr double kNudge = 1e-3;
    nudged.points[k].x() += kNudge;
    const PenalizedFitResult moved_fit = fit_penalized(truth, nudged.points, nudged.params, {}, o);
    const double response = (nurbs::evaluate(moved_fit.surface, data.params[k].u, data.params[k].v) -
                             nurbs::evaluate(base.surface, data.params[k].u, data.params[k].v)).x() / kNudge;
    EXPECT_NEAR(base.variance_factor[k], response, 1e-6 + 1e-6 * response) << k;
  }
  for (double v : base.variance_factor) trace += v;
  // Σ h_k is tr H, which the fit reports from the band of the inverse.
  EXPECT_NEAR(trace, base.effective_dof, 1e-6 * base.effective_dof);
  EXPECT_GT(base.effective_dof, 0.0);
  EXPECT_LT(base.effective_dof, truth.num_u() * truth.num_v());
}

TEST(FitPenalized, TheResidualsLeaveTheNoisePutIn) {
  const Surface truth = testing::random_rational_surface(9, {.nu = 9, .nv = 9});
  constexpr double sigma = 0.004;
  const Samples data = sample(truth, 5000, sigma, 10);
  const PenalizedFitResult fit = fit_penalized(truth, data.points, data.params);
  ASSERT_TRUE(fit.ok());
  // Wahba's estimate: RSS / (n − tr H) per coordinate.
  const double estimate = std::sqrt(fit.rss / (3.0 * (fit.points_used - fit.effective_dof)));
  EXPECT_NEAR(estimate, sigma, 0.05 * sigma);
  // And the fit is closer to the truth than the points are.
  EXPECT_LT(worst_gap(fit.surface, truth), 2.0 * sigma);
}

TEST(FitPenalized, BadInputIsNotDone) {
  const Surface s = testing::random_rational_surface(1, {.nu = 5, .nv = 5});
  EXPECT_EQ(fit_penalized(s, {}, {}).status, PenalizedFitResult::Status::NotDone);
  Samples data = sample(s, 50, 0.0, 2);
  data.params[3].u = 2.0;  // outside the domain
  EXPECT_EQ(fit_penalized(s, data.points, data.params).status, PenalizedFitResult::Status::NotDone);
}

}  // namespace
}  // namespace probecomp::fitting
