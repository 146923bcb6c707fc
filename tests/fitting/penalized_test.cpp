// fit_penalized against answers it does not compute itself: exact data from a known surface (the truth), the
// hat diagonal against the fit's own response to a nudged data point (finite differences, no selected
// inversion), and the noise the fit leaves against the noise put in.

#include "probecomp/fitting/penalized.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "probecomp/fitting/noise_estimate.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::fitting {
namespace {

using nurbs::Surface;

using testing::perturbed;

using Samples = testing::SurfaceSamples;

// n points at uniform random parameters, moved by Gaussian noise of standard deviation sigma in each coordinate.
Samples isotropic_sample(const Surface& s, std::size_t n, double sigma, std::uint64_t seed) {
  return testing::sample_surface(s, n, sigma, seed, testing::Noise::Isotropic);
}

// Largest |a − b| on a 61 × 61 grid over b's domain.
double worst_gap(const Surface& a, const Surface& b) { return testing::surface_deviation(a, b, 61).max; }

TEST(FitPenalized, ExactDataFromASurfaceWithTheSameKnotsAreFollowedToASmallFractionOfAMicrometre) {
  const Surface truth = testing::random_rational_surface(3, {.nu = 8, .nv = 7});
  const Surface start = perturbed(truth, 0.5, 4);
  const Samples data = isotropic_sample(truth, 3000, 0.0, 5);
  const PenalizedFitResult fit = fit_penalized(start, data.points, data.params);
  ASSERT_TRUE(fit.ok());
  // Cross-validation on exact data wants almost no smoothing.
  EXPECT_LE(fit.log10_smoothing, -5.0);
  EXPECT_LE(worst_gap(fit.surface, truth), 1e-4);
}

TEST(FitPenalized, TheHatDiagonalIsTheFitsResponseToItsOwnDataPoint) {
  const Surface truth = testing::random_rational_surface(7, {.nu = 7, .nv = 6});
  Samples data = isotropic_sample(truth, 400, 0.01, 8);
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

// The smoothing bias the fit reports against the true one. On exact data from a surface in the fit's own space,
// the fit with a fixed λ has no variance and no approximation error: its whole error f̂ − f at each point is
// the penalty's bias, which the fit estimates from its own shrunk shape (a plug-in estimate, corrected by terms
// of the shrinkage's inverse; fit_penalized). Each λ shrinks the displacement differently: from a few per cent to
// most of it.
TEST(FitPenalized, TheSmoothingBiasItReportsIsTheErrorOfAFitToExactData) {
  const Surface truth = testing::random_rational_surface(11, {.nu = 8, .nv = 8});
  const Surface start = perturbed(truth, 0.5, 12);
  const Samples data = isotropic_sample(truth, 3000, 0.0, 13);
  // (Two passes of the estimate missed 20, 21 and 44 % at the last three, four passes 8, 12 and 29 %.)
  for (const auto& [log10_smoothing, bound] : {std::pair{-4.0, 0.05}, std::pair{-3.0, 0.05}, std::pair{-2.0, 0.15},
                                              std::pair{-1.0, 0.25}}) {
    SCOPED_TRACE(log10_smoothing);
    PenalizedFitOptions o;
    o.log10_smoothing = log10_smoothing;
    const PenalizedFitResult fit = fit_penalized(start, data.points, data.params, {}, o);
    ASSERT_TRUE(fit.ok());
    double true_squared = 0.0, miss_squared = 0.0, start_squared = 0.0;
    for (std::size_t k = 0; k < data.points.size(); ++k) {
      const Vector3 bias = nurbs::evaluate(fit.surface, data.params[k].u, data.params[k].v) - data.points[k];
      true_squared += bias.squaredNorm();
      miss_squared += (fit.smoothing_bias[k] - bias).squaredNorm();
      start_squared += (nurbs::evaluate(start, data.params[k].u, data.params[k].v) - data.points[k]).squaredNorm();
    }
    const double rms = std::sqrt(true_squared / data.points.size());
    const double miss = std::sqrt(miss_squared / data.points.size());
    std::printf("log10 lambda %+.0f: bias rms %.4f mm (%.0f %% of the start's distance), estimate off by %.0f %% of it\n",
                log10_smoothing, rms, 100.0 * std::sqrt(true_squared / start_squared), 100.0 * miss / rms);
    EXPECT_LT(miss, bound * rms);
  }
}

// null_statistics against closed forms. At a fixed λ the fit's residuals of pure noise of variance 1/w_k are
// (I − H)ε, H the weighted hat matrix, so Σ w_k r_k² has expectation n − 2 tr H + tr H², between n − 2 tr H and
// n − tr H (H's eigenvalues lie in [0, 1]). The draws repeat on a second call.
TEST(FitPenalized, ItsResidualsOfPureNoiseAreThoseOfItsHatMatrix) {
  const Surface truth = testing::random_rational_surface(7, {.nu = 7, .nv = 6});
  const Samples data = isotropic_sample(truth, 2000, 0.01, 8);
  std::vector<double> weights(data.points.size());
  for (std::size_t k = 0; k < weights.size(); ++k) weights[k] = k % 3 == 0 ? 4.0 : 1.0;
  PenalizedFitOptions o;
  o.log10_smoothing = -3.0;
  const PenalizedFitResult fit = fit_penalized(truth, data.points, data.params, weights, o);
  ASSERT_TRUE(fit.ok());
  auto weighted_squares = [&](std::span<const double> r) {
    double sum = 0.0;
    for (std::size_t k = 0; k < r.size(); ++k) sum += weights[k] * r[k] * r[k];
    return sum;
  };
  constexpr int kDraws = 60;
  const std::vector<double> draws = null_statistics(fit, kDraws, weighted_squares);
  ASSERT_EQ(draws.size(), static_cast<std::size_t>(kDraws));
  double mean = 0.0, squares = 0.0;
  for (double x : draws) mean += x / kDraws;
  for (double x : draws) squares += (x - mean) * (x - mean);
  const double standard_error = std::sqrt(squares / (kDraws - 1) / kDraws);
  const double n = static_cast<double>(data.points.size()), h = fit.effective_dof;
  std::printf("tr H %.1f: mean %.1f (standard error %.1f) within [%.1f, %.1f]\n", h, mean, standard_error, n - 2 * h, n - h);
  EXPECT_GT(h, 10.0);
  EXPECT_GT(mean, n - 2.0 * h - 4.0 * standard_error);
  EXPECT_LT(mean, n - h + 4.0 * standard_error);
  EXPECT_EQ(null_statistics(fit, kDraws, weighted_squares), draws);
}

// What the null draws are for: on data of pure noise about a surface in the fit's space, the correlation of the
// fit's residuals with their neighbours' is below 0 (they repel), by what the draws of pure noise through the same
// fit show, not by chance.
TEST(FitPenalized, ItsResidualsOfPureNoiseRepelAsTheNullDrawsSay) {
  const Surface truth = testing::random_rational_surface(9, {.nu = 9, .nv = 9});
  const LocalPredictionNoise local = [&] {
    const Samples exact = isotropic_sample(truth, 4000, 0.0, 21);
    return LocalPredictionNoise(exact.points, {});
  }();
  double observed_sum = 0.0, null_sum = 0.0;
  constexpr int kDataSets = 4;
  for (int d = 0; d < kDataSets; ++d) {
    // The same parameters (seed 21), noise drawn afresh.
    Samples data = isotropic_sample(truth, 4000, 0.0, 21);
    std::mt19937_64 rng(100 + d);
    std::normal_distribution<double> noise(0.0, 0.004);
    for (Point3& x : data.points) x += Vector3(noise(rng), noise(rng), noise(rng));
    PenalizedFitOptions o;
    o.log10_smoothing = -2.0;
    const PenalizedFitResult fit = fit_penalized(truth, data.points, data.params, {}, o);
    ASSERT_TRUE(fit.ok());
    std::vector<double> r(data.points.size());
    for (std::size_t k = 0; k < r.size(); ++k) {
      r[k] = (data.points[k] - nurbs::evaluate(fit.surface, data.params[k].u, data.params[k].v)).z();
    }
    observed_sum += local.neighbour_correlation(r);
    const std::vector<double> draws =
        null_statistics(fit, 12, [&](std::span<const double> x) { return local.neighbour_correlation(x); });
    for (double x : draws) null_sum += x / 12.0;
  }
  const double observed = observed_sum / kDataSets, expected = null_sum / kDataSets;
  // One data set's correlation has a standard error of about 1/√(12·4000) = 0.0046; four of them, 0.0023.
  std::printf("neighbour correlation: observed %.4f, null draws %.4f\n", observed, expected);
  EXPECT_LT(expected, -0.005);
  EXPECT_NEAR(observed, expected, 0.008);
}

TEST(FitPenalized, TheResidualsLeaveTheNoisePutIn) {
  const Surface truth = testing::random_rational_surface(9, {.nu = 9, .nv = 9});
  constexpr double sigma = 0.004;
  const Samples data = isotropic_sample(truth, 5000, sigma, 10);
  const PenalizedFitResult fit = fit_penalized(truth, data.points, data.params);
  ASSERT_TRUE(fit.ok());
  // Wahba's estimate: RSS / (n − tr H) per coordinate.
  const double estimate = std::sqrt(fit.rss / (3.0 * (fit.points_used - fit.effective_dof)));
  EXPECT_NEAR(estimate, sigma, 0.05 * sigma);
  // And the fit is closer to the truth than the points are.
  EXPECT_LT(worst_gap(fit.surface, truth), 2.0 * sigma);
}

// A flat 60 × 40 mm plate on a fine cubic net (an exact plane: control points at the Greville abscissae).
Surface flat_plate(int spans_u, int spans_v) {
  const nurbs::KnotVector U = nurbs::KnotVector::uniform(3, spans_u), V = nurbs::KnotVector::uniform(3, spans_v);
  auto greville = [](const nurbs::KnotVector& K, int i) { return (K[i + 1] + K[i + 2] + K[i + 3]) / 3.0; };
  const int nu = spans_u + 3, nv = spans_v + 3;
  std::vector<Point3> P;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) P.emplace_back(60.0 * greville(U, i), 40.0 * greville(V, j), 0.0);
  }
  return Surface(U, V, P);
}

