#include "probecomp/selftest/reference_elements.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <numbers>

#include "selftest/random.hpp"

namespace probecomp::selftest {

namespace {

// Nominal points q_i with unit normals n_i and the Jacobian rows J_i of the element's distance function at the
// known element: the residuals are a random vector with its component in J's column space removed, scaled so the
// largest is `largest`.
void perturb(ReferenceElement& e, const std::vector<Point3>& q, const std::vector<Vector3>& n, const Eigen::MatrixXd& J,
             double largest, Random& random) {
  const Eigen::Index m = J.rows();
  Eigen::VectorXd z(m);
  for (Eigen::Index i = 0; i < m; ++i) z(i) = random.between(-1.0, 1.0);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(J);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(m, J.cols());
  Eigen::VectorXd r = z - Q * (Q.transpose() * z);
  r *= largest / r.cwiseAbs().maxCoeff();
  e.points.clear();
  for (Eigen::Index i = 0; i < m; ++i) e.points.push_back(q[static_cast<std::size_t>(i)] + r(i) * n[static_cast<std::size_t>(i)]);
  e.rms = std::sqrt(r.squaredNorm() / static_cast<double>(m));
}

ReferenceElement plane(const std::string& name, const Point3& origin, const Vector3& normal, double a, double b, int count,
                       double largest, Random& random) {
  ReferenceElement e{.name = name, .kind = ElementKind::Plane, .points = {}, .point = origin, .direction = normal.normalized()};
  const Vector3 s = e.direction.unitOrthogonal(), t = e.direction.cross(s);
  std::vector<Point3> q;
  std::vector<Vector3> n;
  Eigen::MatrixXd J(count, 3);
  for (int i = 0; i < count; ++i) {
    const double x = random.between(-a / 2, a / 2), y = random.between(-b / 2, b / 2);
    q.push_back(origin + x * s + y * t);
    n.push_back(e.direction);
    // d = n·(p − origin): derivatives in the offset along n and the two tilts.
    J.row(i) << 1.0, x, y;
  }
  perturb(e, q, n, J, largest, random);
  return e;
}

// Points over the zone of the sphere from polar angle 0 (about `axis`) to `cap` (π: the whole sphere).
ReferenceElement sphere(const std::string& name, const Point3& c, double R, const Vector3& axis, double cap, int count,
                        double largest, Random& random) {
  ReferenceElement e{.name = name, .kind = ElementKind::Sphere, .points = {}, .point = c, .radius = R};
  const Vector3 a = axis.normalized(), s = a.unitOrthogonal(), t = a.cross(s);
  std::vector<Point3> q;
  std::vector<Vector3> n;
  Eigen::MatrixXd J(count, 4);
  for (int i = 0; i < count; ++i) {
    // Uniform over the zone's area: cos(polar) uniform in [cos cap, 1].
    const double z = random.between(std::cos(cap), 1.0), phi = random.between(0.0, 2.0 * std::numbers::pi);
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const Vector3 u = rho * std::cos(phi) * s + rho * std::sin(phi) * t + z * a;
    q.push_back(c + R * u);
    n.push_back(u);
    J.row(i) << -u.x(), -u.y(), -u.z(), -1.0;
  }
  perturb(e, q, n, J, largest, random);
  return e;
}

// Points over the angular range [0, sweep] of the cylinder about `axis` through `p`, at axial positions in [0, L].
ReferenceElement cylinder(const std::string& name, const Point3& p, const Vector3& axis, double R, double L, double sweep,
                          int count, double largest, Random& random) {
  ReferenceElement e{.name = name, .kind = ElementKind::Cylinder, .points = {}, .point = p, .direction = axis.normalized(), .radius = R};
  const Vector3 s = e.direction.unitOrthogonal(), t = e.direction.cross(s);
  std::vector<Point3> q;
  std::vector<Vector3> n;
  Eigen::MatrixXd J(count, 5);
  for (int i = 0; i < count; ++i) {
    const double phi = random.between(0.0, sweep), z = random.between(0.0, L);
    const double ux = std::cos(phi), uy = std::sin(phi);
    const Vector3 u = ux * s + uy * t;
    q.push_back(p + z * e.direction + R * u);
    n.push_back(u);
    // Forbes's derivatives in the axis frame (x0, y0, a, b, r): −u_x, −u_y, −u_x z, −u_y z, −1.
    J.row(i) << -ux, -uy, -ux * z, -uy * z, -1.0;
  }
  perturb(e, q, n, J, largest, random);
  return e;
}

}  // namespace

std::vector<ReferenceElement> reference_elements() {
  Random random{20261125};
  constexpr double kResidual = 0.01;  // mm: the largest residual, a rough surface's form error
  std::vector<ReferenceElement> out;
  out.push_back(plane("plane 100 x 60 mm, 1.2 m from the origin", Point3(1000, -500, 250), Vector3(0.2, -0.3, 1.0), 100,
                      60, 40, kResidual, random));
  out.push_back(plane("plane 20 x 2 mm (a narrow strip)", Point3(-35, 12, 480), Vector3(1, 1, 0.1), 20, 2, 40, kResidual,
                      random));
  out.push_back(sphere("sphere R 12.5 mm, whole", Point3(150, 80, -40), 12.5, Vector3(0, 0, 1), std::numbers::pi, 50,
                       kResidual, random));
  out.push_back(sphere("sphere R 50 mm, 30 deg cap, 0.9 m out", Point3(600, -400, 500), 50.0, Vector3(1, 1, 1),
                       std::numbers::pi / 6.0, 50, kResidual, random));
  out.push_back(cylinder("cylinder R 10 mm, L 40 mm, whole", Point3(20, -30, 15), Vector3(0.1, 0.2, 1.0), 10.0, 40.0,
                         2.0 * std::numbers::pi, 60, kResidual, random));
  out.push_back(cylinder("cylinder R 25 mm, 120 deg arc, L 60 mm", Point3(-300, 250, 100), Vector3(1, -0.5, 0.3), 25.0,
                         60.0, 2.0 * std::numbers::pi / 3.0, 60, kResidual, random));
  return out;
}

}  // namespace probecomp::selftest
