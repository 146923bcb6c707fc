#include "probecomp/geometry/statistics.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace probecomp::geometry {

namespace {

// From this many values the order statistics below are found in parallel (a million residuals: nth_element takes
// 10-15 ms on one core, at every ICP step and three times in a face's fit).
constexpr std::size_t kParallelSelection = std::size_t{1} << 17;
// The sample that brackets the order statistic, and how far either side of its place in the sample the bracket
// reaches: 256 sample ranks, 8 times the standard deviation of where the statistic falls among 4 096 samples.
constexpr std::size_t kSample = 4096;
constexpr std::size_t kBracket = 256;
constexpr std::size_t kChunks = 64;  // fixed, so that the work does not depend on the thread count

// The (k − 1)-th and k-th smallest values (0-based; the first is the k-th when k = 0), exactly. Floyd and Rivest's
// selection (1975): two order statistics of a spread sample bracket the k-th value; the values between them are
// counted and gathered in parallel, and only they are selected among. When the bracket misses (never seen: 8
// standard deviations), all of them are, in place.
std::pair<double, double> select_parallel(std::span<double> values, std::size_t k) {
  const std::size_t n = values.size();
  std::vector<double> sample(kSample);
  for (std::size_t i = 0; i < kSample; ++i) sample[i] = values[i * n / kSample];
  std::sort(sample.begin(), sample.end());
  const std::size_t at = k * kSample / n;
  const double lo = sample[at > kBracket ? at - kBracket : 0];
  const double hi = sample[std::min(at + kBracket, kSample - 1)];
  struct Count {
    std::size_t below = 0, between = 0;
    double largest_below = -std::numeric_limits<double>::infinity();
  };
  std::array<Count, kChunks> counts{};
  tbb::parallel_for(std::size_t{0}, kChunks, [&](std::size_t c) {
    Count& count = counts[c];
    for (std::size_t i = n * c / kChunks; i < n * (c + 1) / kChunks; ++i) {
      const double v = values[i];
      if (v < lo) {
        ++count.below;
        count.largest_below = std::max(count.largest_below, v);
      } else if (v <= hi) {
        ++count.between;
      }
    }
  });
  std::array<std::size_t, kChunks + 1> offset{};
  std::size_t below = 0;
  double largest_below = -std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < kChunks; ++c) {
    below += counts[c].below;
    largest_below = std::max(largest_below, counts[c].largest_below);
    offset[c + 1] = offset[c] + counts[c].between;
  }
  if (k < below || k >= below + offset[kChunks]) {
    const auto kth = values.begin() + static_cast<std::ptrdiff_t>(k);
    std::nth_element(values.begin(), kth, values.end());
    return {k > 0 ? *std::max_element(values.begin(), kth) : *kth, *kth};
  }
  std::vector<double> between(offset[kChunks]);
  tbb::parallel_for(std::size_t{0}, kChunks, [&](std::size_t c) {
    std::size_t to = offset[c];
    for (std::size_t i = n * c / kChunks; i < n * (c + 1) / kChunks; ++i) {
      if (values[i] >= lo && values[i] <= hi) between[to++] = values[i];
    }
  });
  const auto kth = between.begin() + static_cast<std::ptrdiff_t>(k - below);
  std::nth_element(between.begin(), kth, between.end());
  const double before = k == 0 ? *kth : kth != between.begin() ? *std::max_element(between.begin(), kth) : largest_below;
  return {before, *kth};
}

}  // namespace

double upper_median_in_place(std::span<double> values) {
  if (values.empty()) return 0.0;
  if (values.size() >= kParallelSelection) return select_parallel(values, values.size() / 2).second;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

double median_in_place(std::span<double> values) {
  if (values.empty()) return 0.0;
  if (values.size() >= kParallelSelection) {
    const auto [lower, upper] = select_parallel(values, values.size() / 2);
    return values.size() % 2 == 0 ? 0.5 * (upper + lower) : upper;
  }
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  double m = *mid;
  // After nth_element every value before `mid` is at most *mid: the lower middle value is their largest.
  if (values.size() % 2 == 0) m = 0.5 * (m + *std::max_element(values.begin(), mid));
  return m;
}

double robust_scale(std::span<const double> residuals, double min_scale) {
  std::vector<double> a(residuals.begin(), residuals.end());
  return robust_scale_in_place(a, min_scale);
}

double robust_scale_in_place(std::span<double> residuals, double min_scale) {
  if (residuals.empty()) return min_scale;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, residuals.size(), std::size_t{1} << 16), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) residuals[i] = std::abs(residuals[i]);
  });
  return std::max(kMadToSigma * upper_median_in_place(residuals), min_scale);
}

double normal_upper_quantile(double alpha) {
  const double t = std::sqrt(-2.0 * std::log(alpha));
  const double numerator = 2.515517 + 0.802853 * t + 0.010328 * t * t;
  const double denominator = 1.0 + 1.432788 * t + 0.189269 * t * t + 0.001308 * t * t * t;
  return t - numerator / denominator;
}

double chi2_upper_quantile(double n, double alpha) {
  const double h = 2.0 / (9.0 * n);
  const double c = 1.0 - h + normal_upper_quantile(alpha) * std::sqrt(h);
  return n * c * c * c;
}

}  // namespace probecomp::geometry
