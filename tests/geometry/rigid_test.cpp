// Rigid-motion helpers against closed forms.

#include "probecomp/geometry/rigid.hpp"
#include "probecomp/simulation/random.hpp"

#include <gtest/gtest.h>

#include <random>

namespace probecomp::geometry {
namespace {

TEST(Rigid, PoseIsTranslationAfterRotationsAboutXThenYThenZ) {
  const RigidTransform T = from_pose({.rx = 90.0, .ry = 0.0, .rz = 0.0, .t = Vector3(1, 2, 3)});
  EXPECT_LT((T * Point3(0, 1, 0) - Point3(1, 2, 4)).norm(), 1e-15);  // y turns into z about x
  const RigidTransform U = from_pose({.rx = 90.0, .ry = 0.0, .rz = 90.0, .t = Vector3::Zero()});
  // x-rotation first: y → z; then z-rotation leaves z: (0,1,0) → (0,0,1).
  EXPECT_LT((U * Point3(0, 1, 0) - Point3(0, 0, 1)).norm(), 1e-15);
  // And x → x (about x) → y (about z).
  EXPECT_LT((U * Point3(1, 0, 0) - Point3(0, 1, 0)).norm(), 1e-15);
}

TEST(Rigid, PoseRoundTrips) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> a(-170.0, 170.0), b(-85.0, 85.0), t(-100.0, 100.0);
  for (int k = 0; k < 1000; ++k) {
    const Pose p{.rx = a(rng), .ry = b(rng), .rz = a(rng), .t = simulation::draw_vector(t, rng)};
    const Pose q = to_pose(from_pose(p));
    EXPECT_NEAR(q.rx, p.rx, 1e-11);
    EXPECT_NEAR(q.ry, p.ry, 1e-11);
    EXPECT_NEAR(q.rz, p.rz, 1e-11);
    EXPECT_LT((q.t - p.t).norm(), 1e-13);
  }
}

TEST(Rigid, TwistIsRotationVectorAndTranslation) {
  Twist xi;
  xi << 0.0, 0.0, M_PI / 2, 1.0, 0.0, 0.0;
  const RigidTransform T = from_twist(xi);
  EXPECT_LT((T * Point3(1, 0, 0) - Point3(1, 1, 0)).norm(), 1e-15);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> w(-1.5, 1.5);
  for (int k = 0; k < 100; ++k) {
    Twist x;
    x << w(rng), w(rng), w(rng), w(rng), w(rng), w(rng);
    EXPECT_LT((to_twist(from_twist(x)) - x).norm(), 1e-12);
  }
}

TEST(Rigid, LargestMotionBoundsEveryPointAndIsReached) {
  const RigidTransform T = from_pose({.rx = 3.0, .ry = -2.0, .rz = 1.0, .t = Vector3(0.1, -0.2, 0.3)});
  const Point3 c(10, 20, 30);
  const double bound = largest_motion(T, c, 50.0);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  double worst = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const Point3 p = c + 50.0 * simulation::draw_vector(g, rng).normalized();
    worst = std::max(worst, (T * p - p).norm());
  }
  EXPECT_LE(worst, bound * (1 + 1e-12));
  EXPECT_GT(worst, 0.9 * bound);  // the bound is the triangle inequality: tight within the rotation's share
}

}  // namespace
}  // namespace probecomp::geometry