// n points at uniform random parameters of the 60 × 40 mm plate, at height(x, y) plus Gaussian noise of standard
// deviation sigma; rng drawn u, v, then the noise, point by point.
template <class Height>
void sample_plate(std::mt19937_64& rng, int n, double sigma, Height height, std::vector<Point3>& points,
                  std::vector<SurfaceParameter>& params) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, sigma);
  for (int k = 0; k < n; ++k) {
    const double u = unit(rng), v = unit(rng), x = 60.0 * u, y = 40.0 * v;
    points.emplace_back(x, y, height(x, y) + noise(rng));
    params.push_back({u, v});
  }
}

// The fit's rms height error against the closed form height(x, y), on a 41 × 41 grid of parameters.
template <class Height>
double rms_height_error(const Surface& fit, Height height) {
  double sum = 0.0;
  for (int a = 0; a <= 40; ++a) {
    for (int c = 0; c <= 40; ++c) {
      const Point3 x = nurbs::evaluate(fit, a / 40.0, c / 40.0);
      const double e = x.z() - height(x.x(), x.y());
      sum += e * e;
    }
  }
  return std::sqrt(sum / (41.0 * 41.0));
}

// A wave whose crests run across the plate (it varies along one direction only), measured through noise: the
// anisotropy chosen by cross-validation makes bending along the wave cheap and along its crests dear, so the fit
// follows the wave with less noise in it than the isotropic energy's. Both judged against the closed form.
TEST(FitPenalized, AWaveAlongOneDirectionIsFollowedBetterWithTheAnisotropyCrossValidationChooses) {
  const Surface start = flat_plate(24, 16);
  constexpr double A = 0.05, L = 12.0, sigma = 0.003;
  for (const bool along_u : {true, false}) {
    // z = A sin(2π·c/L), c the plate's x (along u) or y (along v).
    auto wave = [&](double x, double y) { return A * std::sin(2.0 * std::numbers::pi * (along_u ? x : y) / L); };
    std::mt19937_64 rng(along_u ? 21 : 22);
    std::vector<Point3> points;
    std::vector<SurfaceParameter> params;
    sample_plate(rng, 3000, sigma, wave, points, params);
    PenalizedFitOptions isotropic;
    isotropic.anisotropic = false;
    const PenalizedFitResult plain = fit_penalized(start, points, params, {}, isotropic);
    const PenalizedFitResult fit = fit_penalized(start, points, params);
    ASSERT_TRUE(plain.ok() && fit.ok());
    EXPECT_EQ(plain.log10_anisotropy, 0.0);
    // θ weighs bending along u (s): below 1 when the wave runs along u, above when along v.
    if (along_u) {
      EXPECT_LT(fit.log10_anisotropy, -0.2);
    } else {
      EXPECT_GT(fit.log10_anisotropy, 0.2);
    }
    EXPECT_LE(fit.cv_score, plain.cv_score);
    const double e_plain = rms_height_error(plain.surface, wave);
    const double e_fit = rms_height_error(fit.surface, wave);
    std::printf("wave along %s: log10 theta %.2f, rms error %.3f um (isotropic %.3f um)\n", along_u ? "u" : "v",
                fit.log10_anisotropy, 1e3 * e_fit, 1e3 * e_plain);
    // Measured: 1.31 against 1.46 um along u (log10 θ = −0.33), 1.27 against 1.46 um along v (0.56).
    EXPECT_LT(e_fit, 0.93 * e_plain);
    EXPECT_LT(e_fit, 0.5 * sigma);
  }
}

