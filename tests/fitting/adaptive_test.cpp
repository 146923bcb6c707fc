// fit_surface (refinement, parameter correction, noise estimate) against a known truth that the nominal knots
// cannot follow: a free-form patch with a small dent.

#include "probecomp/fitting/adaptive.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "probecomp/nurbs/closest_point.hpp"
#include "probecomp/nurbs/constructors.hpp"
#include "support/light.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::fitting {
namespace {

using nurbs::Surface;

// A 100 × 100 mm rational bicubic patch, 8 × 8 control points on uniform knots, heights from two gentle waves
// (curvature radius above 50 mm), weights 0.9–1.1.
Surface nominal_patch() {
  std::vector<Point3> P;
  std::vector<double> w;
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j) {
      const double x = 100.0 * i / 7, y = 100.0 * j / 7;
      P.emplace_back(x, y, 4.0 * std::sin(x / 25.0) + 3.0 * std::cos(y / 30.0 + 0.4));
      w.push_back(1.0 + 0.1 * std::sin(1.3 * i + 0.7 * j));
    }
  }
  return Surface(nurbs::KnotVector::uniform(3, 5), nurbs::KnotVector::uniform(3, 5), P, w);
}

// The truth: the nominal pushed in along its normal by a dent 3 mm wide and `depth` deep (cos² profile, slopes
// up to about 17° for 0.3 mm) about S(0.43, 0.57).
struct DentedPart {
  Surface nominal = nominal_patch();
  Point3 centre = nurbs::evaluate(nominal, 0.43, 0.57);
  double depth = 0.3, half_width = 1.5;

  [[nodiscard]] Point3 at(double u, double v) const {
    const Point3 S = nurbs::evaluate(nominal, u, v);
    const double r = (S - centre).norm();
    const double c = r < half_width ? std::cos(0.5 * std::numbers::pi * r / half_width) : 0.0;
    return S - depth * c * c * nurbs::unit_normal(nominal, u, v).n;
  }
};

struct Data {
  std::vector<Point3> points;
  std::vector<SurfaceParameter> params;
};

// An n × n grid of parameters (a scan), the truth there plus Gaussian noise along the nominal normal; the
// parameters are the nominal foot points, as registration gives them.
Data scan(const DentedPart& part, int n, double sigma, std::uint64_t seed, double u_max = 1.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  Data d;
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const double u = u_max * a / (n - 1), v = static_cast<double>(b) / (n - 1);
      d.points.push_back(part.at(u, v) + noise(rng) * nurbs::unit_normal(part.nominal, u, v).n);
      d.params.push_back({u, v});
    }
  }
  return d;
}

// An n × n grid of parameters at the cells' centres, truth(u, v) there plus Gaussian noise along the nominal's
// normal; the parameters are the nominal foot points.
template <typename Truth>
Data grid_at_cell_centres(const Surface& nominal, const Truth& truth, int n, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  Data d;
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const double u = (a + 0.5) / n, v = (b + 0.5) / n;
      d.points.push_back(truth(u, v) + noise(rng) * nurbs::unit_normal(nominal, u, v).n);
      d.params.push_back({u, v});
    }
  }
  return d;
}

// Each point's distance from the truth at its parameters to the fit, found from the fit's own foot point.
template <typename Truth>
std::vector<double> distances_to_truth(const AdaptiveFitResult& fit, const Data& data, const Truth& truth) {
  std::vector<double> e(data.points.size());
  for (std::size_t k = 0; k < data.points.size(); ++k) {
    const nurbs::ClosestPointResult r = nurbs::refine_closest_point(
        fit.surface, truth(data.params[k].u, data.params[k].v), fit.params[k].u, fit.params[k].v);
    EXPECT_TRUE(r.ok());
    e[k] = r.distance;
  }
  return e;
}

// Largest distance from the noise-free truth to the fitted surface on an m × m grid between the scan lines.
double worst_gap_to_truth(const DentedPart& part, const Surface& fit, int m, double u_max = 1.0) {
  double worst = 0.0;
  for (int a = 0; a < m; ++a) {
    for (int b = 0; b < m; ++b) {
      const double u = u_max * (a + 0.5) / m, v = (b + 0.5) / m;
      const nurbs::ClosestPointResult r = nurbs::refine_closest_point(fit, part.at(u, v), u, v);
      EXPECT_TRUE(r.ok());
      worst = std::max(worst, r.distance);
    }
  }
  return worst;
}

