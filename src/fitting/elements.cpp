#include "probecomp/fitting/elements.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

namespace probecomp::fitting {

namespace {

// Gauss-Newton has converged when a step changes no parameter by more than kRelativeStep of the data's size
// (the points' largest distance from their centroid): 0.05 pm on a 50 mm part. On ill-conditioned data (a small
// cap of a sphere, an arc of a cylinder) rounding may keep the steps above that; a step that no longer shrinks
// once below kRoundingFloor of the size is that floor, and ends the iteration too.
constexpr double kRelativeStep = 1e-12;
constexpr double kRoundingFloor = 1e-9;
// From the algebraic starts here Gauss-Newton takes under 20 steps (13 and 17 on the reference cylinders, fewer on
// spheres); a hundred means it cannot converge.
constexpr int kMaxIterations = 100;

bool settled(double moved, double last_moved, double size) {
  return moved <= kRelativeStep * size || (moved >= last_moved && last_moved <= kRoundingFloor * size);
}

// Gauss-Newton on n orthogonal distances in `parameters` unknowns. `linearise(J, d)` fills the Jacobian and the
// distances at the current estimate (false: a point where the distance has no direction); `update(step)` applies
// a step and returns how far it moved the element (mm). Degenerate when a step cannot be solved for.
//
// With `hold` (a cone's or torus's fit from the nominal), the steps leave out the combinations of parameters the
// points fix too poorly: the singular vectors of J S (S = `hold->scale`, parameters in mm) whose singular value is
// below `hold->min_singular`. Each step is then the least-squares step within the others (truncated SVD; Hansen,
// "Rank-Deficient and Discrete Ill-Posed Problems", 1998, §3.2), so those combinations stay at the start's values;
// `hold->held` counts them at the last step.
struct Hold {
  Eigen::VectorXd scale;
  double min_singular = 0.0;
  int held = 0;
};
template <class Linearise, class Update>
ElementFitStatus gauss_newton(Eigen::Index n, Eigen::Index parameters, double size, int& iterations,
                              Linearise&& linearise, Update&& update, Hold* hold = nullptr) {
  Eigen::MatrixXd J(n, parameters);
  Eigen::VectorXd d(n);
  double last_moved = std::numeric_limits<double>::infinity();
  for (iterations = 1; iterations <= kMaxIterations; ++iterations) {
    if (!linearise(J, d)) return ElementFitStatus::Degenerate;
    Eigen::VectorXd step;
    if (hold != nullptr) {
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J * hold->scale.asDiagonal(), Eigen::ComputeThinU | Eigen::ComputeThinV);
      const Eigen::VectorXd& s = svd.singularValues();
      // Rounding's floor as well: a combination the points do not fix at all (a torus's equator) is held too.
      const double floor = std::max(hold->min_singular, 1e-12 * s(0));
      Eigen::VectorXd within = Eigen::VectorXd::Zero(s.size());
      hold->held = 0;
      for (Eigen::Index i = 0; i < s.size(); ++i) {
        if (s(i) > floor) {
          within(i) = -svd.matrixU().col(i).dot(d) / s(i);
        } else {
          ++hold->held;
        }
      }
      hold->held += static_cast<int>(parameters - s.size());
      step = hold->scale.asDiagonal() * (svd.matrixV() * within);
    } else {
      const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(J);
      if (qr.rank() < parameters) return ElementFitStatus::Degenerate;
      step = qr.solve(-d);
    }
    if (!step.allFinite()) return ElementFitStatus::Degenerate;
    const double moved = update(step);
    if (settled(moved, last_moved, size)) return ElementFitStatus::OK;
    last_moved = moved;
  }
  iterations = kMaxIterations;
  return ElementFitStatus::NotConverged;
}

struct Centred {
  Point3 centroid = Point3::Zero();
  std::vector<Vector3> p;  // points − centroid
  double size = 0.0;       // largest |p|
};

Centred centre(std::span<const Point3> points) {
  Centred c;
  for (const Point3& x : points) c.centroid += x;
  c.centroid /= static_cast<double>(points.size());
  c.p.reserve(points.size());
  for (const Point3& x : points) {
    c.p.push_back(x - c.centroid);
    c.size = std::max(c.size, c.p.back().norm());
  }
  return c;
}

// Eigenvectors of the centred points' scatter matrix, columns in increasing order of eigenvalue.
Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> principal_directions(const Centred& c) {
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Vector3& x : c.p) scatter += x * x.transpose();
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter);
}