// A round bump has no direction: wherever the score cannot tell θ apart (on 3 × 3 spans it hardly depends on it)
// or tells it only by the noise, θ stays near 1 rather than where a search happened to stop (golden sections on
// such a flat score ended at 10^-1.91 on shape suite D400). Judged against the closed form: the fit is as good as
// the isotropic energy's.
TEST(FitPenalized, ARoundBumpKeepsTheAnisotropyNearOne) {
  for (const int controls : {3, 12}) {
    const Surface start = flat_plate(controls, controls);
    auto bump = [](double x, double y) { return 0.02 * std::exp(-((x - 30.0) * (x - 30.0) + (y - 20.0) * (y - 20.0)) / 200.0); };
    std::mt19937_64 rng(31 + controls);
    std::vector<Point3> points;
    std::vector<SurfaceParameter> params;
    sample_plate(rng, 2000, 0.003, bump, points, params);
    PenalizedFitOptions isotropic;
    isotropic.anisotropic = false;
    const PenalizedFitResult plain = fit_penalized(start, points, params, {}, isotropic);
    const PenalizedFitResult fit = fit_penalized(start, points, params);
    ASSERT_TRUE(plain.ok() && fit.ok());
    const double e_fit = rms_height_error(fit.surface, bump), e_plain = rms_height_error(plain.surface, bump);
    std::printf("%d x %d spans: log10 theta %+.3f, rms error %.3f um (isotropic %.3f um)\n", controls,
                controls, fit.log10_anisotropy, 1e3 * e_fit, 1e3 * e_plain);
    EXPECT_LE(std::abs(fit.log10_anisotropy), 0.5);
    EXPECT_LE(e_fit, 1.05 * e_plain + 1e-5);
  }
}

