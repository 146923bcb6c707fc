#pragma once
// The probe tip radius of each measured point, mm: one for every point, or one per point when a run mixes styli
// (a CSV column r, DMIS sensors, QIF ProbeRadii). The model is offset by the smallest of them: the centre of a
// larger tip touching the same surface point sits farther out along the surface normal by the difference, exactly
// wherever both offsets are regular (the closest point of an offset surface does not depend on the offset).

#include <cstddef>
#include <span>
#include <vector>

namespace probecomp::geometry {

class TipRadii {
 public:
  TipRadii() = default;
  // Every point's (implicit: one radius for the whole run is the usual case).
  TipRadii(double every_point);  // NOLINT(google-explicit-constructor)
  // One per point; stored as one radius when they are all equal.
  explicit TipRadii(std::vector<double> per_point);

  [[nodiscard]] double operator[](std::size_t point) const { return per_point_.empty() ? smallest_ : per_point_[point]; }
  [[nodiscard]] double smallest() const { return smallest_; }
  [[nodiscard]] double largest() const { return largest_; }
  [[nodiscard]] bool uniform() const { return per_point_.empty(); }
  // Points with a radius of their own: 0 when uniform.
  [[nodiscard]] std::size_t count() const { return per_point_.size(); }
  // Per point, how much farther out its centre sits than a tip of the smallest radius would: r − smallest(). Empty
  // when every point has the same radius.
  [[nodiscard]] std::vector<double> beyond_smallest() const;
  // Those of `points`, in that order.
  [[nodiscard]] TipRadii subset(std::span<const std::size_t> points) const;

 private:
  double smallest_ = 0.0, largest_ = 0.0;
  std::vector<double> per_point_;  // empty when uniform
};

}  // namespace probecomp::geometry
