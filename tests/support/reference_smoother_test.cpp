// The reference P-spline smoother against exact answers: its null space, spline approximation orders, a dense
// solve of the same normal equations, finite differences, and noise of known σ.

#include "support/reference_smoother.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace probecomp::reference {
namespace {

constexpr double kPi = std::numbers::pi;

std::string text(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

struct Data {
  std::vector<double> s, t, z, truth;
};

template <class F>
Data random_data(F&& f, std::size_t n, double s0, double s1, double t0, double t1, double sigma, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> us(s0, s1), ut(t0, t1);
  std::normal_distribution<double> noise(0.0, 1.0);
  Data d;
  for (std::size_t k = 0; k < n; ++k) {
    d.s.push_back(us(rng));
    d.t.push_back(ut(rng));
    d.truth.push_back(f(d.s.back(), d.t.back()));
    d.z.push_back(d.truth.back() + (sigma > 0.0 ? sigma * noise(rng) : 0.0));
  }
  return d;
}

SmootherOptions rectangle(double s0, double s1, double t0, double t1, int spans_s, int spans_t) {
  SmootherOptions o;
  o.s0 = s0, o.s1 = s1, o.t0 = t0, o.t1 = t1, o.spans_s = spans_s, o.spans_t = spans_t;
  return o;
}

// Largest and rms |fit − f| over a lattice of step about `step` on the fit's rectangle less `margin` all round.
struct Deviation {
  double max = 0.0, rms = 0.0;
};
template <class F>
Deviation deviation(const SmootherResult& fit, F&& f, double step, double margin = 0.0) {
  Deviation d;
  double sum = 0.0;
  int count = 0;
  const double s0 = fit.s0 + margin, s1 = fit.s1 - margin, t0 = fit.t0 + margin, t1 = fit.t1 - margin;
  const int ns = static_cast<int>(std::lround((s1 - s0) / step)), nt = static_cast<int>(std::lround((t1 - t0) / step));
  for (int i = 0; i <= ns; ++i) {
    for (int j = 0; j <= nt; ++j) {
      const double s = s0 + (s1 - s0) * i / ns, t = t0 + (t1 - t0) * j / nt;
      const double e = evaluate(fit, s, t).value - f(s, t);
      d.max = std::max(d.max, std::abs(e));
      sum += e * e;
      ++count;
    }
  }
  d.rms = std::sqrt(sum / count);
  return d;
}

// 0.1 mm waves of 40 mm along s and 30 mm along t.
double waves(double s, double t) { return 0.1 * std::sin(2.0 * kPi * s / 40.0) * std::cos(2.0 * kPi * t / 30.0); }

TEST(ReferenceSmoother, ABilinearFunctionIsReproducedWhateverLambda) {
  // α + βs + γt + δst has second differences zero in both directions: the penalty cannot touch it.
  const auto f = [](double s, double t) { return 0.3 + 0.02 * s - 0.015 * t + 4e-4 * s * t; };
  const Data d = random_data(f, 600, -20.0, 80.0, 10.0, 50.0, 0.0, 11);
  SmootherOptions o = rectangle(-20.0, 80.0, 10.0, 50.0, 14, 9);
  const SmootherResult chosen = smooth(d.s, d.t, d.z, o);
  ASSERT_EQ(chosen.status, SmootherStatus::OK);
  double worst = deviation(chosen, f, 0.5).max;
  EXPECT_LT(worst, 1e-9);
  // From near interpolation to near-bilinear: the ends of the GCV grid and beyond, in each direction.
  for (const double xs : {-6.0, 0.0, 8.0}) {
    for (const double xt : {-6.0, 0.0, 8.0}) {
      o.lambda_s = chosen.lambda_reference * std::pow(10.0, xs);
      o.lambda_t = chosen.lambda_reference * std::pow(10.0, xt);
      const SmootherResult fit = smooth(d.s, d.t, d.z, o);
      ASSERT_EQ(fit.status, SmootherStatus::OK);
      const double e = deviation(fit, f, 0.5).max;
      EXPECT_LT(e, 1e-9) << xs << " " << xt;
      worst = std::max(worst, e);
      const SmootherValue v = evaluate(fit, 31.0, 17.0);
      EXPECT_NEAR(v.ds, 0.02 + 4e-4 * 17.0, 1e-10);
      EXPECT_NEAR(v.dt, -0.015 + 4e-4 * 31.0, 1e-10);
    }
  }
  RecordProperty("max_error_mm", text(worst));
}

// Least-squares cubic-spline approximation is O(h⁴): within the interpolating spline's bound
// (5/384)·h⁴·max|f⁗| summed over the two directions (de Boor, "A practical guide to splines", ch. XVII), and the
// penalty, GCV-chosen on data without noise, should add nothing near that size.
double spline_bound(double hs, double ht) {
  const double ks = 2.0 * kPi / 40.0, kt = 2.0 * kPi / 30.0;
  return 5.0 / 384.0 * 0.1 * (std::pow(hs, 4) * std::pow(ks, 4) + std::pow(ht, 4) * std::pow(kt, 4));
}

TEST(ReferenceSmoother, SmoothDataWithoutNoiseOnAGridIsReproduced) {
  Data d;
  for (int i = 0; i <= 120; ++i) {
    for (int j = 0; j <= 60; ++j) {
      d.s.push_back(i), d.t.push_back(j), d.z.push_back(waves(i, j));
    }
  }
  const SmootherResult fit = smooth(d.s, d.t, d.z, rectangle(0.0, 120.0, 0.0, 60.0, 40, 20));  // 3 mm spans
  ASSERT_EQ(fit.status, SmootherStatus::OK);
  const Deviation dev = deviation(fit, waves, 0.25);
  EXPECT_LT(dev.max, spline_bound(3.0, 3.0));  // 0.27 µm
  RecordProperty("max_error_um", text(dev.max * 1e3));
}

TEST(ReferenceSmoother, SmoothDataWithoutNoiseAtRandomPointsIsReproduced) {
  const Data d = random_data(waves, 6000, 0.0, 120.0, 0.0, 60.0, 0.0, 5);
  const SmootherResult fit = smooth(d.s, d.t, d.z, rectangle(0.0, 120.0, 0.0, 60.0, 40, 20));
  ASSERT_EQ(fit.status, SmootherStatus::OK);
  // Away from the edge: in a corner span the nearest points may be a span away and the fit extrapolates to them
  // (up to 1.5 µm in the corners over other seeds; inside, 0.06 µm at most).
  const Deviation dev = deviation(fit, waves, 0.25, 3.0);
  EXPECT_LT(dev.max, spline_bound(3.0, 3.0));
  RecordProperty("max_error_um", text(dev.max * 1e3));
}

TEST(ReferenceSmoother, NoiseIsFilteredAndItsSigmaEstimated) {
  constexpr double sigma = 4.5e-3;
  const Data d = random_data(waves, 5000, 0.0, 120.0, 0.0, 60.0, sigma, 21);
  const SmootherResult fit = smooth(d.s, d.t, d.z, rectangle(0.0, 120.0, 0.0, 60.0, 40, 20));
  ASSERT_EQ(fit.status, SmootherStatus::OK);
  // An unbiased linear smoother of edf parameters leaves σ·sqrt(edf/n) of noise: 4.5 µm·sqrt(335/5000) ≈ 1.2 µm here.
  // The bar, σ/3, asks that GCV's bias and variance together stay near that.
  const Deviation dev = deviation(fit, waves, 0.25);
  EXPECT_LT(dev.rms, sigma / 3.0);
  EXPECT_NEAR(fit.sigma, sigma, 0.1 * sigma);
  RecordProperty("rms_error_um", text(dev.rms * 1e3));
  RecordProperty("sigma_estimate_um", text(fit.sigma * 1e3));
  RecordProperty("edf", text(fit.edf));
  EXPECT_GT(fit.edf, 4.0);
  EXPECT_LT(fit.edf, static_cast<double>(d.s.size()));
  double hat_sum = 0.0;
  for (const double h : fit.hat) {
    EXPECT_GE(h, 0.0);
    EXPECT_LE(h, 1.0);
    hat_sum += h;
  }
  EXPECT_NEAR(hat_sum, fit.edf, 1e-8 * fit.edf);
}

TEST(ReferenceSmoother, GcvPicksNearTheOracle) {
  // The true error at GCV's λ against the best true error over a half-decade λ grid.
  constexpr double sigma = 4.5e-3;
  const auto f = [](double s, double t) {
    return 0.08 * std::sin(2.0 * kPi * s / 50.0) * std::cos(2.0 * kPi * t / 35.0);
  };
  const Data d = random_data(f, 3000, 0.0, 80.0, 0.0, 60.0, sigma, 8);
  SmootherOptions o = rectangle(0.0, 80.0, 0.0, 60.0, 24, 18);
  const SmootherResult chosen = smooth(d.s, d.t, d.z, o);
  ASSERT_EQ(chosen.status, SmootherStatus::OK);
  const double chosen_error = deviation(chosen, f, 0.5).rms;
  double best_error = std::numeric_limits<double>::infinity(), best_gcv = best_error;
  for (double xs = -5.0; xs <= 7.0; xs += 0.5) {
    for (double xt = -5.0; xt <= 7.0; xt += 0.5) {
      o.lambda_s = chosen.lambda_reference * std::pow(10.0, xs);
      o.lambda_t = chosen.lambda_reference * std::pow(10.0, xt);
      const SmootherResult fit = smooth(d.s, d.t, d.z, o);
      ASSERT_EQ(fit.status, SmootherStatus::OK);
      best_error = std::min(best_error, deviation(fit, f, 0.5).rms);
      best_gcv = std::min(best_gcv, fit.gcv);
    }
  }
  EXPECT_LT(chosen_error, 1.05 * best_error);
  EXPECT_LE(chosen.gcv, best_gcv * (1.0 + 1e-9));  // the search found GCV's minimum over the grid too
  RecordProperty("error_ratio", text(chosen_error / best_error));
}

// The same normal equations solved densely: B from evaluate() with unit coefficients, the penalty built from the
// header's definition, A⁻¹ in full.
// Returns the largest relative difference in tr H and the h_k.
double expect_matches_dense(const Data& d, const std::vector<double>& w, SmootherOptions o) {
  const SmootherResult fit = smooth(d.s, d.t, d.z, o, w);
  EXPECT_EQ(fit.status, SmootherStatus::OK);
  if (fit.status != SmootherStatus::OK) return 1.0;
  const int Ns = o.spans_s + 3, Nt = o.spans_t + 3, N = Ns * Nt;
  const auto n = static_cast<Eigen::Index>(d.s.size());
  Eigen::MatrixXd B(n, N);
  SmootherResult unit = fit;
  for (int c = 0; c < N; ++c) {
    std::fill(unit.coefficients.begin(), unit.coefficients.end(), 0.0);
    unit.coefficients[c] = 1.0;
    for (Eigen::Index k = 0; k < n; ++k) B(k, c) = evaluate(unit, d.s[k], d.t[k]).value;
  }
  const double hs = (o.s1 - o.s0) / o.spans_s, ht = (o.t1 - o.t0) / o.spans_t;
  const int K = o.adaptive_blocks;
  const auto block = [&](double x, double x0, double x1) {
    const double c = std::clamp(x, x0, x1);
    return std::min(K - 1, static_cast<int>(std::floor(K * (c - x0) / (x1 - x0))));
  };
  const auto weight = [&](int i, int j) {  // coefficient (i, j) is the middle of the difference
    if (fit.log_weights.empty()) return 1.0;
    const int b = block(o.s0 + (i - 1) * hs, o.s0, o.s1) * K + block(o.t0 + (j - 1) * ht, o.t0, o.t1);
    return std::exp(fit.log_weights[b]);
  };
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(N, N);
  const auto add_difference = [&](int i, int j, int di, int dj, double scale) {
    Eigen::VectorXd r = Eigen::VectorXd::Zero(N);
    r((i - di) * Nt + j - dj) = 1.0, r(i * Nt + j) = -2.0, r((i + di) * Nt + j + dj) = 1.0;
    P += scale * weight(i, j) * r * r.transpose();
  };
  for (int i = 0; i < Ns; ++i) {
    for (int j = 0; j < Nt; ++j) {
      if (i > 0 && i + 1 < Ns) add_difference(i, j, 1, 0, fit.lambda_s / std::pow(hs, 4));
      if (j > 0 && j + 1 < Nt) add_difference(i, j, 0, 1, fit.lambda_t / std::pow(ht, 4));
    }
  }
  const Eigen::VectorXd W = Eigen::Map<const Eigen::VectorXd>(w.data(), n);
  const Eigen::VectorXd z = Eigen::Map<const Eigen::VectorXd>(d.z.data(), n);
  const Eigen::MatrixXd A = B.transpose() * W.asDiagonal() * B + P;
  const Eigen::MatrixXd Ainv = A.inverse();
  const Eigen::VectorXd c = Ainv * (B.transpose() * W.asDiagonal() * z);
  const double edf = (Ainv * B.transpose() * W.asDiagonal() * B).trace();
  for (int k = 0; k < N; ++k) EXPECT_NEAR(fit.coefficients[k], c(k), 1e-9 * c.cwiseAbs().maxCoeff());
  EXPECT_NEAR(fit.edf, edf, 1e-9 * edf);
  double worst = std::abs(fit.edf - edf) / edf;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double h = W(k) * B.row(k).dot(Ainv * B.row(k).transpose());
    EXPECT_NEAR(fit.hat[k], h, 1e-9 * h) << k;
    worst = std::max(worst, std::abs(fit.hat[k] - h) / h);
  }
  const Eigen::VectorXd r = z - B * c;
  const double rss = r.dot(W.asDiagonal() * r), dn = static_cast<double>(n);
  EXPECT_NEAR(fit.gcv, dn * rss / ((dn - edf) * (dn - edf)), 1e-9 * fit.gcv);
  EXPECT_NEAR(fit.sigma, std::sqrt(rss / (dn - edf)), 1e-9 * fit.sigma);
  return worst;
}

// A tilted bowl with a wave: the tilt is large next to the rest, so the solve here (which fits z less its
// bilinear trend) is compared with a dense one that does not.
Data small_case(std::vector<double>& w) {
  const auto f = [](double s, double t) {
    return 2.0 + 0.3 * s - 0.2 * t + 0.01 * s * t + 0.05 * std::sin(s / 3.0) + 0.02 * t * t / 100.0;
  };
  const Data d = random_data(f, 160, -5.0, 15.0, 2.0, 14.0, 3e-3, 4);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.5, 2.0);
  w.clear();
  for (std::size_t k = 0; k < d.s.size(); ++k) w.push_back(u(rng));
  return d;
}

