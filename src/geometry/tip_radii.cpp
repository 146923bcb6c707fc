#include "probecomp/geometry/tip_radii.hpp"

#include <algorithm>

namespace probecomp::geometry {

TipRadii::TipRadii(double every_point) : smallest_(every_point), largest_(every_point) {}

TipRadii::TipRadii(std::vector<double> per_point) {
  if (per_point.empty()) return;
  const auto [lo, hi] = std::minmax_element(per_point.begin(), per_point.end());
  smallest_ = *lo;
  largest_ = *hi;
  if (smallest_ != largest_) per_point_ = std::move(per_point);
}

std::vector<double> TipRadii::beyond_smallest() const {
  std::vector<double> out(per_point_.size());
  for (std::size_t k = 0; k < per_point_.size(); ++k) out[k] = per_point_[k] - smallest_;
  return out;
}

TipRadii TipRadii::subset(std::span<const std::size_t> points) const {
  if (per_point_.empty()) return *this;
  std::vector<double> out(points.size());
  for (std::size_t k = 0; k < points.size(); ++k) out[k] = per_point_[points[k]];
  return TipRadii(std::move(out));
}

}  // namespace probecomp::geometry
