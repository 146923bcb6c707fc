// The reference data really have their stated least-squares element: at it, the gradient of Σ d_i² in every
// parameter is zero. Checked by central differences of the distances themselves, not with the Jacobian the data
// were made with.

#include "probecomp/selftest/reference_elements.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

namespace probecomp::selftest {
namespace {

double sum_of_squares(const ReferenceElement& e, const Point3& p, const Vector3& dir, double r) {
  double ss = 0.0;
  for (const Point3& x : e.points) {
    const Vector3 d = x - p;
    double dist = 0.0;
    switch (e.kind) {
      case ElementKind::Plane: dist = d.dot(dir.normalized()); break;
      case ElementKind::Sphere: dist = d.norm() - r; break;
      case ElementKind::Cylinder: {
        const Vector3 a = dir.normalized();
        dist = (d - d.dot(a) * a).norm() - r;
        break;
      }
    }
    ss += dist * dist;
  }
  return ss;
}

TEST(ReferenceElements, TheStatedElementIsAStationaryPointOfTheSumOfSquares) {
  for (const ReferenceElement& e : reference_elements()) {
    SCOPED_TRACE(e.name);
    ASSERT_GE(e.points.size(), 40u);
    const double ss = sum_of_squares(e, e.point, e.direction, e.radius);
    EXPECT_NEAR(std::sqrt(ss / e.points.size()), e.rms, 1e-12);
    const Vector3 u = e.direction.norm() > 0 ? e.direction.unitOrthogonal() : Vector3::UnitX();
    const Vector3 w = e.direction.norm() > 0 ? e.direction.cross(u) : Vector3::UnitY();
    // Moves of the position, the direction (tilts) and the radius by h = 1e-4 of a unit; central differences at h and
    // h/2 extrapolated (Richardson), which removes the h² error that a tilt's far-reaching effect would leave.
    // The gradient's scale: √(n Σ d_i²) times the data's size, what one unit of move could change it by.
    constexpr double h = 1e-4;
    std::vector<std::function<double(double)>> moves = {
        [&](double s) { return sum_of_squares(e, e.point + s * Vector3::UnitX(), e.direction, e.radius); },
        [&](double s) { return sum_of_squares(e, e.point + s * Vector3::UnitY(), e.direction, e.radius); },
        [&](double s) { return sum_of_squares(e, e.point + s * Vector3::UnitZ(), e.direction, e.radius); },
    };
    if (e.kind != ElementKind::Sphere) {
      moves.push_back([&](double s) { return sum_of_squares(e, e.point, e.direction + s * u, e.radius); });
      moves.push_back([&](double s) { return sum_of_squares(e, e.point, e.direction + s * w, e.radius); });
    }
    if (e.kind != ElementKind::Plane) {
      moves.push_back([&](double s) { return sum_of_squares(e, e.point, e.direction, e.radius + s); });
    }
    double size = 0.0;
    for (const Point3& x : e.points) size = std::max(size, (x - e.point).norm());
    const double scale = 2.0 * std::sqrt(ss * e.points.size()) * size;
    for (std::size_t k = 0; k < moves.size(); ++k) {
      const double at_h = (moves[k](h) - moves[k](-h)) / (2.0 * h);
      const double at_half = (moves[k](h / 2) - moves[k](-h / 2)) / h;
      const double gradient = (4.0 * at_half - at_h) / 3.0;
      EXPECT_LT(std::abs(gradient), 1e-7 * scale) << "parameter " << k;
      // And a minimum, not a saddle: both moves raise the sum.
      EXPECT_GT(moves[k](h), ss) << "parameter " << k;
      EXPECT_GT(moves[k](-h), ss) << "parameter " << k;
    }
  }
}

}  // namespace
}  // namespace probecomp::selftest
