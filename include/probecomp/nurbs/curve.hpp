#pragma once
// A rational B-spline (NURBS) curve C(u) = Σ N_{i,p}(u) w_i P_i / Σ N_{i,p}(u) w_i, stored as homogeneous
// control points Pw_i = (w_i P_i, w_i). Weights must be positive.

#include <vector>

#include "probecomp/nurbs/knot_vector.hpp"
#include "probecomp/geometry/types.hpp"

namespace probecomp::nurbs {

class Curve {
 public:
  // Throws InvalidGeometry if the counts disagree or a weight is not positive. Empty w: all ones.
  Curve(KnotVector U, const std::vector<Point3>& P, const std::vector<double>& w = {});
  Curve(KnotVector U, std::vector<HomogeneousPoint> Pw);

  [[nodiscard]] int degree() const { return U_.degree(); }
  [[nodiscard]] const KnotVector& knots() const { return U_; }
  [[nodiscard]] int num_control_points() const { return static_cast<int>(Pw_.size()); }
  [[nodiscard]] const std::vector<HomogeneousPoint>& homogeneous() const { return Pw_; }
  [[nodiscard]] Point3 control_point(int i) const;
  [[nodiscard]] double weight(int i) const { return Pw_[static_cast<std::size_t>(i)].w(); }

 private:
  KnotVector U_;
  std::vector<HomogeneousPoint> Pw_;
};

struct CurveD2 {
  Point3 C;
  Vector3 Cu;
  Vector3 Cuu;
};

[[nodiscard]] Point3 evaluate(const Curve& c, double u);
// A4.2 restricted to order 2: point, first and second derivatives.
[[nodiscard]] CurveD2 derivatives_d2(const Curve& c, double u);
// A5.1: insert u r times; the curve's shape and parametrisation are unchanged.
[[nodiscard]] Curve insert_knot(const Curve& c, double u, int r = 1);

}  // namespace probecomp::nurbs