TEST(FitSurface, ADentTheNominalKnotsCannotFollowIsRefinedUntilTheResidualsAreNoise) {
  const DentedPart part;
  constexpr double sigma = 0.005;
  const Data data = scan(part, 250, sigma, 1);  // 0.4 mm spacing, 62 500 points
  // Without refinement the dent stays in the residuals.
  const FitResult plain = fit_control_points(part.nominal, data.points, data.params);
  ASSERT_TRUE(plain.ok());
  EXPECT_GT(plain.max_residual, 0.1);

  const AdaptiveFitResult fit = fit_surface(part.nominal, data.points, data.params);
  EXPECT_EQ(fit.status, AdaptiveFitResult::Status::OK)
      << "spans above noise " << fit.spans_above_noise << ", rounds " << fit.rounds << ", control points "
      << fit.control_points << ", rms " << fit.rms << ", sigma " << fit.noise_sigma << ", max " << fit.max_residual;
  EXPECT_GT(fit.rounds, 0);
  EXPECT_NEAR(fit.rms, sigma, 0.1 * sigma) << fit.control_points << " control points";
  EXPECT_NEAR(fit.noise_sigma, sigma, 0.1 * sigma);
  const double gap = worst_gap_to_truth(part, fit.surface, 300);
  EXPECT_LE(gap, 3.0 * sigma);
  RecordProperty("worst_gap_to_truth_um", std::to_string(gap * 1000.0));
  RecordProperty("rms_um", std::to_string(fit.rms * 1000.0));
  RecordProperty("noise_sigma_um", std::to_string(fit.noise_sigma * 1000.0));
  RecordProperty("control_points", fit.control_points);
  RecordProperty("rounds", fit.rounds);
}

// The fit's variance factor is its hat matrix's: σ²·v_k must be the scatter of the fitted surface at point k over
// noise seeds, refinement and adaptive penalty included (measured here: 0.94). (This case does not tell the rounds'
// target apart: the free-form case does, bench/fit_cases, where a cascade of fits from the last round's surface
// scattered 2.7 times, in variance, what its last hat matrix said.)
// (Whether u, which adds the fit's estimated bias, covers the true error is tested on the free-form case, where
// the smoothing bias matters: tests/studies/freeform_study_test.cpp.)
TEST(FitSurface, ItsVarianceFactorPredictsTheScatterOverNoiseSeeds) {
  DentedPart part;
  part.depth = 0.03;  // a dent the 1.4 mm scan can follow (0.3 mm would be a feature between scan lines)
  constexpr double sigma = 0.005;
  constexpr int kSeeds = 6, n = 70;
  std::vector<double> sum(n * n, 0.0), sum2(n * n, 0.0);
  double predicted_variance = 0.0;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const Data data = scan(part, n, sigma, static_cast<std::uint64_t>(seed));
    const AdaptiveFitResult fit = fit_surface(part.nominal, data.points, data.params);
    ASSERT_TRUE(fit.fitted());
    for (std::size_t k = 0; k < data.points.size(); ++k) {
      // The truth's signed distance from the fit along the fit's normal at its foot point.
      const Point3 truth = part.at(data.params[k].u, data.params[k].v);
      const nurbs::ClosestPointResult r = nurbs::refine_closest_point(fit.surface, truth, fit.params[k].u, fit.params[k].v);
      ASSERT_TRUE(r.ok());
      const double e = (truth - r.point).dot(nurbs::unit_normal(fit.surface, r.u, r.v).n);
      sum[k] += e;
      sum2[k] += e * e;
      const double v = fit.noise_sigma * fit.noise_sigma * fit.variance_factor[k];
      predicted_variance += v;
    }
  }
  double scatter = 0.0;
  for (std::size_t k = 0; k < sum.size(); ++k) {
    const double mean = sum[k] / kSeeds;
    scatter += (sum2[k] - kSeeds * mean * mean) / (kSeeds - 1);
  }
  predicted_variance /= kSeeds;
  RecordProperty("scatter_over_predicted_variance", std::to_string(scatter / predicted_variance));
  EXPECT_GT(scatter / predicted_variance, 0.75);
  EXPECT_LT(scatter / predicted_variance, 1.33);
}

