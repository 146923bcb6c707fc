// Least-squares planes, spheres, cylinders, cones and tori: exact on exact data, refusing data that do not fix the
// element, and on NIST-style reference data (selftest::reference_elements) the known element; plus an optimality
// check that uses only distances (computed here, not by the code under test): no small change of the fitted element
// lowers the sum of squares.

#include "probecomp/fitting/elements.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
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

// Points of a cone and a torus from their parametric form (not from a distance), far from the origin and tilted.
struct Frame {
  Point3 c;
  Vector3 a, s, q;
  Frame(const Point3& centre, const Vector3& axis)
      : c(centre), a(axis.normalized()), s(a.unitOrthogonal()), q(a.cross(s)) {}
  [[nodiscard]] Vector3 radial(double phi) const { return std::cos(phi) * s + std::sin(phi) * q; }
};

// Cone: radius r0 at the axis point c, growing along a at the half-angle alpha.
Point3 on_cone(const Frame& f, double r0, double alpha, double phi, double h) {
  return f.c + (r0 + h * std::tan(alpha)) * f.radial(phi) + h * f.a;
}
Point3 on_torus(const Frame& f, double R, double r, double u, double v) {
  return f.c + (R + r * std::cos(v)) * f.radial(u) + r * std::sin(v) * f.a;
}

// Σ d² in the meridian half-plane (ρ, h): the cone's generator through (r0, 0) along (sin α, cos α), the torus's
// tube circle about (R, 0).
double cone_ss(const std::vector<Point3>& x, const Point3& p, const Vector3& axis, double r0, double alpha) {
  const Vector3 a = axis.normalized();
  double ss = 0.0;
  for (const Point3& y : x) {
    const double h = (y - p).dot(a), rho = ((y - p) - h * a).norm();
    const double d = (rho - r0) * std::cos(alpha) - h * std::sin(alpha);
    ss += d * d;
  }
  return ss;
}
double torus_ss(const std::vector<Point3>& x, const Point3& c, const Vector3& axis, double R, double r) {
  const Vector3 a = axis.normalized();
  double ss = 0.0;
  for (const Point3& y : x) {
    const double h = (y - c).dot(a), rho = ((y - c) - h * a).norm();
    const double d = std::hypot(rho - R, h) - r;
    ss += d * d;
  }
  return ss;
}

TEST(ElementFits, ConesAndToriFromANearbyStartAreExactOnExactData) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  // A widening cone (a boss's taper) and a narrowing one (a countersink along its axis), on 120° of their turn.
  for (const double alpha : {25.0 * std::numbers::pi / 180, -30.0 * std::numbers::pi / 180}) {
    SCOPED_TRACE(alpha);
    const Frame f(Point3(250, -120, 60), Vector3(0.2, -0.4, 1.0));
    std::vector<Point3> x;
    for (int k = 0; k < 40; ++k) {
      const double phi = 2.1 * t(rng);
      const double h = -4.0 + 10.0 * t(rng);
      x.push_back(on_cone(f, 12.0, alpha, phi, h));
    }
    // The start: axis 1° off, 0.3 mm aside and at another height, radius 0.05 mm and angle 0.6° off.
    ConeFit start;
    start.axis = (f.a + 0.0175 * f.s).normalized();
    start.axis_point = f.c + 0.3 * f.s + 2.0 * f.a;
    start.radius = 12.0 + 2.0 * std::tan(alpha) + 0.05;
    start.half_angle = alpha + 0.01;
    const ConeFit cone = fit_cone(x, start);
    ASSERT_EQ(cone.status, ElementFitStatus::OK);
    EXPECT_LT(angle(cone.axis, f.a), 1e-11);
    EXPECT_GT(cone.axis.dot(f.a), 0.0);
    const Vector3 off = f.c - cone.axis_point;
    const double h = off.dot(cone.axis);
    EXPECT_LT((off - h * cone.axis).norm(), 1e-9);
    EXPECT_NEAR(cone.radius + h * std::tan(cone.half_angle), 12.0, 1e-9);
    EXPECT_NEAR(cone.half_angle, alpha, 1e-11);
    EXPECT_LT(cone.rms, 1e-10);
    for (const Point3& y : x) EXPECT_NEAR(distance(cone, y), 0.0, 1e-9);
    EXPECT_NEAR(distance(cone, x[0] + 0.01 * (x[0] - cone.axis_point).cross(cone.axis).cross(cone.axis).normalized()),
                -0.01 * std::cos(alpha), 1e-6);  // toward the axis: inside
  }
  // A torus (a fillet's) on a quarter of its tube and 100° of its turn.
  const Frame f(Point3(-80, 40, 300), Vector3(-0.3, 0.1, 1.0));
  std::vector<Point3> x;
  for (int k = 0; k < 40; ++k) {
    const double u = 1.75 * t(rng);
    const double v = -0.2 + 1.6 * t(rng);
    x.push_back(on_torus(f, 30.0, 5.0, u, v));
  }
  TorusFit start;
  start.axis = (f.a + 0.0175 * f.q).normalized();
  start.center = f.c + Vector3(0.2, -0.1, 0.15);
  start.radius = 30.05;
  start.minor_radius = 4.95;
  const TorusFit torus = fit_torus(x, start);
  ASSERT_EQ(torus.status, ElementFitStatus::OK);
  EXPECT_LT(angle(torus.axis, f.a), 1e-11);
  EXPECT_LT((torus.center - f.c).norm(), 1e-9);
  EXPECT_NEAR(torus.radius, 30.0, 1e-9);
  EXPECT_NEAR(torus.minor_radius, 5.0, 1e-9);
  EXPECT_LT(torus.rms, 1e-10);
  for (const Point3& y : x) EXPECT_NEAR(distance(torus, y), 0.0, 1e-9);
}