double rms_of(const Eigen::VectorXd& d) { return std::sqrt(d.squaredNorm() / static_cast<double>(d.size())); }

// Kåsa's algebraic fit of a circle (2 columns) or sphere (3 columns) to the rows of X: |x|² = 2 c·x + (r² − |c|²),
// linear in c and r² − |c|². The start of the geometric fits; none when the points do not fix it.
struct Algebraic {
  Eigen::VectorXd centre;
  double radius = 0.0;
};
std::optional<Algebraic> algebraic_fit(const Eigen::MatrixXd& X) {
  const Eigen::Index dim = X.cols();
  Eigen::MatrixXd A(X.rows(), dim + 1);
  A << 2.0 * X, Eigen::VectorXd::Ones(X.rows());
  const Eigen::VectorXd b = X.rowwise().squaredNorm();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  if (qr.rank() < dim + 1) return std::nullopt;
  const Eigen::VectorXd s = qr.solve(b);
  Algebraic out{s.head(dim), 0.0};
  out.radius = std::sqrt(std::max(s(dim) + out.centre.squaredNorm(), 0.0));
  return out;
}

// gauss_newton with the caller's limits (HoldPoorlyFixed; none asked for: every parameter fitted, no Hold), the
// parameters scaled to mm by `scale`; `held` as Hold::held.
template <class Linearise, class Update>
ElementFitStatus gauss_newton_within(const HoldPoorlyFixed& limits, const Eigen::VectorXd& scale, Eigen::Index n,
                                     double size, int& iterations, int& held, Linearise&& linearise, Update&& update) {
  held = 0;
  if (!(limits.sigma > 0.0) || !(limits.max_std > 0.0)) {
    return gauss_newton(n, scale.size(), size, iterations, linearise, update);
  }
  Hold hold{.scale = scale, .min_singular = limits.sigma / limits.max_std};
  const ElementFitStatus status = gauss_newton(n, scale.size(), size, iterations, linearise, update, &hold);
  held = hold.held;
  return status;
}

// The rms of the points' distances from a fitted element (fitting::distance), in the points' own coordinates.
template <class Element>
double rms_distance(const Centred& c, const Element& e) {
  Eigen::VectorXd d(static_cast<Eigen::Index>(c.p.size()));
  for (std::size_t i = 0; i < c.p.size(); ++i) d(static_cast<Eigen::Index>(i)) = distance(e, c.centroid + c.p[i]);
  return rms_of(d);
}

// A rotation taking `axis` (unit) to +z.
Eigen::Matrix3d to_z(const Vector3& axis) {
  return Eigen::Quaterniond::FromTwoVectors(axis, Vector3::UnitZ()).toRotationMatrix();
}

// One cylinder fit from a starting axis through `start` (centred coordinates). Parametrisation of Forbes
// (DITC 140/89 §4.3): in a frame where the current axis is z through the origin, the axis is (x0, y0, 0) +
// t(a, b, 1); at a = b = x0 = y0 = 0 the distance of (x, y, z) is ρ − r, ρ = √(x² + y²), with derivatives
// (−x/ρ, −y/ρ, −xz/ρ, −yz/ρ, −1) in (x0, y0, a, b, r).
CylinderFit cylinder_from(const Centred& c, Vector3 axis, Point3 through, double radius) {
  CylinderFit f;
  const Eigen::Index n = static_cast<Eigen::Index>(c.p.size());
  Eigen::Matrix3d R;
  const auto linearise = [&](Eigen::MatrixXd& J, Eigen::VectorXd& d) {
    R = to_z(axis);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Vector3 q = R * (c.p[static_cast<std::size_t>(i)] - through);
      const double rho = std::hypot(q.x(), q.y());
      if (!(rho > 0.0)) return false;  // a point on the axis: no direction to it
      d(i) = rho - radius;
      J.row(i) << -q.x() / rho, -q.y() / rho, -q.x() * q.z() / rho, -q.y() * q.z() / rho, -1.0;
    }
    return true;
  };
  const auto update = [&](const Eigen::VectorXd& step) {
    const Eigen::Matrix3d back = R.transpose();
    through += back * Vector3(step(0), step(1), 0.0);
    axis = (back * Vector3(step(2), step(3), 1.0)).normalized();
    radius += step(4);
    return std::max({std::abs(step(0)), std::abs(step(1)), std::abs(step(4)), c.size * std::abs(step(2)),
                     c.size * std::abs(step(3))});
  };
  f.status = gauss_newton(n, 5, c.size, f.iterations, linearise, update);
  if (f.status == ElementFitStatus::Degenerate) return f;
  // Residuals at the final parameters, and the axis point nearest the centroid (the origin here).
  Eigen::VectorXd d(n);
  R = to_z(axis);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vector3 q = R * (c.p[static_cast<std::size_t>(i)] - through);
    d(i) = std::hypot(q.x(), q.y()) - radius;
  }
  through -= through.dot(axis) * axis;
  f.axis_point = c.centroid + through;
  f.axis = axis;
  f.radius = std::abs(radius);
  f.rms = rms_of(d);
  return f;
}