TEST(ReferenceSmoother, TraceAndHatMatchADenseInverse) {
  std::vector<double> w;
  const Data d = small_case(w);
  double worst = expect_matches_dense(d, w, rectangle(-5.0, 15.0, 2.0, 14.0, 6, 4));  // blocks along s
  worst = std::max(worst, expect_matches_dense(d, w, rectangle(-5.0, 15.0, 2.0, 14.0, 3, 7)));  // along t
  worst = std::max(worst, expect_matches_dense(d, w, rectangle(-5.0, 15.0, 2.0, 14.0, 9, 8)));  // 12 × 11 blocks
  SmootherOptions a = rectangle(-5.0, 15.0, 2.0, 14.0, 7, 5);
  a.adaptive = true;
  worst = std::max(worst, expect_matches_dense(d, w, a));
  const std::vector<double> weights = smooth(d.s, d.t, d.z, a, w).log_weights;  // not all 0: a real check
  ASSERT_EQ(weights.size(), 16u);
  EXPECT_GT(*std::max_element(weights.begin(), weights.end()) - *std::min_element(weights.begin(), weights.end()), 1.0);
  RecordProperty("worst_relative_difference", text(worst));
}

TEST(ReferenceSmoother, DerivativesMatchCentralDifferences) {
  const Data d = random_data(waves, 3000, 0.0, 120.0, 0.0, 60.0, 4.5e-3, 2);
  const SmootherResult fit = smooth(d.s, d.t, d.z, rectangle(0.0, 120.0, 0.0, 60.0, 40, 20));
  ASSERT_EQ(fit.status, SmootherStatus::OK);
  // Central differences of step e err by e²/6·|f'''| (≤ 1e-12 here) plus rounding ~1e-16·|f|/e: 1e-9 is loose.
  constexpr double e = 1e-4;
  double worst = 0.0;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> us(1.0, 119.0), ut(1.0, 59.0);
  for (int i = 0; i < 200; ++i) {
    const double s = us(rng), t = ut(rng);
    const SmootherValue v = evaluate(fit, s, t);
    const double fs = (evaluate(fit, s + e, t).value - evaluate(fit, s - e, t).value) / (2.0 * e);
    const double ft = (evaluate(fit, s, t + e).value - evaluate(fit, s, t - e).value) / (2.0 * e);
    EXPECT_NEAR(v.ds, fs, 1e-9);
    EXPECT_NEAR(v.dt, ft, 1e-9);
    worst = std::max({worst, std::abs(v.ds - fs), std::abs(v.dt - ft)});
  }
  RecordProperty("max_difference", text(worst));
}