// A broad bulge (Gaussian, 0.3 mm high, σ_r 12 mm) on the 100 mm patch, 90 × 90 points at σ = 5 µm. From the
// nominal's 5 × 5 spans every span ends consistent with the noise, but the residuals show a misfit thin over the
// face (AdaptiveFitResult::thin_misfit_seen), so the fit is made again from the spans halved
// (AdaptiveFitOptions::dense_start_points_per_control_point) and the one with the lower cross-validation score
// taken. Measured: 420 control points, rms error 0.81 µm, ±2u covers 97.3 %, against 529, 0.63 µm and 99.2 %.
// With the balanced penalty (AdaptiveFitOptions::SpatialPenalty::Balance) the fit from the nominal's spans follows
// it: 361 control points, 0.64 µm, 97.5 %. (Not caught: where the residuals show nothing, e.g. 0.2 mm high and
// σ_r 25 mm, 64 control points, 0.60 µm and 83.1 %; tried on every face the second start costs BM_Compensate10k
// 4.8 times.)
TEST(FitSurface, ABroadMisfitTheSpanTestsCannotSeeIsFollowedFromAFinerStart) {
  const Surface nominal = nominal_patch();
  const Point3 centre = nurbs::evaluate(nominal, 0.55, 0.45);
  auto truth = [&](double u, double v) -> Point3 {
    const Point3 S = nurbs::evaluate(nominal, u, v);
    return S + 0.3 * std::exp(-(S - centre).squaredNorm() / (2.0 * 12.0 * 12.0)) * nurbs::unit_normal(nominal, u, v).n;
  };
  constexpr double sigma = 0.005;
  constexpr int n = 90;
  const Data data = grid_at_cell_centres(nominal, truth, n, sigma, 12);
  struct Score {
    double rms = 0.0, covered = 0.0;
  };
  auto score = [&](const AdaptiveFitResult& fit) {
    Score out;
    const std::vector<double> e = distances_to_truth(fit, data, truth);
    for (std::size_t k = 0; k < data.points.size(); ++k) {
      const double u = std::hypot(fit.noise_sigma * std::sqrt(fit.variance_factor[k]), fit.misfit[k]);
      out.rms += e[k] * e[k];
      out.covered += e[k] <= 2.0 * u;
    }
    out.rms = std::sqrt(out.rms / static_cast<double>(data.points.size()));
    out.covered /= static_cast<double>(data.points.size());
    return out;
  };
  AdaptiveFitOptions coarse_only;
  coarse_only.dense_start_points_per_control_point = 0.0;
  AdaptiveFitOptions balance;
  balance.spatial_penalty = AdaptiveFitOptions::SpatialPenalty::Balance;
  const AdaptiveFitResult coarse = fit_surface(nominal, data.points, data.params, {}, coarse_only);
  const AdaptiveFitResult fit = fit_surface(nominal, data.points, data.params);
  const AdaptiveFitResult balanced = fit_surface(nominal, data.points, data.params, {}, balance);
  ASSERT_TRUE(coarse.fitted());
  ASSERT_TRUE(fit.fitted());
  ASSERT_TRUE(balanced.fitted());
  const Score c = score(coarse), f = score(fit), b = score(balanced);
  std::printf("balanced weights: %d control points, rms %.2f um, +-2u covers %.1f %%\n", balanced.control_points,
              b.rms * 1e3, 100.0 * b.covered);
  EXPECT_LT(b.rms, 0.0007);
  EXPECT_GE(b.covered, 0.92);
  std::printf("from the nominal's knots: %d control points, rms %.2f um, +-2u covers %.1f %%; begun finer: %d, %.2f um, %.1f %%\n",
              coarse.control_points, c.rms * 1e3, 100.0 * c.covered, fit.control_points, f.rms * 1e3,
              100.0 * f.covered);
  EXPECT_TRUE(coarse.thin_misfit_seen);
  EXPECT_FALSE(coarse.dense_start);
  EXPECT_TRUE(fit.dense_start);
  EXPECT_LT(fit.cv_score, coarse.cv_score);
  EXPECT_LT(f.rms, c.rms);
  EXPECT_GE(f.covered, 0.92);
}