TEST(ElementFits, ConesAndToriThatThePointsDoNotFixAreDegenerate) {
  const Frame f(Point3(5, 6, 7), Vector3(0, 0.3, 1));
  std::vector<Point3> ring, equator;
  for (int k = 0; k < 20; ++k) {
    ring.push_back(on_cone(f, 10.0, 0.4, 0.3 * k, 0.0));       // one height: the angle trades for the radius
    equator.push_back(on_torus(f, 30.0, 5.0, 0.3 * k, 0.0));   // the tube's outer equator: R + r alone is fixed
  }
  const ConeFit cone{.axis_point = f.c, .axis = f.a, .radius = 10.0, .half_angle = 0.4};
  const TorusFit torus{.center = f.c, .axis = f.a, .radius = 30.0, .minor_radius = 5.0};
  EXPECT_EQ(fit_cone(ring, cone).status, ElementFitStatus::Degenerate);
  EXPECT_EQ(fit_torus(equator, torus).status, ElementFitStatus::Degenerate);
  EXPECT_EQ(fit_cone(std::vector<Point3>(ring.begin(), ring.begin() + 5), cone).status, ElementFitStatus::Degenerate);
  EXPECT_EQ(fit_torus(std::vector<Point3>(ring.begin(), ring.begin() + 6), torus).status, ElementFitStatus::Degenerate);
}