TEST(ReferenceSmoother, AdaptivePenaltiesFollowANarrowRidge) {
  // Gentle waves everywhere, and in the band 20 < t < 35 a 0.12 mm sine of wavelength 8 mm along s.
  const auto f = [](double s, double t) {
    double v = 0.1 * std::sin(2.0 * kPi * s / 100.0) * std::cos(2.0 * kPi * t / 80.0);
    if (t > 20.0 && t < 35.0) {
      const double window = std::sin(kPi * (t - 20.0) / 15.0);
      v += 0.12 * window * window * std::sin(2.0 * kPi * s / 8.0);
    }
    return v;
  };
  const Data d = random_data(f, 6000, 0.0, 100.0, 0.0, 60.0, 4.5e-3, 3);
  SmootherOptions o = rectangle(0.0, 100.0, 0.0, 60.0, 50, 30);
  const SmootherResult plain = smooth(d.s, d.t, d.z, o);
  o.adaptive = true;
  const SmootherResult adaptive = smooth(d.s, d.t, d.z, o);
  ASSERT_EQ(plain.status, SmootherStatus::OK);
  ASSERT_EQ(adaptive.status, SmootherStatus::OK);
  ASSERT_EQ(adaptive.log_weights.size(), 16u);
  const double e_plain = deviation(plain, f, 0.25).rms, e_adaptive = deviation(adaptive, f, 0.25).rms;
  EXPECT_LT(e_adaptive, 0.9 * e_plain);
  EXPECT_LE(adaptive.gcv, plain.gcv);
  // Blocks b_t = 1, 2 (15 < t < 45) hold the ridge: penalised less than the calm rows b_t = 0, 3.
  for (int bs = 0; bs < 4; ++bs) {
    EXPECT_LT(std::max(adaptive.log_weights[bs * 4 + 1], adaptive.log_weights[bs * 4 + 2]),
              std::min(adaptive.log_weights[bs * 4 + 0], adaptive.log_weights[bs * 4 + 3]));
  }
  RecordProperty("rms_plain_um", text(e_plain * 1e3));
  RecordProperty("rms_adaptive_um", text(e_adaptive * 1e3));
}