// The shape suite's S07 on the patch: a dent 1 mm deep and 1.2 mm wide (σ of a Gaussian; slopes to 27°) beside a
// bulge 0.25 mm high and 12 mm wide, an 84 × 84 grid (1.2 mm apart) at σ = 4.5 µm. One λ cannot suit both: the
// penalty's weight must go down at the dent and stay up elsewhere. The weights from the local balance of data and
// penalty against those from the fit's roughness alone, each fit scored against the truth over five draws of the
// noise. One draw's largest error is a poor statistic: over seeds 21-30 it ranged from 6.3 to 11.1 µm (balanced)
// and from 8.6 to 16.9 µm (roughness), so the largest is held by its median over the draws, the rms by its mean.
TEST(FitSurface, TheBalancedPenaltyFollowsANarrowDentWithoutRoughnessElsewhere) {
  const Surface nominal = nominal_patch();
  const Point3 dent = nurbs::evaluate(nominal, 0.43, 0.57), bulge = nurbs::evaluate(nominal, 0.6, 0.4);
  auto truth = [&](double u, double v) -> Point3 {
    const Point3 S = nurbs::evaluate(nominal, u, v);
    const double h = 0.25 * std::exp(-(S - bulge).squaredNorm() / (2.0 * 12.0 * 12.0)) -
                     1.0 * std::exp(-(S - dent).squaredNorm() / (2.0 * 1.2 * 1.2));
    return S + h * nurbs::unit_normal(nominal, u, v).n;
  };
  constexpr double sigma = 0.0045;
  constexpr int n = 84;
  struct Score {
    double rms = 0.0, max = 0.0;
  };
  std::vector<Score> balanced, roughness;
  for (const std::uint64_t seed : test::cases<std::uint64_t>({21, 22, 23, 24, 25})) {
    const Data data = grid_at_cell_centres(nominal, truth, n, sigma, seed);
    auto score = [&](const AdaptiveFitResult& fit) {
      Score out;
      for (const double e : distances_to_truth(fit, data, truth)) {
        out.rms += e * e;
        out.max = std::max(out.max, e);
      }
      out.rms = std::sqrt(out.rms / static_cast<double>(data.points.size()));
      return out;
    };
    AdaptiveFitOptions balance;
    balance.spatial_penalty = AdaptiveFitOptions::SpatialPenalty::Balance;
    const AdaptiveFitResult fit_b = fit_surface(nominal, data.points, data.params, {}, balance);
    const AdaptiveFitResult fit_r = fit_surface(nominal, data.points, data.params);
    ASSERT_TRUE(fit_b.fitted());
    ASSERT_TRUE(fit_r.fitted());
    const Score b = score(fit_b), r = score(fit_r);
    std::printf("seed %d: balanced %d control points, rms %.2f um, largest %.2f um; roughness %d, %.2f um, %.2f um\n",
                static_cast<int>(seed), fit_b.control_points, b.rms * 1e3, b.max * 1e3, fit_r.control_points,
                r.rms * 1e3, r.max * 1e3);
    EXPECT_LT(b.rms, 0.001) << "seed " << seed;
    balanced.push_back(b);
    roughness.push_back(r);
  }
  auto mean_rms = [](const std::vector<Score>& s) {
    double sum = 0.0;
    for (const Score& x : s) sum += x.rms;
    return sum / static_cast<double>(s.size());
  };
  auto median_max = [](std::vector<Score> s) {
    std::sort(s.begin(), s.end(), [](const Score& x, const Score& y) { return x.max < y.max; });
    return s[s.size() / 2].max;
  };
  std::printf("balanced: mean rms %.3f um, median largest %.2f um; roughness: %.3f um, %.2f um\n",
              mean_rms(balanced) * 1e3, median_max(balanced) * 1e3, mean_rms(roughness) * 1e3,
              median_max(roughness) * 1e3);
  if (test::kLight) return;  // one draw: the figures over the five are held by the Release run (support/light.hpp)
  EXPECT_LT(mean_rms(balanced), 0.8 * mean_rms(roughness));
  EXPECT_LT(median_max(balanced), 0.009);
  EXPECT_LT(median_max(balanced), median_max(roughness));
}