// The cone's parametrisation follows the cylinder's: in a frame where the current axis is z through `through`, the
// axis is (x0, y0, 0) + t(a, b, 1), and with ρ = √(x² + y²), h = z, the distance of (x, y, z) from the cone of
// radius r at the origin and half-angle α is (ρ − r − h tan α) cos α = ρ cos α − h sin α − r cos α. At
// a = b = x0 = y0 = 0, ρ moves as for the cylinder and h by (x, y) per (a, b), so its derivatives in
// (x0, y0, a, b, r, α) are (−c x/ρ, −c y/ρ, −c xz/ρ − s x, −c yz/ρ − s y, −c, −(ρ − r) s − h c), c = cos α, s = sin α.
// After each step `through` goes back to the axis point nearest the centroid, r with it.
ConeFit cone_from(const Centred& c, Vector3 axis, Point3 through, double radius, double half_angle,
                  const HoldPoorlyFixed& limits) {
  ConeFit f;
  const Eigen::Index n = static_cast<Eigen::Index>(c.p.size());
  Eigen::Matrix3d R;
  const auto linearise = [&](Eigen::MatrixXd& J, Eigen::VectorXd& d) {
    R = to_z(axis);
    const double cs = std::cos(half_angle), sn = std::sin(half_angle);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Vector3 q = R * (c.p[static_cast<std::size_t>(i)] - through);
      const double rho = std::hypot(q.x(), q.y());
      if (!(rho > 0.0)) return false;
      d(i) = (rho - radius - q.z() * std::tan(half_angle)) * cs;
      J.row(i) << -cs * q.x() / rho, -cs * q.y() / rho, -cs * q.x() * q.z() / rho - sn * q.x(),
          -cs * q.y() * q.z() / rho - sn * q.y(), -cs, -(rho - radius) * sn - q.z() * cs;
    }
    return true;
  };
  const auto recentre = [&] {
    const double shift = -through.dot(axis);
    through += shift * axis;
    radius += shift * std::tan(half_angle);
  };
  const auto update = [&](const Eigen::VectorXd& step) {
    const Eigen::Matrix3d back = R.transpose();
    through += back * Vector3(step(0), step(1), 0.0);
    axis = (back * Vector3(step(2), step(3), 1.0)).normalized();
    radius += step(4);
    half_angle += step(5);
    recentre();
    return std::max({std::abs(step(0)), std::abs(step(1)), std::abs(step(4)), c.size * std::abs(step(2)),
                     c.size * std::abs(step(3)), c.size * std::abs(step(5))});
  };
  recentre();
  Eigen::VectorXd scale(6);
  scale << 1.0, 1.0, 1.0 / c.size, 1.0 / c.size, 1.0, 1.0 / c.size;
  f.status = gauss_newton_within(limits, scale, n, c.size, f.iterations, f.held, linearise, update);
  if (f.status == ElementFitStatus::Degenerate || !(std::abs(half_angle) < 0.5 * std::numbers::pi)) {
    f.status = ElementFitStatus::Degenerate;
    return f;
  }
  f.axis_point = c.centroid + through;
  f.axis = axis;
  f.radius = radius;
  f.half_angle = half_angle;
  f.rms = rms_distance(c, f);
  return f;
}

