#pragma once
// A face's trimming: the part of its surface's parameter domain that belongs to the face, bounded by closed
// loops of boundary curves in (u, v) (pcurves; the outer loop and any holes).
//
// Membership uses polygons sampled from the boundary curves (even-odd rule, so loop orientation does not
// matter); points on the face's boundary itself come from the exact curves (see TrimmedFace).

#include <vector>

#include "probecomp/nurbs/closest_point.hpp"
#include "probecomp/nurbs/curve.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::cad {

// A boundary curve in the parameter plane: (x, y) of the curve are (u, v); z is zero.
struct BoundaryCurve {
  nurbs::Curve uv;
  std::vector<double> t;  // sample parameters along the curve, first to last knot
  bool reversed = false;  // the face's boundary runs along the curve from its last knot to its first
};

class Trim final : public nurbs::ParameterRegion {
 public:
  Trim() = default;
  // `curves` must form closed loops in the parameter plane; each has its sample parameters filled in.
  explicit Trim(std::vector<BoundaryCurve> curves);

  [[nodiscard]] bool contains(double u, double v) const override;
  [[nodiscard]] bool meets(const nurbs::Domain& box) const override;

  [[nodiscard]] const std::vector<BoundaryCurve>& curves() const { return curves_; }
  [[nodiscard]] bool empty() const { return curves_.empty(); }
  // The smallest parameter box holding the boundary polygons.
  [[nodiscard]] nurbs::Domain parameter_bounds() const;
  // The area enclosed in the parameter plane (holes subtracted).
  [[nodiscard]] double parameter_area() const;

 private:
  struct Segment {
    double u0, v0, u1, v1;
  };
  void close_loops();
  std::vector<BoundaryCurve> curves_;
  std::vector<Segment> segments_;
  // Segments grouped by horizontal band of v, so a membership test only crosses the segments of its band.
  double v_min_ = 0.0, v_max_ = 0.0, band_height_ = 1.0;
  std::vector<std::vector<std::uint32_t>> bands_;
};

// Sample parameters for a boundary curve, bisected until every chord is within `chord_tolerance` of the
// curve at its middle (parameter units), starting from a few samples per knot span.
[[nodiscard]] std::vector<double> boundary_samples(const nurbs::Curve& uv, double chord_tolerance);

}  // namespace probecomp::cad