TEST(ReferenceSmoother, TooFewOrDegeneratePointsAreNotEnoughData) {
  const SmootherOptions o = rectangle(0.0, 10.0, 0.0, 10.0, 5, 5);
  const auto expect_not_enough = [&](const std::vector<double>& s, const std::vector<double>& t) {
    const std::vector<double> z(s.size(), 1.0);
    const SmootherResult r = smooth(s, t, z, o);
    EXPECT_EQ(r.status, SmootherStatus::NotEnoughData);
    EXPECT_TRUE(r.coefficients.empty());
    EXPECT_TRUE(std::isfinite(r.sigma) && std::isfinite(r.edf) && std::isfinite(r.gcv));
    EXPECT_EQ(r.hat.size(), s.size());
    for (const double h : r.hat) EXPECT_EQ(h, 0.0);
    EXPECT_TRUE(std::isnan(evaluate(r, 5.0, 5.0).value));
  };
  expect_not_enough({}, {});
  expect_not_enough({1.0, 2.0, 3.0}, {1.0, 5.0, 2.0});
  expect_not_enough(std::vector<double>(50, 4.0), std::vector<double>(50, 6.0));  // all the same point
  std::vector<double> s, t;
  for (int k = 0; k < 50; ++k) s.push_back(0.2 * k), t.push_back(0.2 * k);  // on the diagonal s = t
  expect_not_enough(s, t);
  expect_not_enough({1.0, 2.0, 3.0, 4.0, 20.0, 30.0}, {1.0, 5.0, 2.0, 7.0, 3.0, 3.0});  // two outside: 4 left
  // Zero weights leave points out too.
  const std::vector<double> s6 = {1.0, 2.0, 3.0, 4.0, 5.0, 6.0}, t6 = {1.0, 5.0, 2.0, 7.0, 3.0, 9.0};
  const std::vector<double> z6(6, 1.0), w6 = {1.0, 1.0, 0.0, 1.0, 0.0, 1.0};
  EXPECT_EQ(smooth(s6, t6, z6, o, w6).status, SmootherStatus::NotEnoughData);
  EXPECT_EQ(smooth(s6, t6, z6, o).status, SmootherStatus::OK);
  std::vector<double> z_nan = z6;
  z_nan[1] = std::numeric_limits<double>::quiet_NaN();  // left out: 5 remain
  const SmootherResult r5 = smooth(s6, t6, z_nan, o);
  EXPECT_EQ(r5.status, SmootherStatus::OK);
  EXPECT_EQ(r5.points_used, 5u);
  EXPECT_EQ(r5.hat[1], 0.0);
  // A malformed call is the caller's error, not the data's.
  EXPECT_THROW((void)smooth(s6, t6, std::vector<double>(5, 1.0), o), std::invalid_argument);
  EXPECT_THROW((void)smooth(s6, t6, z6, rectangle(1.0, 1.0, 0.0, 10.0, 5, 5)), std::invalid_argument);
}

}  // namespace
}  // namespace probecomp::reference
