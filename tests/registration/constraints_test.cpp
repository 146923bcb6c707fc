// Degrees of freedom of point-to-plane alignment for shapes whose symmetries are known.

#include "probecomp/registration/constraints.hpp"
#include "probecomp/simulation/random.hpp"

#include <gtest/gtest.h>

#include <random>

namespace probecomp::registration {
namespace {

Constraints of(const std::vector<Point3>& x, const std::vector<Vector3>& n) {
  Point3 c = Point3::Zero();
  for (const Point3& p : x) c += p;
  c /= static_cast<double>(x.size());
  double L2 = 0.0;
  for (const Point3& p : x) L2 += (p - c).squaredNorm();
  const double L = std::sqrt(L2 / static_cast<double>(x.size()));
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  for (std::size_t i = 0; i < x.size(); ++i) {
    geometry::Twist J;
    J.head<3>() = (x[i] - c).cross(n[i]) / L;
    J.tail<3>() = n[i];
    H += J * J.transpose();
  }
  return analyse_constraints(H, c, L);
}

TEST(Constraints, SphereLeavesThreeRotationsAboutItsCentre) {
  const Point3 centre(3, -2, 7);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Point3> x;
  std::vector<Vector3> n;
  for (int k = 0; k < 500; ++k) {
    Vector3 d = simulation::draw_vector(g, rng);
    d.normalize();
    if (d.z() < 0.2) continue;  // a cap, so the centroid is not the sphere's centre
    x.push_back(centre + 12.0 * d);
    n.push_back(d);
  }
  const Constraints c = of(x, n);
  EXPECT_EQ(c.fixed, 3);
  ASSERT_EQ(c.free.size(), 3u);
  for (const FreeMotion& f : c.free) {
    EXPECT_EQ(f.kind, FreeMotion::Kind::Rotation);
    // Each axis passes through the sphere's centre.
    const Vector3 off = f.through - centre;
    EXPECT_LT((off - off.dot(f.direction) * f.direction).norm(), 1e-9);
  }
}

TEST(Constraints, ThreeOrthogonalPlanesFixEverythingAndTwoParallelPlanesDoNot) {
  std::vector<Point3> x;
  std::vector<Vector3> n;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) {
      x.emplace_back(0, 2.0 * i, 2.0 * j), n.emplace_back(-1, 0, 0);
      x.emplace_back(2.0 * i, 0, 2.0 * j), n.emplace_back(0, -1, 0);
      x.emplace_back(2.0 * i, 2.0 * j, 0), n.emplace_back(0, 0, -1);
    }
  }
  EXPECT_EQ(of(x, n).fixed, 6);
  std::vector<Point3> y;
  std::vector<Vector3> m;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) {
      y.emplace_back(i, j, 0), m.emplace_back(0, 0, 1);
      y.emplace_back(i, j, 5), m.emplace_back(0, 0, -1);
    }
  }
  const Constraints c = of(y, m);
  EXPECT_EQ(c.fixed, 3);
  EXPECT_EQ(c.free.size(), 3u);
}

}  // namespace
}  // namespace probecomp::registration