// A ridge along u (0.1 mm high, Gaussian across it with sd 3 mm, at v = 0.55 on the 100 mm patch), 6 000 random
// points at σ = 4.5 µm. Along the ridge the shape is the nominal's, across it it changes within millimetres: the
// smoothing moved as two directional weights on the final net (AdaptiveFitOptions::directional_smoothing) bends
// the fit freely across the ridge and stiffly along it, where θ sought at the isotropic fit's λ stopped short.
// Measured on three seeds: rms distance to the truth 0.704, 0.669 and 0.728 µm with it (log10 θ +1.8, λ ten times
// larger), 1.130, 1.129 and 1.144 µm without (log10 θ +0.3).
TEST(FitSurface, ARidgeAlongOneDirectionIsSmoothedAlongItMoreThanAcross) {
  const Surface nominal = nominal_patch();
  // (Point3, not auto: an Eigen expression would refer to the evaluations' temporaries after they are gone.)
  auto truth = [&](double u, double v) -> Point3 {
    const double d = 100.0 * (v - 0.55) / 3.0;
    return nurbs::evaluate(nominal, u, v) - 0.1 * std::exp(-0.5 * d * d) * nurbs::unit_normal(nominal, u, v).n;
  };
  constexpr double sigma = 0.0045;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> at(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, sigma);
    Data data;
    for (int k = 0; k < 6000; ++k) {
      const double u = at(rng), v = at(rng);
      data.points.push_back(truth(u, v) + noise(rng) * nurbs::unit_normal(nominal, u, v).n);
      data.params.push_back({u, v});
    }
    AdaptiveFitOptions without;
    without.directional_smoothing = false;
    const AdaptiveFitResult fit = fit_surface(nominal, data.points, data.params);
    const AdaptiveFitResult plain = fit_surface(nominal, data.points, data.params, {}, without);
    ASSERT_TRUE(fit.fitted() && plain.fitted());
    auto rms = [](const std::vector<double>& e) {
      double s = 0.0;
      for (double x : e) s += x * x;
      return std::sqrt(s / static_cast<double>(e.size()));
    };
    const double e_fit = rms(distances_to_truth(fit, data, truth)), e_plain = rms(distances_to_truth(plain, data, truth));
    EXPECT_LT(e_fit, 0.85 * e_plain) << "seed " << seed;
    EXPECT_LT(e_fit, 0.0008) << "seed " << seed;
    // Stiff along u (θ weighs bending along u), within the bound of two decades.
    EXPECT_GT(fit.log10_anisotropy, 1.0) << "seed " << seed;
  }
}

TEST(FitSurface, NoRefinementWhereTheNominalKnotsAlreadyExplainTheData) {
  DentedPart part;
  part.depth = 0.0;
  constexpr double sigma = 0.005;
  const Data data = scan(part, 100, sigma, 2);
  const AdaptiveFitResult fit = fit_surface(part.nominal, data.points, data.params);
  ASSERT_TRUE(fit.ok());
  EXPECT_EQ(fit.rounds, 0);
  EXPECT_EQ(fit.control_points, 64);
  EXPECT_NEAR(fit.noise_sigma, sigma, 0.1 * sigma);
  EXPECT_LE(worst_gap_to_truth(part, fit.surface, 50), 3.0 * sigma);
}

TEST(FitSurface, DataOnHalfThePatchWithTheDentFitThatHalf) {
  const DentedPart part;
  constexpr double sigma = 0.005;
  const Data data = scan(part, 250, sigma, 3, 0.5);  // u ≤ 0.5 holds the dent (u = 0.43)
  const AdaptiveFitResult fit = fit_surface(part.nominal, data.points, data.params);
  ASSERT_TRUE(fit.ok()) << fit.spans_above_noise;
  EXPECT_NEAR(fit.rms, sigma, 0.1 * sigma);
  EXPECT_LE(worst_gap_to_truth(part, fit.surface, 200, 0.5), 3.0 * sigma);
}

