// Least-squares planes, spheres and cylinders: exact on exact data, refusing data that do not fix the element,
// and on NIST-style reference data (selftest::reference_elements) the known element; plus an optimality check that
// uses only distances: no small change of the fitted element lowers the sum of squares.

#include "probecomp/fitting/elements.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "probecomp/selftest/reference_elements.hpp"
#include "probecomp/simulation/random.hpp"

namespace probecomp::fitting {
namespace {

double angle(const Vector3& a, const Vector3& b) { return std::atan2(a.cross(b).norm(), std::abs(a.dot(b))); }

TEST(ElementFits, ExactDataGiveTheElement) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  const Point3 c(3, -4, 12);
  const Vector3 a = Vector3(1, -2, 0.5).normalized(), s = a.unitOrthogonal(), q = a.cross(s);
  std::vector<Point3> sphere, cylinder, plane;
  for (int k = 0; k < 30; ++k) {
    const double phi = 2.0 * std::numbers::pi * t(rng), z = 2.0 * t(rng) - 1.0, rho = std::sqrt(1 - z * z);
    sphere.push_back(c + 7.0 * (rho * std::cos(phi) * s + rho * std::sin(phi) * q + z * a));
    cylinder.push_back(c + 30.0 * t(rng) * a + 4.0 * (std::cos(phi) * s + std::sin(phi) * q));
    const double along_q = t(rng), along_s = t(rng);  // as gcc drew them in one expression, last term first
    plane.push_back(c + 50.0 * along_s * s + 20.0 * along_q * q);
  }
  const SphereFit fs = fit_sphere(sphere);
  ASSERT_EQ(fs.status, ElementFitStatus::OK);
  EXPECT_LT((fs.center - c).norm(), 1e-12);
  EXPECT_NEAR(fs.radius, 7.0, 1e-12);
  EXPECT_LT(fs.rms, 1e-12);
  const CylinderFit fc = fit_cylinder(cylinder);
  ASSERT_EQ(fc.status, ElementFitStatus::OK);
  EXPECT_LT(angle(fc.axis, a), 1e-13);
  const Vector3 off = c - fc.axis_point;
  EXPECT_LT((off - off.dot(fc.axis) * fc.axis).norm(), 1e-12);
  EXPECT_NEAR(fc.radius, 4.0, 1e-12);
  const PlaneFit fp = fit_plane(plane);
  ASSERT_EQ(fp.status, ElementFitStatus::OK);
  EXPECT_LT(angle(fp.normal, a), 1e-13);
  EXPECT_LT(std::abs(fp.normal.dot(c - fp.point)), 1e-12);
}

TEST(ElementFits, DataThatDoNotFixTheElementAreDegenerate) {
  std::vector<Point3> line, flat;
  for (int k = 0; k < 10; ++k) {
    line.emplace_back(k, 2.0 * k, -k);
    flat.emplace_back(std::cos(k), std::sin(k), 0.0);  // a circle: one plane, many spheres
  }
  EXPECT_EQ(fit_plane(line).status, ElementFitStatus::Degenerate);
  EXPECT_EQ(fit_sphere(flat).status, ElementFitStatus::Degenerate);
  EXPECT_EQ(fit_plane(std::vector<Point3>{{0, 0, 0}, {1, 0, 0}}).status, ElementFitStatus::Degenerate);
  EXPECT_EQ(fit_sphere(std::vector<Point3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}).status, ElementFitStatus::Degenerate);
  EXPECT_EQ(fit_cylinder(std::vector<Point3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}).status, ElementFitStatus::Degenerate);
}