// Held at the start: the combinations the points do not fix stay as started, the rest is fitted (the least-squares
// step of smallest size from the start, a closed form here), and the fit is OK where it was Degenerate.
TEST(ElementFits, WhatThePointsDoNotFixIsHeldAtTheStart) {
  const Frame f(Point3(5, 6, 7), Vector3(0, 0.3, 1));
  std::vector<Point3> ring, equator;
  for (int k = 0; k < 20; ++k) {
    ring.push_back(on_cone(f, 10.0, 0.4, 0.3 * k, 0.0));
    equator.push_back(on_torus(f, 30.0, 5.0, 0.3 * k, 0.0));
  }
  const HoldPoorlyFixed limits{.sigma = 0.002, .max_std = 0.025};
  // The equator fixes the centre across the axis and R + r; not the centre along the axis, the tilt, nor R − r.
  // Started with R 0.05 mm off, the smallest step that fits takes half of it from R and half from r.
  const TorusFit torus = fit_torus(equator, {.center = f.c, .axis = f.a, .radius = 30.05, .minor_radius = 5.0}, limits);
  ASSERT_EQ(torus.status, ElementFitStatus::OK);
  EXPECT_EQ(torus.held, 4);
  EXPECT_NEAR(torus.radius, 30.025, 1e-9);
  EXPECT_NEAR(torus.minor_radius, 4.975, 1e-9);
  EXPECT_LT((torus.center - f.c).norm(), 1e-9);
  EXPECT_LT(angle(torus.axis, f.a), 1e-12);
  for (const Point3& y : equator) EXPECT_NEAR(distance(torus, y), 0.0, 1e-9);
  // One ring of a cone fixes its radius there, the axis's place and tilt together (one combination of each pair),
  // not the angle: started 0.01 rad off, it stays there, and the radius at the ring is fitted. (The first step is
  // taken where the start's radius is off by 0.05 mm, and there the angle and the radius are not quite apart: the
  // angle moves by 1e-5 rad with it.)
  const ConeFit cone = fit_cone(ring, {.axis_point = f.c, .axis = f.a, .radius = 10.05, .half_angle = 0.41}, limits);
  ASSERT_EQ(cone.status, ElementFitStatus::OK);
  EXPECT_EQ(cone.held, 3);
  EXPECT_NEAR(cone.half_angle, 0.41, 2e-5);
  const ConeFit exact = fit_cone(ring, {.axis_point = f.c, .axis = f.a, .radius = 10.0, .half_angle = 0.41}, limits);
  ASSERT_EQ(exact.status, ElementFitStatus::OK);
  EXPECT_NEAR(exact.half_angle, 0.41, 1e-12);
  const double h = (f.c - cone.axis_point).dot(cone.axis);
  EXPECT_NEAR(cone.radius + h * std::tan(cone.half_angle), 10.0, 1e-9);
  for (const Point3& y : ring) EXPECT_NEAR(distance(cone, y), 0.0, 1e-9);
  // Points that fix everything: held nothing, the same fit as without limits.
  std::vector<Point3> tube;
  for (int k = 0; k < 40; ++k) tube.push_back(on_torus(f, 30.0, 5.0, 0.15 * k, 0.37 * k));
  const TorusFit start{.center = f.c + Vector3(0.1, 0, 0), .axis = f.a, .radius = 30.05, .minor_radius = 5.0};
  const TorusFit held = fit_torus(tube, start, limits), free = fit_torus(tube, start);
  ASSERT_EQ(held.status, ElementFitStatus::OK);
  EXPECT_EQ(held.held, 0);
  EXPECT_NEAR(held.radius, 30.0, 1e-9);
  EXPECT_NEAR(held.minor_radius, free.minor_radius, 1e-12);
}

// Twelve touches on a short arc of a fillet, σ = 2 µm, over seeds: its radius and its centre's place trade, and
// fitted free the radius wanders. Held, every fit is OK, its radius stays near the truth, and its surface passes
// within a few σ of the true points.
TEST(ElementFits, AShortArcOfAFilletHoldsItsRadiusAndFollowsItsPoints) {
  const Frame f(Point3(-40, 20, 10), Vector3(0.1, -0.2, 1));
  const double R = 20.0, r = 3.0, sigma = 0.002;
  std::normal_distribution<double> noise(0.0, sigma);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  double worst_radius = 0.0, worst_free_radius = 0.0, worst_distance = 0.0;
  for (int seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
    std::vector<Point3> truth, measured;
    for (int k = 0; k < 12; ++k) {
      const double u = 0.3 * t(rng);
      const double v = 0.5 * t(rng);
      truth.push_back(on_torus(f, R, r, u, v));
      measured.push_back(truth.back() + simulation::draw_vector(noise, rng));
    }
    const TorusFit start{.center = f.c, .axis = f.a, .radius = R, .minor_radius = r};
    const TorusFit held = fit_torus(measured, start, {.sigma = sigma, .max_std = 0.025});
    ASSERT_EQ(held.status, ElementFitStatus::OK) << "seed " << seed;
    EXPECT_GE(held.held, 1);
    worst_radius = std::max(worst_radius, std::abs(held.radius - R));
    for (const Point3& y : truth) worst_distance = std::max(worst_distance, std::abs(distance(held, y)));
    const TorusFit free = fit_torus(measured, start);
    if (free.status == ElementFitStatus::OK) worst_free_radius = std::max(worst_free_radius, std::abs(free.radius - R));
  }
  std::printf("largest radius error held %.4f mm, free %.4f mm; largest distance of a true point from the held fit "
              "%.2f um\n", worst_radius, worst_free_radius, worst_distance * 1e3);
  EXPECT_LT(worst_radius, 0.1);           // 4 of the fitted combinations' largest standard deviation
  EXPECT_LT(worst_distance, 3.0 * sigma);
}