// θ is chosen on a fixed grid and at the vertex of a parabola through the grid's best three, so a slight change
// of the data (here 0.02 µm of noise added, a hundred-and-fiftieth of the data's) moves it and the fit slightly:
// chosen again on each net of an adaptive fit, a choice that jumps turned the registration made again without a
// few gross errors into a different path of fits (Pipeline.GrossOutliersMoveNoOtherPoint).
TEST(FitPenalized, TheAnisotropyMovesLittleWithALittleChangeOfTheData) {
  const Surface start = flat_plate(24, 16);
  std::mt19937_64 rng(41);
  std::vector<Point3> points;
  std::vector<SurfaceParameter> params;
  sample_plate(rng, 3000, 0.003, [](double x, double) { return 0.05 * std::sin(2.0 * std::numbers::pi * x / 12.0); },
               points, params);
  const PenalizedFitResult fit = fit_penalized(start, points, params);
  ASSERT_TRUE(fit.ok());
  std::normal_distribution<double> nudge(0.0, 2e-5);
  for (int draw = 0; draw < 3; ++draw) {
    std::vector<Point3> nudged = points;
    for (Point3& p : nudged) p.z() += nudge(rng);
    const PenalizedFitResult again = fit_penalized(start, nudged, params);
    ASSERT_TRUE(again.ok());
    const double gap = worst_gap(again.surface, fit.surface);
    std::printf("draw %d: log10 theta %+.4f against %+.4f, surfaces %.4f um apart at most\n", draw,
                again.log10_anisotropy, fit.log10_anisotropy, 1e3 * gap);
    EXPECT_LT(fit.log10_anisotropy, -0.2);  // the wave runs along u
    EXPECT_NEAR(again.log10_anisotropy, fit.log10_anisotropy, 0.05);
    EXPECT_LT(gap, 5e-5);
  }
}