// The torus about the axis z through `centre` (free in x0, y0, z0; the axis tilted by (a, b) as the cylinder's):
// with ρ = √(x² + y²), h = z and w = √((ρ − R)² + h²), the distance is w − r; its derivatives in
// (x0, y0, z0, a, b, R, r) follow from ∂w/∂ρ = (ρ − R)/w, ∂w/∂h = h/w and ρ's and h's as for the cone.
TorusFit torus_from(const Centred& c, Vector3 axis, Point3 centre_estimate, double radius, double minor,
                    const HoldPoorlyFixed& limits) {
  TorusFit f;
  const Eigen::Index n = static_cast<Eigen::Index>(c.p.size());
  Eigen::Matrix3d R;
  const auto linearise = [&](Eigen::MatrixXd& J, Eigen::VectorXd& d) {
    R = to_z(axis);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Vector3 q = R * (c.p[static_cast<std::size_t>(i)] - centre_estimate);
      const double rho = std::hypot(q.x(), q.y());
      const double w = std::hypot(rho - radius, q.z());
      if (!(rho > 0.0) || !(w > 0.0)) return false;  // on the axis, or on the tube's centre circle
      const double dr = (rho - radius) / w, dh = q.z() / w;
      d(i) = w - minor;
      J.row(i) << -dr * q.x() / rho, -dr * q.y() / rho, -dh, -dr * q.x() * q.z() / rho + dh * q.x(),
          -dr * q.y() * q.z() / rho + dh * q.y(), -dr, -1.0;
    }
    return true;
  };
  const auto update = [&](const Eigen::VectorXd& step) {
    const Eigen::Matrix3d back = R.transpose();
    centre_estimate += back * step.head<3>();
    axis = (back * Vector3(step(3), step(4), 1.0)).normalized();
    radius += step(5);
    minor += step(6);
    return std::max({step.head<3>().cwiseAbs().maxCoeff(), std::abs(step(5)), std::abs(step(6)),
                     c.size * std::abs(step(3)), c.size * std::abs(step(4))});
  };
  Eigen::VectorXd scale(7);
  scale << 1.0, 1.0, 1.0, 1.0 / c.size, 1.0 / c.size, 1.0, 1.0;
  f.status = gauss_newton_within(limits, scale, n, c.size, f.iterations, f.held, linearise, update);
  if (f.status == ElementFitStatus::Degenerate || !(minor > 0.0)) {
    f.status = ElementFitStatus::Degenerate;
    return f;
  }
  f.center = c.centroid + centre_estimate;
  f.axis = axis;
  f.radius = radius;
  f.minor_radius = minor;
  f.rms = rms_distance(c, f);
  return f;
}

}  // namespace

const char* to_string(ElementFitStatus s) {
  switch (s) {
    case ElementFitStatus::OK: return "ok";
    case ElementFitStatus::NotConverged: return "not-converged";
    case ElementFitStatus::Degenerate: return "degenerate";
  }
  return "?";
}

PlaneFit fit_plane(std::span<const Point3> points) {
  PlaneFit f;
  if (points.size() < 3) return f;
  const Centred c = centre(points);
  const auto eig = principal_directions(c);
  // Two directions of spread are needed: the middle eigenvalue must stand clear of rounding.
  if (!(eig.eigenvalues()(1) > 1e-24 * eig.eigenvalues()(2))) return f;
  f.point = c.centroid;
  f.normal = eig.eigenvectors().col(0).normalized();
  Eigen::VectorXd d(static_cast<Eigen::Index>(c.p.size()));
  for (std::size_t i = 0; i < c.p.size(); ++i) d(static_cast<Eigen::Index>(i)) = c.p[i].dot(f.normal);
  f.rms = rms_of(d);
  f.status = ElementFitStatus::OK;
  return f;
}

