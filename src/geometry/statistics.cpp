#include "probecomp/geometry/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace probecomp::geometry {

double upper_median_in_place(std::span<double> values) {
  if (values.empty()) return 0.0;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

double median_in_place(std::span<double> values) {
  if (values.empty()) return 0.0;
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
  for (double& r : residuals) r = std::abs(r);
  return std::max(kMadToSigma * upper_median_in_place(residuals), min_scale);
}

}  // namespace probecomp::geometry