TEST(ElementFits, ReferenceDataGiveTheirKnownElement) {
  for (const selftest::ReferenceElement& e : selftest::reference_elements()) {
    SCOPED_TRACE(e.name);
    switch (e.kind) {
      case selftest::ElementKind::Plane: {
        const PlaneFit f = fit_plane(e.points);
        ASSERT_EQ(f.status, ElementFitStatus::OK);
        EXPECT_LT(angle(f.normal, e.direction), 1e-12);
        EXPECT_LT(std::abs(f.normal.dot(e.point - f.point)), 1e-10);
        EXPECT_NEAR(f.rms, e.rms, 1e-12);
        break;
      }
      case selftest::ElementKind::Sphere: {
        const SphereFit f = fit_sphere(e.points);
        ASSERT_EQ(f.status, ElementFitStatus::OK);
        EXPECT_LT((f.center - e.point).norm(), 1e-10);
        EXPECT_NEAR(f.radius, e.radius, 1e-10);
        EXPECT_NEAR(f.rms, e.rms, 1e-12);
        EXPECT_LT(f.iterations, 20);
        break;
      }
      case selftest::ElementKind::Cylinder: {
        const CylinderFit f = fit_cylinder(e.points);
        ASSERT_EQ(f.status, ElementFitStatus::OK);
        EXPECT_LT(angle(f.axis, e.direction), 1e-12);
        const Vector3 off = e.point - f.axis_point;
        EXPECT_LT((off - off.dot(f.axis) * f.axis).norm(), 1e-10);
        EXPECT_NEAR(f.radius, e.radius, 1e-10);
        EXPECT_NEAR(f.rms, e.rms, 1e-12);
        EXPECT_LT(f.iterations, 20);
        break;
      }
    }
  }
}

// Sum of squared distances to a cylinder, from the distances alone.
double cylinder_ss(const std::vector<Point3>& x, const Point3& p, const Vector3& axis, double r) {
  const Vector3 a = axis.normalized();
  double ss = 0.0;
  for (const Point3& y : x) {
    const Vector3 d = y - p;
    ss += std::pow((d - d.dot(a) * a).norm() - r, 2);
  }
  return ss;
}

TEST(ElementFits, NoSmallChangeOfTheFittedCylinderLowersTheSumOfSquares) {
  // Noisy points on a 100 degree arc: the fit must be a minimum of Σ d², checked by moving each parameter.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.005);
  const Point3 c(40, 10, -5);
  const Vector3 a = Vector3(0.3, 1, 0.2).normalized(), s = a.unitOrthogonal(), q = a.cross(s);
  std::vector<Point3> x;
  for (int k = 0; k < 80; ++k) {
    const double phi = 1.745 * t(rng);
    // Drawn in the order gcc drew them in one expression, last term first.
    const Vector3 e = simulation::draw_vector(noise, rng);
    const double radius = 15.0 + noise(rng), along = 25.0 * t(rng);
    x.push_back(c + along * a + radius * (std::cos(phi) * s + std::sin(phi) * q) + e);
  }
  const CylinderFit f = fit_cylinder(x);
  ASSERT_EQ(f.status, ElementFitStatus::OK);
  const double best = cylinder_ss(x, f.axis_point, f.axis, f.radius);
  EXPECT_NEAR(std::sqrt(best / x.size()), f.rms, 1e-12);
  const Vector3 u = f.axis.unitOrthogonal(), w = f.axis.cross(u);
  for (const double h : {1e-4, 1e-3}) {
    for (const double sign : {-1.0, 1.0}) {
      EXPECT_GE(cylinder_ss(x, f.axis_point + sign * h * u, f.axis, f.radius), best);
      EXPECT_GE(cylinder_ss(x, f.axis_point + sign * h * w, f.axis, f.radius), best);
      EXPECT_GE(cylinder_ss(x, f.axis_point, f.axis + sign * h * u, f.radius), best);
      EXPECT_GE(cylinder_ss(x, f.axis_point, f.axis + sign * h * w, f.radius), best);
      EXPECT_GE(cylinder_ss(x, f.axis_point, f.axis, f.radius + sign * h), best);
    }
  }
}

}  // namespace
}  // namespace probecomp::fitting