SphereFit fit_sphere(std::span<const Point3> points) {
  SphereFit f;
  if (points.size() < 4) return f;
  const Centred c = centre(points);
  const Eigen::Index n = static_cast<Eigen::Index>(c.p.size());
  Eigen::MatrixXd X(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) X.row(i) = c.p[static_cast<std::size_t>(i)].transpose();
  const std::optional<Algebraic> start = algebraic_fit(X);
  if (!start) return f;
  Vector3 centre_estimate = start->centre;
  double radius = start->radius;
  // Gauss-Newton on d_i = |x_i − c| − r, derivatives (−(x_i − c)/|x_i − c|, −1).
  const auto linearise = [&](Eigen::MatrixXd& J, Eigen::VectorXd& d) {
    for (Eigen::Index i = 0; i < n; ++i) {
      const Vector3 v = c.p[static_cast<std::size_t>(i)] - centre_estimate;
      const double len = v.norm();
      if (!(len > 0.0)) return false;
      d(i) = len - radius;
      J.row(i) << -v.x() / len, -v.y() / len, -v.z() / len, -1.0;
    }
    return true;
  };
  const auto update = [&](const Eigen::VectorXd& step) {
    centre_estimate += step.head<3>();
    radius += step(3);
    return step.cwiseAbs().maxCoeff();
  };
  f.status = gauss_newton(n, 4, c.size, f.iterations, linearise, update);
  if (f.status == ElementFitStatus::Degenerate) return f;
  Eigen::VectorXd d(n);
  for (Eigen::Index i = 0; i < n; ++i) d(i) = (c.p[static_cast<std::size_t>(i)] - centre_estimate).norm() - radius;
  f.center = c.centroid + centre_estimate;
  f.radius = radius;
  f.rms = rms_of(d);
  return f;
}

CylinderFit fit_cylinder(std::span<const Point3> points) {
  CylinderFit best;
  if (points.size() < 5) return best;
  const Centred c = centre(points);
  const auto eig = principal_directions(c);
  for (int k = 2; k >= 0; --k) {
    const Vector3 axis = eig.eigenvectors().col(k).normalized();
    // Start: the algebraic circle fit of the points projected along this axis (an arc's centre is far from its
    // centroid, so the centroid would be a poor start).
    const Vector3 e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
    Eigen::MatrixXd X(static_cast<Eigen::Index>(c.p.size()), 2);
    for (Eigen::Index i = 0; i < X.rows(); ++i) {
      const Vector3& x = c.p[static_cast<std::size_t>(i)];
      X.row(i) << x.dot(e1), x.dot(e2);
    }
    const std::optional<Algebraic> circle = algebraic_fit(X);
    if (!circle) continue;
    const Point3 through = Point3::Zero() + circle->centre(0) * e1 + circle->centre(1) * e2;
    const double radius = circle->radius;
    const CylinderFit f = cylinder_from(c, axis, through, radius);
    const bool better = f.status == ElementFitStatus::OK &&
                        (best.status != ElementFitStatus::OK || f.rms < best.rms);
    if (better || (best.status == ElementFitStatus::Degenerate && f.status == ElementFitStatus::NotConverged)) best = f;
  }
  return best;
}

ConeFit fit_cone(std::span<const Point3> points, const ConeFit& start, const HoldPoorlyFixed& limits) {
  ConeFit f;
  if (points.size() < 6 || !(start.axis.norm() > 0.0)) return f;
  const Centred c = centre(points);
  return cone_from(c, start.axis.normalized(), start.axis_point - c.centroid, start.radius, start.half_angle, limits);
}

TorusFit fit_torus(std::span<const Point3> points, const TorusFit& start, const HoldPoorlyFixed& limits) {
  TorusFit f;
  if (points.size() < 7 || !(start.axis.norm() > 0.0)) return f;
  const Centred c = centre(points);
  return torus_from(c, start.axis.normalized(), start.center - c.centroid, start.radius, start.minor_radius, limits);
}

double distance(const ConeFit& cone, const Point3& x) {
  const Vector3 q = x - cone.axis_point;
  const double h = q.dot(cone.axis);
  const double rho = (q - h * cone.axis).norm();
  return (rho - cone.radius - h * std::tan(cone.half_angle)) * std::cos(cone.half_angle);
}

double distance(const TorusFit& torus, const Point3& x) {
  const Vector3 q = x - torus.center;
  const double h = q.dot(torus.axis);
  const double rho = (q - h * torus.axis).norm();
  return std::hypot(rho - torus.radius, h) - torus.minor_radius;
}

}  // namespace probecomp::fitting
