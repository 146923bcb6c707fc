#include "probecomp/studies/analytic_cylinder.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "probecomp/error.hpp"
#include "probecomp/geometry/types.hpp"

namespace probecomp::studies {

namespace {

constexpr double kSampleStepDeg = 0.01;
constexpr double kAngleToleranceDeg = 1e-9;

}  // namespace

AnalyticTouch conventional_touch(const CircleCase& c, double theta_deg) {
  if (!(c.R > 0.0) || !(c.r >= 0.0) || !(std::abs(c.dy) < c.R + c.r)) {
    throw InputError("analytic cylinder: need R > 0, r >= 0 and |dy| < R + r");
  }
  AnalyticTouch out;
  out.theta_deg = theta_deg;
  const Eigen::Vector2d d(std::cos(theta_deg * kDegree), std::sin(theta_deg * kDegree));
  const Eigen::Vector2d centre(0.0, c.dy);
  // (1)–(2): |t·d − (0, dy)|² = (R + r)², i.e. t² − 2t·dy·sin θ + dy² − (R + r)² = 0. Since |dy| < R + r the
  // constant term is negative, so exactly one root is positive: the probe comes in from outside.
  const double b = c.dy * d.y();
  const double t = b + std::sqrt(b * b - c.dy * c.dy + (c.R + c.r) * (c.R + c.r));
  out.raw = t * d;
  out.compensated = out.raw - c.r * d;
  // (3)–(4): the nearest point of a circle lies on the line through its centre.
  const Eigen::Vector2d from_centre = out.compensated - centre;
  const double rho = from_centre.norm();
  out.closest = rho > 0.0 ? Eigen::Vector2d(centre + c.R * from_centre / rho) : Eigen::Vector2d(centre + Eigen::Vector2d(c.R, 0.0));
  out.error = rho - c.R;
  return out;
}

MaxError max_conventional_error(const CircleCase& c) {
  auto size = [&](double theta) { return std::abs(conventional_touch(c, theta).error); };
  const int n = static_cast<int>(std::lround(180.0 / kSampleStepDeg));
  int best = 0;
  double best_size = -1.0;
  for (int k = 0; k <= n; ++k) {
    const double s = size(k * kSampleStepDeg);
    if (s > best_size) {
      best_size = s;
      best = k;
    }
  }
  // Golden-section search for the maximum within one sample step either side (clamped to [0°, 180°]).
  double a = std::max(0.0, (best - 1) * kSampleStepDeg), b = std::min(180.0, (best + 1) * kSampleStepDeg);
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = size(x1), f2 = size(x2);
  while (b - a > kAngleToleranceDeg) {
    if (f1 > f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - g * (b - a);
      f1 = size(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + g * (b - a);
      f2 = size(x2);
    }
  }
  double theta = (a + b) / 2.0;
  // The ends of the range are candidates too (the maximum is often at θ = 0° or 180°).
  for (double end : {0.0, 180.0, best * kSampleStepDeg}) {
    if (size(end) >= size(theta)) theta = end;
  }
  return {conventional_touch(c, theta).error, theta};
}

std::vector<Fig5Point> fig5_series(double R, const std::vector<double>& r_over_R, const std::vector<double>& dy) {
  std::vector<Fig5Point> out;
  for (double ratio : r_over_R) {
    for (double d : dy) out.push_back({ratio, d, max_conventional_error({.R = R, .r = ratio * R, .dy = d})});
  }
  return out;
}

}  // namespace probecomp::studies
