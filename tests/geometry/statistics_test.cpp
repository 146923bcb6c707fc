// Medians and the robust scale against a full sort: small sets (std::nth_element) and large ones (found in
// parallel from a sample's bracket), with ties, sorted input, and a sample that misses the median.

#include "probecomp/geometry/statistics.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace probecomp::geometry {
namespace {

// The sorted set's middle values: the upper median and the median.
std::pair<double, double> by_sorting(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t k = v.size() / 2;
  return {v[k], v.size() % 2 == 0 ? 0.5 * (v[k - 1] + v[k]) : v[k]};
}

void expect_medians(const std::vector<double>& values) {
  const auto [upper, median] = by_sorting(values);
  for (const int threads : {1, 2}) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    std::vector<double> a = values, b = values;
    EXPECT_EQ(upper_median_in_place(a), upper) << values.size() << " values, " << threads << " threads";
    EXPECT_EQ(median_in_place(b), median) << values.size() << " values, " << threads << " threads";
  }
}

TEST(Statistics, MediansAreTheSortedSetsMiddleValues) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (const std::size_t n : {1u, 2u, 1001u, 1000u, 131071u, 131072u, 131073u, 1000000u, 1000001u}) {
    std::vector<double> v(n);
    for (double& x : v) x = gauss(rng);
    expect_medians(v);
    // Ties: values on a coarse grid, many equal to the median.
    for (double& x : v) x = std::round(4.0 * x) / 4.0;
    expect_medians(v);
    // Sorted, and reversed.
    std::sort(v.begin(), v.end());
    expect_medians(v);
    std::reverse(v.begin(), v.end());
    expect_medians(v);
  }
}

TEST(Statistics, ALargeSetWhoseSpreadSampleMissesTheMedianStillGivesIt) {
  // 2^20 values, every 256th (where the sample of 4 096 looks) far below all the others: the sample's bracket
  // holds none of the middle values, and the selection falls back to all of them.
  const std::size_t n = std::size_t{1} << 20;
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = i % 256 == 0 ? -1e6 - static_cast<double>(i) : static_cast<double>((i * 7919) % n);
  expect_medians(v);
  // All values equal.
  expect_medians(std::vector<double>(300000, 2.5));
}

TEST(Statistics, RobustScaleIsTheNormalisedMedianAbsoluteResidual) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> gauss(0.0, 0.004);
  for (const std::size_t n : {5000u, 500000u}) {
    std::vector<double> r(n);
    for (double& x : r) x = gauss(rng);
    std::vector<double> a(r.size());
    for (std::size_t i = 0; i < r.size(); ++i) a[i] = std::abs(r[i]);
    const double expected = kMadToSigma * by_sorting(a).first;
    EXPECT_EQ(robust_scale(r, 0.0), expected);
    EXPECT_EQ(robust_scale(r, 1.0), 1.0);  // at least min_scale
    EXPECT_NEAR(expected, 0.004, 0.0002);  // consistent for Gaussian noise
  }
}

}  // namespace
}  // namespace probecomp::geometry