TEST(ElementFits, NoSmallChangeOfTheFittedConeOrTorusLowersTheSumOfSquares) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.005);
  const Frame f(Point3(40, 10, -5), Vector3(0.3, 1, 0.2));
  std::vector<Point3> cone_points, torus_points;
  for (int k = 0; k < 60; ++k) {
    const double phi = 1.8 * t(rng);
    const double h = 8.0 * t(rng);
    cone_points.push_back(on_cone(f, 9.0, 0.5, phi, h) + simulation::draw_vector(noise, rng));
    const double u = 1.8 * t(rng);
    const double v = 1.6 * t(rng);
    torus_points.push_back(on_torus(f, 25.0, 4.0, u, v) + simulation::draw_vector(noise, rng));
  }
  const ConeFit cone = fit_cone(cone_points, {.axis_point = f.c, .axis = f.a, .radius = 9.0, .half_angle = 0.5});
  ASSERT_EQ(cone.status, ElementFitStatus::OK);
  const double cone_best = cone_ss(cone_points, cone.axis_point, cone.axis, cone.radius, cone.half_angle);
  EXPECT_NEAR(std::sqrt(cone_best / cone_points.size()), cone.rms, 1e-12);
  const TorusFit torus = fit_torus(torus_points, {.center = f.c, .axis = f.a, .radius = 25.0, .minor_radius = 4.0});
  ASSERT_EQ(torus.status, ElementFitStatus::OK);
  const double torus_best = torus_ss(torus_points, torus.center, torus.axis, torus.radius, torus.minor_radius);
  EXPECT_NEAR(std::sqrt(torus_best / torus_points.size()), torus.rms, 1e-12);
  const Vector3 cu = cone.axis.unitOrthogonal(), cw = cone.axis.cross(cu);
  const Vector3 tu = torus.axis.unitOrthogonal(), tw = torus.axis.cross(tu);
  for (const double h : {1e-4, 1e-3}) {
    for (const double sign : {-1.0, 1.0}) {
      const double e = sign * h;
      const Point3& p = cone.axis_point;
      EXPECT_GE(cone_ss(cone_points, p + e * cu, cone.axis, cone.radius, cone.half_angle), cone_best);
      EXPECT_GE(cone_ss(cone_points, p + e * cw, cone.axis, cone.radius, cone.half_angle), cone_best);
      EXPECT_GE(cone_ss(cone_points, p, cone.axis + e * cu, cone.radius, cone.half_angle), cone_best);
      EXPECT_GE(cone_ss(cone_points, p, cone.axis + e * cw, cone.radius, cone.half_angle), cone_best);
      EXPECT_GE(cone_ss(cone_points, p, cone.axis, cone.radius + e, cone.half_angle), cone_best);
      EXPECT_GE(cone_ss(cone_points, p, cone.axis, cone.radius, cone.half_angle + e), cone_best);
      const Point3& c = torus.center;
      for (const Vector3& d : {tu, tw, Vector3(torus.axis)}) {
        EXPECT_GE(torus_ss(torus_points, c + e * d, torus.axis, torus.radius, torus.minor_radius), torus_best);
      }
      EXPECT_GE(torus_ss(torus_points, c, torus.axis + e * tu, torus.radius, torus.minor_radius), torus_best);
      EXPECT_GE(torus_ss(torus_points, c, torus.axis + e * tw, torus.radius, torus.minor_radius), torus_best);
      EXPECT_GE(torus_ss(torus_points, c, torus.axis, torus.radius + e, torus.minor_radius), torus_best);
      EXPECT_GE(torus_ss(torus_points, c, torus.axis, torus.radius, torus.minor_radius + e), torus_best);
    }
  }
}

}  // namespace
}  // namespace probecomp::fitting
