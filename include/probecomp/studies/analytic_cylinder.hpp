#pragma once
// The paper's analytic check of conventional compensation (§2.1, equations (1)–(4), Figs 3 and 5; DESIGN.md §1):
// a nominal circle of radius R about the origin, the actual circle displaced by dy along y. The probe travels
// along the nominal normal at angle θ (the line y = x·tan θ) until its centre is R + r from the actual centre
// (the raw point); conventional compensation moves it back by r along that normal; the error is the compensated
// point's signed distance from the actual circle (+ outside the material). Everything in closed form.

#include <Eigen/Core>
#include <vector>

namespace probecomp::studies {

struct CircleCase {
  double R = 10.0;  // nominal (and actual) radius, mm
  double r = 1.0;   // probe tip radius, mm
  double dy = 2.0;  // misalignment of the actual circle along y, mm
};

struct AnalyticTouch {
  double theta_deg = 0.0;
  Eigen::Vector2d raw = Eigen::Vector2d::Zero();          // probe centre, equations (1)–(2)
  Eigen::Vector2d compensated = Eigen::Vector2d::Zero();  // raw − r·(cos θ, sin θ)
  Eigen::Vector2d closest = Eigen::Vector2d::Zero();      // nearest point of the actual circle, equations (3)–(4)
  double error = 0.0;                                     // signed distance compensated → actual circle, mm
};

// Throws std::invalid_argument unless R > 0, r ≥ 0 and |dy| < R + r (the line must meet the offset circle).
[[nodiscard]] AnalyticTouch conventional_touch(const CircleCase& c, double theta_deg);

struct MaxError {
  double error = 0.0;      // mm, the largest |error| over θ ∈ [0°, 180°], with its sign
  double theta_deg = 0.0;  // where it occurs
};
// Sampled every 0.01° and refined by golden-section search about the best sample, to 1e-9°.
[[nodiscard]] MaxError max_conventional_error(const CircleCase& c);

// The Fig. 5 series: for each r/R and each dy, the largest error (R fixed).
struct Fig5Point {
  double r_over_R = 0.0, dy = 0.0;
  MaxError max;
};
[[nodiscard]] std::vector<Fig5Point> fig5_series(double R, const std::vector<double>& r_over_R,
                                                 const std::vector<double>& dy);

}  // namespace probecomp::studies