TEST(FitSurface, SparseDataStopRefinementAndSaySo) {
  const DentedPart part;
  const Data data = scan(part, 30, 0.005, 4);  // 3.4 mm spacing: the dent falls between scan lines
  AdaptiveFitOptions options;
  options.max_rounds = 20;
  const AdaptiveFitResult fit = fit_surface(part.nominal, data.points, data.params, {}, options);
  EXPECT_NE(fit.status, AdaptiveFitResult::Status::NotDone);
  EXPECT_LE(fit.control_points * options.min_points_per_control_point, 900.0);
}

// A crease across a plane (the shape suite's smoothed step: 0.2 mm over 1 mm at 45°), sampled on a 1 mm grid with
// σ = 3 µm: knot lines through every span it crosses cover the whole face, and soon the points support no more of
// them. Local refinement (AdaptiveFitOptions::local_refinement) then goes on near the crease alone. Errors against
// the closed form, in the band |s| < 3 mm about the crease and outside it.
TEST(FitSurface, WhereThePointsSupportNoMoreKnotLinesACreaseIsRefinedLocally) {
  const Surface start = nurbs::make_plane_patch(Point3(0, 0, 0), Vector3(50, 0, 0), Vector3(0, 50, 0), 3, 3, 5, 5);
  auto crease = [](double x, double y) { return 0.1 * (1.0 + std::tanh(2.0 * (x - y) / std::sqrt(2.0))); };
  for (const std::uint64_t seed : test::cases<std::uint64_t>({7, 8})) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, 0.003);
    Data d;
    for (int a = 0; a <= 50; ++a) {
      for (int b = 0; b <= 50; ++b) {
        d.params.push_back({a / 50.0, b / 50.0});
        d.points.emplace_back(a, b, crease(a, b) + noise(rng));
      }
    }
    struct Errors {
      double band = 0.0, outside = 0.0;  // rms, µm
    };
    auto errors = [&](const AdaptiveFitResult& fit) {
      double band = 0, outside = 0;
      int nb = 0, no = 0;
      for (int a = 0; a <= 200; ++a) {
        for (int b = 0; b <= 200; ++b) {
          const Point3 S = nurbs::evaluate(fit.surface, a / 200.0, b / 200.0);
          const double e = 1e3 * std::abs(S.z() - crease(S.x(), S.y()));
          const bool in_band = std::abs(S.x() - S.y()) / std::sqrt(2.0) < 3.0;
          (in_band ? band : outside) += e * e;
          ++(in_band ? nb : no);
        }
      }
      return Errors{std::sqrt(band / nb), std::sqrt(outside / no)};
    };
    AdaptiveFitOptions lines;
    lines.local_refinement = false;
    const AdaptiveFitResult a = fit_surface(start, d.points, d.params, {}, lines);
    const AdaptiveFitResult b = fit_surface(start, d.points, d.params, {}, AdaptiveFitOptions{});
    ASSERT_TRUE(a.fitted() && b.fitted());
    const Errors ea = errors(a), eb = errors(b);
    std::printf("seed %d: band rms %.2f -> %.2f um, outside %.2f -> %.2f um; %d -> %d control points, %d cells refined\n",
                static_cast<int>(seed), ea.band, eb.band, ea.outside, eb.outside, a.control_points, b.control_points,
                b.refined_cells);
    EXPECT_EQ(a.refined_cells, 0);
    EXPECT_GT(b.refined_cells, 0);
    EXPECT_LE(2.0 * b.control_points, static_cast<int>(d.points.size()));
    EXPECT_LE(eb.band, 0.7 * ea.band);
    EXPECT_LE(eb.outside, 1.05 * ea.outside);
  }
}

TEST(RobustNoiseSigma, IgnoresAMinorityOfLargeResiduals) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<double> r(20000);
  for (double& x : r) x = noise(rng);
  for (std::size_t k = 0; k < r.size(); k += 20) r[k] = 0.5;  // 5 % outliers
  EXPECT_NEAR(robust_noise_sigma(r, {}, 0), 0.01, 0.0008);
}

}  // namespace
}  // namespace probecomp::fitting
