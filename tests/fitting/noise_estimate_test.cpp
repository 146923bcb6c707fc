// LocalPredictionNoise against noise of known σ added to closed-form residual fields: smooth misfits of several
// sizes (which must not move it), gross errors, and the three samplings (grid, random points, scan lines).

#include "probecomp/fitting/noise_estimate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "probecomp/geometry/neighbours.hpp"

namespace probecomp::fitting {
namespace {

enum class Sampling { Grid, Random, ScanLines };

struct Field {
  std::vector<Point3> points;
  std::vector<double> residuals;
};

// About n points over a 100 × 60 mm face (on a cylinder of radius 80 mm about x, so that the neighbourhoods are
// curved in space), residual = misfit(x, y) + N(0, σ).
template <typename Misfit>
Field make_field(Sampling sampling, int n, double sigma, unsigned seed, Misfit misfit) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<std::pair<double, double>> xy;
  if (sampling == Sampling::Grid) {
    const int nx = static_cast<int>(std::round(std::sqrt(n * 100.0 / 60.0))), ny = n / nx;
    for (int i = 0; i < nx; ++i) {
      for (int j = 0; j < ny; ++j) xy.emplace_back(100.0 * (i + 0.5) / nx, 60.0 * (j + 0.5) / ny);
    }
  } else if (sampling == Sampling::Random) {
    for (int k = 0; k < n; ++k) {
      const double y = unit(rng), x = unit(rng);  // as gcc drew them as the call's arguments
      xy.emplace_back(100.0 * x, 60.0 * y);
    }
  } else {
    const int lines = 15, along = n / lines;  // lines 4 mm apart, points 0.1–0.2 mm apart along them
    for (int l = 0; l < lines; ++l) {
      for (int k = 0; k < along; ++k) xy.emplace_back(100.0 * (k + 0.3 * unit(rng)) / along, 2.0 + 4.0 * l);
    }
  }
  Field f;
  for (const auto& [x, y] : xy) {
    f.points.emplace_back(x, 80.0 * std::sin(y / 80.0), 80.0 * std::cos(y / 80.0));
    f.residuals.push_back(misfit(x, y) + noise(rng));
  }
  return f;
}

double estimate(const Field& f, std::span<const double> weights = {}) {
  return LocalPredictionNoise(f.points, weights).sigma(f.residuals);
}

// The spread of the estimate over seeds: its mean within 3 % of σ and every seed within 6 % (its own standard
// error at 6 000 points is about 1.2 %: 1.4826 × MAD has 37 % efficiency).
template <typename Misfit>
void expect_sigma(Sampling sampling, double sigma, Misfit misfit) {
  double sum = 0.0;
  constexpr int kSeeds = 8;
  for (unsigned seed = 1; seed <= kSeeds; ++seed) {
    const double s = estimate(make_field(sampling, 6000, sigma, seed, misfit));
    EXPECT_NEAR(s / sigma, 1.0, 0.06) << "seed " << seed;
    sum += s / sigma;
  }
  EXPECT_NEAR(sum / kSeeds, 1.0, 0.03);
}

TEST(LocalPredictionNoise, ReadsTheNoiseAloneOnEverySampling) {
  for (Sampling s : {Sampling::Grid, Sampling::Random, Sampling::ScanLines}) {
    SCOPED_TRACE(static_cast<int>(s));
    expect_sigma(s, 0.0045, [](double, double) { return 0.0; });
  }
}

// A broad misfit many times the noise (a bulge 0.3 mm high, 14 mm wide, the nominal's knots cannot follow), which
// the residuals' own spread reads as noise, is not.
TEST(LocalPredictionNoise, IsNotMovedByABroadMisfit) {
  auto bulge = [](double x, double y) {
    const double r2 = (x - 45.0) * (x - 45.0) + (y - 28.0) * (y - 28.0);
    return 0.3 * std::exp(-r2 / (2.0 * 7.0 * 7.0));
  };
  for (Sampling s : {Sampling::Grid, Sampling::Random, Sampling::ScanLines}) {
    SCOPED_TRACE(static_cast<int>(s));
    expect_sigma(s, 0.0045, bulge);
  }
}

// A wave of 20 µm and 12 mm wavelength across the whole face: not quadratic over a neighbourhood, but nearly so.
TEST(LocalPredictionNoise, IsNotMovedByAWave) {
  expect_sigma(Sampling::Random, 0.003, [](double x, double y) { return 0.02 * std::sin(2.0 * M_PI * (0.8 * x + 0.6 * y) / 12.0); });
}

// The correlation of neighbouring residuals: about 0 on independent noise (within 4 standard errors of about
// 1/√(12·6000)), and positive where a misfit smooth over a neighbourhood remains: a wave of 12 mm at σ = 4.5 µm,
// 2 µm high, holds 2²/2 / (2²/2 + 4.5²) = 0.090 of the variance, and neighbours within 2 mm (a sixth of its length)
// share cos(2π·d/12) ≥ 0.5 of it: between 0.045 and 0.090.
TEST(LocalPredictionNoise, NeighbouringResidualsCorrelateOnlyUnderASmoothMisfit) {
  for (Sampling s : {Sampling::Grid, Sampling::Random}) {
    SCOPED_TRACE(static_cast<int>(s));
    const Field noise = make_field(s, 6000, 0.0045, 3, [](double, double) { return 0.0; });
    EXPECT_NEAR(LocalPredictionNoise(noise.points, {}).neighbour_correlation(noise.residuals), 0.0, 4.0 / std::sqrt(12.0 * 6000));
    const Field wave = make_field(s, 6000, 0.0045, 3, [](double x, double y) { return 0.002 * std::sin(2.0 * M_PI * (0.8 * x + 0.6 * y) / 12.0); });
    const double rho = LocalPredictionNoise(wave.points, {}).neighbour_correlation(wave.residuals);
    EXPECT_GT(rho, 0.045);
    EXPECT_LT(rho, 0.090 + 4.0 / std::sqrt(12.0 * 6000));
  }
}

// 3 % of the points 0.1–0.5 mm off: a minority the median ignores.
TEST(LocalPredictionNoise, IgnoresAMinorityOfGrossErrors) {
  Field f = make_field(Sampling::Random, 6000, 0.003, 7, [](double, double) { return 0.0; });
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> size(0.1, 0.5);
  for (std::size_t k = 0; k < f.residuals.size(); k += 33) f.residuals[k] += size(rng);
  EXPECT_NEAR(estimate(f) / 0.003, 1.0, 0.08);
  // Weighted out, they are neither tested nor used as neighbours.
  std::vector<double> w(f.residuals.size(), 1.0);
  for (std::size_t k = 0; k < w.size(); k += 33) w[k] = 0.0;
  EXPECT_NEAR(estimate(f, w) / 0.003, 1.0, 0.06);
}

// A single point off by 11 σ stands out beyond 5 σ̂, on every sampling and seed; under smooth shape the local
// quadratic follows (a broad bulge and a wave) hardly a point does: over 12 fields of 6 000 points, at most 2 (a
// Gaussian passes 5 σ once in 1.7 million points; pure noise on the grid: 1 in 120 000 here).
TEST(LocalPredictionNoise, AGrossErrorStandsOutAndSmoothShapeHardlyEver) {
  auto shape = [](double x, double y) {
    const double r2 = (x - 45.0) * (x - 45.0) + (y - 28.0) * (y - 28.0);
    return 0.3 * std::exp(-r2 / (2.0 * 7.0 * 7.0)) + 0.02 * std::sin(2.0 * M_PI * (0.8 * x + 0.6 * y) / 20.0);
  };
  std::size_t clean = 0;
  for (Sampling s : {Sampling::Grid, Sampling::Random, Sampling::ScanLines}) {
    for (unsigned seed = 1; seed <= 4; ++seed) {
      SCOPED_TRACE(::testing::Message() << "sampling " << static_cast<int>(s) << " seed " << seed);
      Field f = make_field(s, 6000, 0.0045, seed, shape);
      const LocalPredictionNoise local(f.points, {});
      clean += local.standing_out(f.residuals, 5.0, 0.002);
      f.residuals[2500] += 0.05;
      EXPECT_GE(local.standing_out(f.residuals, 5.0, 0.002), 1u);
      // Below the floor nothing stands out: exact data's model error is no gross error.
      EXPECT_EQ(local.standing_out(f.residuals, 5.0, 0.08), 0u);
    }
  }
  EXPECT_LE(clean, 2u);
}

// Gross errors 0.1–5 mm alone, in pairs and in threes of nearest neighbours (60 clusters over 6 000 points), on
// the bulge and wave above at σ = 4.5 µm and without noise: every one is peeled (a cluster's smaller errors once
// its larger ones are out of their neighbours' predictions; on random points clusters fall among each other's
// neighbours: four passes left 1–2 per field, eight none). Other points are peeled where a gross neighbour weighs more in
// their prediction than in its own (random points, where a quadratic through uneven neighbours extrapolates):
// 2–7 per field there, none on the grid, one on the scan lines; a fit that leaves them out predicts them and takes
// them back (compensation/face_fits.cpp).
TEST(LocalPredictionNoise, PeelsClustersOfGrossErrorsAndHardlyAnythingElse) {
  auto shape = [](double x, double y) {
    const double r2 = (x - 45.0) * (x - 45.0) + (y - 28.0) * (y - 28.0);
    return 0.3 * std::exp(-r2 / (2.0 * 7.0 * 7.0)) + 0.02 * std::sin(2.0 * M_PI * (0.8 * x + 0.6 * y) / 20.0);
  };
  for (const double sigma : {0.0045, 0.0}) {
    for (Sampling s : {Sampling::Grid, Sampling::Random, Sampling::ScanLines}) {
      for (unsigned seed = 1; seed <= 3; ++seed) {
        SCOPED_TRACE(::testing::Message() << "sigma " << sigma << " sampling " << static_cast<int>(s) << " seed " << seed);
        Field f = make_field(s, 6000, sigma, seed, shape);
        const std::vector<std::uint32_t> near = geometry::nearest_others(f.points, 2);
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<double> size(0.1, 5.0);
        std::vector<char> moved(f.points.size(), 0);
        for (std::size_t m = 0; m < 60; ++m) {
          const std::size_t k = 100 * m + 7;
          const std::size_t cluster[] = {k, near[2 * k], near[2 * k + 1]};
          for (std::size_t c = 0; c <= m % 3; ++c) {
            if (moved[cluster[c]]) continue;
            moved[cluster[c]] = 1;
            f.residuals[cluster[c]] += (rng() % 2 ? 1.0 : -1.0) * size(rng);
          }
        }
        const LocalPredictionNoise local(f.points, {}, f.points.size());
        const std::vector<char> peeled = peel_isolated_errors(local, f.points, f.residuals, 5.0, 0.002);
        int missed = 0, others = 0;
        for (std::size_t k = 0; k < moved.size(); ++k) {
          missed += moved[k] && !peeled[k];
          others += !moved[k] && peeled[k];
        }
        EXPECT_EQ(missed, 0);
        EXPECT_LE(others, s == Sampling::Random ? 10 : 1);
      }
    }
  }
}

TEST(LocalPredictionNoise, IsZeroOnExactAndInfiniteOnTooFewPoints) {
  const Field exact = make_field(Sampling::Grid, 2000, 0.0, 1, [](double x, double y) { return 1e-3 * (x * y / 3000.0 + 0.3 * x); });
  EXPECT_LT(estimate(exact), 1e-9);
  const Field few = make_field(Sampling::Random, 10, 0.003, 1, [](double, double) { return 0.0; });
  EXPECT_TRUE(std::isinf(estimate(few)));
}

}  // namespace
}  // namespace probecomp::fitting