// PenalizedFitOptions::lambda, an absolute λ, is the same fit as the relative λ cross-validation chose on the same
// net, and on a net with every span halved keeps that λ (the relative one moves with the net's traces).
TEST(FitPenalized, AFixedAbsoluteLambdaIsTheFitOfThatLambda) {
  const Surface truth = testing::random_rational_surface(11, {.nu = 7, .nv = 6});
  const Samples data = isotropic_sample(truth, 2000, 0.004, 12);
  PenalizedFitOptions chosen;
  chosen.anisotropic = false;
  const PenalizedFitResult by_cv = fit_penalized(truth, data.points, data.params, {}, chosen);
  ASSERT_TRUE(by_cv.ok());
  PenalizedFitOptions fixed = chosen;
  fixed.lambda = by_cv.lambda;
  const PenalizedFitResult again = fit_penalized(truth, data.points, data.params, {}, fixed);
  ASSERT_TRUE(again.ok());
  EXPECT_NEAR(again.lambda, by_cv.lambda, 1e-12 * by_cv.lambda);
  EXPECT_NEAR(again.log10_smoothing, by_cv.log10_smoothing, 1e-12);
  EXPECT_LE(worst_gap(again.surface, by_cv.surface), 1e-10);
  auto midpoints = [](const std::vector<double>& b) {
    std::vector<double> m;
    for (std::size_t i = 0; i + 1 < b.size(); ++i) m.push_back(0.5 * (b[i] + b[i + 1]));
    return m;
  };
  const Surface finer = nurbs::refine_knots_v(nurbs::refine_knots_u(truth, midpoints(truth.U().breakpoints())),
                                              midpoints(truth.V().breakpoints()));
  const PenalizedFitResult on_finer = fit_penalized(finer, data.points, data.params, {}, fixed);
  ASSERT_TRUE(on_finer.ok());
  EXPECT_NEAR(on_finer.lambda, by_cv.lambda, 1e-12 * by_cv.lambda);
  EXPECT_GT(std::abs(on_finer.log10_smoothing - by_cv.log10_smoothing), 0.1);
}

TEST(FitPenalized, BadInputIsNotDone) {
  const Surface s = testing::random_rational_surface(1, {.nu = 5, .nv = 5});
  EXPECT_EQ(fit_penalized(s, {}, {}).status, PenalizedFitResult::Status::NotDone);
  Samples data = isotropic_sample(s, 50, 0.0, 2);
  data.params[3].u = 2.0;  // outside the domain
  EXPECT_EQ(fit_penalized(s, data.points, data.params).status, PenalizedFitResult::Status::NotDone);
}

}  // namespace
}  // namespace probecomp::fitting
