// ICP against known rigid motions: the truth is the motion the test applied, never an earlier output.

#include "probecomp/registration/icp.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <iostream>
#include <random>

#include "probecomp/nurbs/constructors.hpp"
#include "probecomp/simulation/random.hpp"
#include "registration/support.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::registration {
namespace {

using testing::largest_disagreement;
using testing::moved;
using testing::points_on;
using testing::rotation_disagreement_deg;
using testing::single_face_model;

// About 1 mm and 1° on each axis, as the issue asks.
const geometry::RigidTransform kMisalignment = geometry::from_pose({.rx = 0.7, .ry = -0.9, .rz = 0.6, .t = Vector3(0.8, -0.6, 0.9)});

nurbs::Surface freeform() { return testing::random_rational_surface(11, {.nu = 10, .nv = 9, .height = 12.0}); }

TEST(Icp, RecoversAKnownMotionOfAFreeFormFaceFromNoiseFreePoints) {
  const cad::Model model = single_face_model(freeform());
  const cad::ModelLocator locator(model);
  const std::vector<Point3> nominal = points_on(model.faces[0].surface, 5000, 0.03, 1);
  const std::vector<Point3> measured = moved(kMisalignment, nominal);
  const RegistrationResult r = register_points(locator, measured);
  ASSERT_TRUE(r.converged()) << r.stop_reason;
  EXPECT_LT(largest_disagreement(r.transform, kMisalignment, nominal), 1e-7);
  EXPECT_LT(rotation_disagreement_deg(r.transform, kMisalignment), 1e-6);
  EXPECT_EQ(r.constraints.fixed, 6);
  EXPECT_LT(r.rms, 1e-9);
  EXPECT_LT(r.iterations, 20);
  ASSERT_EQ(r.matches.size(), measured.size());
  for (const PointMatch& m : r.matches) {
    EXPECT_TRUE(m.inlier);
    EXPECT_LT(std::abs(m.distance), 1e-9);
  }
}

// 1 % of the points pushed 0.5–2 mm off the surface, all on one side (a burr, dirt, a probe that skidded):
// plain least squares shifts by about 1 % of their mean; the robust losses must not.
struct NoisyCase {
  std::vector<Point3> nominal, measured;
  std::vector<bool> outlier;
};

// Points over (u, v) in [margin, 1 − margin]².
NoisyCase noisy_case(const nurbs::Surface& s, double sigma, int n = 10000, double margin = 0.03) {
  NoisyCase c;
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> t(margin, 1.0 - margin), gross(0.5, 2.0), pick(0.0, 1.0);
  std::normal_distribution<double> g(0.0, sigma);
  for (int k = 0; k < n; ++k) {
    const double u = t(rng), v = t(rng);
    const Point3 p = nurbs::evaluate(s, u, v);
    Point3 q = p + simulation::draw_vector(g, rng);
    const bool out = pick(rng) < 0.01;
    if (out) q += gross(rng) * nurbs::unit_normal(s, u, v).n;
    c.nominal.push_back(p);
    c.measured.push_back(kMisalignment * q);
    c.outlier.push_back(out);
  }
  return c;
}

TEST(Icp, WithNoiseAndOnePercentGrossOutliersTheRobustLossesStayWithinTheNoise) {
  const double sigma = 0.005;
  const cad::Model model = single_face_model(freeform());
  const cad::ModelLocator locator(model);
  const NoisyCase c = noisy_case(model.faces[0].surface, sigma);
  double plain = 0.0, best = 1e9;
  for (RobustLoss loss : {RobustLoss::None, RobustLoss::Huber, RobustLoss::Cauchy, RobustLoss::Trimmed}) {
    RegistrationOptions o;
    o.robust.loss = loss;
    const RegistrationResult r = register_points(locator, c.measured, o);
    ASSERT_TRUE(r.converged()) << to_string(loss) << ": " << r.stop_reason;
    const double err = largest_disagreement(r.transform, kMisalignment, c.nominal);
    int flagged = 0, missed = 0;
    for (std::size_t i = 0; i < c.outlier.size(); ++i) {
      flagged += c.outlier[i] && !r.matches[i].inlier;
      missed += !c.outlier[i] && !r.matches[i].inlier;
    }
    std::cout << "[ measured ] " << to_string(loss) << ": largest point error " << err * 1e3 << " µm, rotation error "
              << rotation_disagreement_deg(r.transform, kMisalignment) << "°, " << r.iterations << " iterations, scale "
              << r.scale * 1e3 << " µm, outliers flagged " << flagged << ", good points flagged " << missed << "\n";
    if (loss == RobustLoss::None) {
      plain = err;
      continue;
    }
    best = std::min(best, err);
    EXPECT_LT(err, sigma) << to_string(loss);
    EXPECT_NEAR(r.scale, sigma, 0.1 * sigma) << to_string(loss);  // the noise along the normal, estimated
    EXPECT_EQ(flagged, std::count(c.outlier.begin(), c.outlier.end(), true)) << to_string(loss);
  }
  EXPECT_GT(plain, 2.0 * best);  // why the weights are there
}

TEST(Icp, StepsBetweenSearchesSlideOnOsculatingParaboloidsAndKeepTheAccuracy) {
  // The robust weights converge linearly over many steps; between closest-point searches the points slide on their
  // feet's osculating paraboloids, and a search where they end confirms it. Fewer searches than steps, the same
  // answer.
  const double sigma = 0.005;
  const cad::Model model = single_face_model(freeform());
  const cad::ModelLocator locator(model);
  const NoisyCase c = noisy_case(model.faces[0].surface, sigma, 20000);
  const RegistrationResult r = register_points(locator, c.measured);
  ASSERT_TRUE(r.converged()) << r.stop_reason;
  EXPECT_GT(r.searches, 0);
  EXPECT_LT(r.searches, r.iterations);
  const double err = largest_disagreement(r.transform, kMisalignment, c.nominal);
  std::cout << "[ measured ] 20 000 points: " << r.iterations << " steps, " << r.searches << " searches of all points, "
            << r.coarse_iterations << " steps on the subset; largest point error " << err * 1e3 << " µm\n";
  // The estimate's own uncertainty is about σ/√n = 0.035 µm; the largest point error is a few times that.
  EXPECT_LT(err, 0.1 * sigma);
}

TEST(Icp, SlidesSeeFeetCrossTheFaceEdgeSoTheSearchAfterThemConfirms) {
  // 2 000 of 20 000 points lie within 0.1 mm of the face's edge u = 0, on either side, so their feet cross it as the
  // estimate moves. The slides follow each foot's parameters on its paraboloid and leave such points out of the
  // estimate (or take them back) as a search would, so the search after the slides confirms: two searches of all
  // points, the first from the subset's feet. Slides blind to the edge need a third.
  const double sigma = 0.005;
  const cad::Model model = single_face_model(freeform());
  const nurbs::Surface& s = model.faces[0].surface;
  const cad::ModelLocator locator(model);
  NoisyCase c = noisy_case(s, sigma, 18000);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> along(0.03, 0.97), across(-0.1, 0.1);
  std::normal_distribution<double> noise(0.0, sigma);
  int beyond = 0;
  for (int k = 0; k < 2000; ++k) {
    const double v = along(rng), a = across(rng);  // a > 0: inside, mm
    const nurbs::SurfaceD1 d = nurbs::derivatives_d1(s, 0.0, v);
    // Beyond the edge: along the edge's tangent outwards; inside: at the parameter that far in, to first order.
    const Point3 p = a < 0.0 ? Point3(d.S + a * d.Su.normalized()) : nurbs::evaluate(s, a / d.Su.norm(), v);
    beyond += a < 0.0;
    c.nominal.push_back(p);
    c.measured.push_back(kMisalignment * (p + noise(rng) * nurbs::unit_normal(s, 0.0, v).n));
  }
  const RegistrationResult r = register_points(locator, c.measured);
  ASSERT_TRUE(r.converged()) << r.stop_reason;
  const long on_edge = std::count_if(r.matches.begin(), r.matches.end(), [](const PointMatch& m) { return m.on_edge; });
  const double err = largest_disagreement(r.transform, kMisalignment, c.nominal);
  std::cout << "[ measured ] 20 000 points, " << beyond << " placed beyond the face's edge and " << on_edge
            << " found there: " << r.iterations << " steps, " << r.searches << " searches of all points; largest point "
            << "error " << err * 1e3 << " µm\n";
  EXPECT_NEAR(on_edge, beyond, 0.02 * beyond);
  EXPECT_EQ(r.searches, 2);
  EXPECT_LT(err, 0.1 * sigma);
}

TEST(Icp, SameResultWithOneAndTwoThreads) {
  // Enough points for the coarse stage (a subset first, then all points from their neighbours' feet).
  const cad::Model model = single_face_model(freeform());
  const cad::ModelLocator locator(model);
  const NoisyCase c = noisy_case(model.faces[0].surface, 0.005, 20000);
  std::vector<RegistrationResult> results;
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    results.push_back(register_points(locator, c.measured));
  }
  EXPECT_EQ(results[0].transform.matrix(), results[1].transform.matrix());
  EXPECT_EQ(results[0].iterations, results[1].iterations);
  EXPECT_GT(results[0].coarse_iterations, 0);
  ASSERT_TRUE(results[0].converged()) << results[0].stop_reason;
  EXPECT_LT(largest_disagreement(results[0].transform, kMisalignment, c.nominal), 0.005);
  for (std::size_t i = 0; i < c.measured.size(); ++i) {
    EXPECT_EQ(results[0].matches[i].distance, results[1].matches[i].distance);
    EXPECT_EQ(results[0].matches[i].inlier, results[1].matches[i].inlier);
  }
}

TEST(Icp, APlaneFixesThreeMotionsAndTheOthersStayAtTheStart) {
  const cad::Model model = single_face_model(nurbs::make_plane_patch({0, 0, 0}, {100, 0, 0}, {0, 100, 0}));
  const cad::ModelLocator locator(model);
  const std::vector<Point3> nominal = points_on(model.faces[0].surface, 2000, 0.05, 4);
  const std::vector<Point3> measured = moved(kMisalignment, nominal);
  const RegistrationResult r = register_points(locator, measured);
  ASSERT_TRUE(r.converged()) << r.stop_reason;
  EXPECT_EQ(r.constraints.fixed, 3);
  ASSERT_EQ(r.constraints.free.size(), 3u);
  int translations = 0;
  for (const FreeMotion& f : r.constraints.free) {
    if (f.kind == FreeMotion::Kind::Translation) {
      ++translations;
      EXPECT_LT(std::abs(f.direction.z()), 1e-9);  // sliding in the plane
    } else {
      EXPECT_NEAR(std::abs(f.direction.z()), 1.0, 1e-9);  // turning about the normal
    }
  }
  EXPECT_EQ(translations, 2);
  for (const PointMatch& m : r.matches) EXPECT_LT(std::abs(m.distance), 1e-9);
  // Held at the start: the data's centroid moved only along the plane's normal, and nothing turned about it.
  Point3 c = Point3::Zero();
  for (const Point3& p : measured) c += p;
  c /= static_cast<double>(measured.size());
  const geometry::RigidTransform to_cad = r.transform.inverse();
  const Vector3 shift = to_cad * c - c;
  EXPECT_LT(std::hypot(shift.x(), shift.y()), 1e-9);
  EXPECT_LT(std::abs(geometry::to_twist(to_cad)(2)), 1e-12);
}

TEST(Icp, ACylinderLeavesItsAxisFree) {
  // Radius 10 mm, half a turn, 40 mm long along z: sliding along z and turning about z are not measurable.
  const cad::Model model =
      single_face_model(nurbs::make_cylinder_section({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 10.0, 0.0, M_PI, 40.0));
  const cad::ModelLocator locator(model);
  const std::vector<Point3> nominal = points_on(model.faces[0].surface, 2000, 0.05, 5);
  const geometry::RigidTransform motion = geometry::from_pose({.rx = 0.3, .ry = 0.2, .rz = 1.0, .t = Vector3(0.2, -0.3, 0.7)});
  const std::vector<Point3> measured = moved(motion, nominal);
  const RegistrationResult r = register_points(locator, measured);
  ASSERT_TRUE(r.converged()) << r.stop_reason;
  EXPECT_EQ(r.constraints.fixed, 4);
  ASSERT_EQ(r.constraints.free.size(), 2u);
  EXPECT_EQ(r.constraints.free[0].kind, FreeMotion::Kind::Translation);
  EXPECT_NEAR(std::abs(r.constraints.free[0].direction.z()), 1.0, 1e-9);
  EXPECT_EQ(r.constraints.free[1].kind, FreeMotion::Kind::Rotation);
  EXPECT_NEAR(std::abs(r.constraints.free[1].direction.z()), 1.0, 1e-9);
  EXPECT_LT(std::hypot(r.constraints.free[1].through.x(), r.constraints.free[1].through.y()), 1e-6);  // the axis
  for (const PointMatch& m : r.matches) EXPECT_LT(std::abs(m.distance), 1e-9);
  // The measured cylinder's axis is where the registered model puts it: the fixed motions are right.
  const geometry::RigidTransform to_cad = r.transform.inverse();
  for (const Point3& p : measured) EXPECT_NEAR(std::hypot((to_cad * p).x(), (to_cad * p).y()), 10.0, 1e-9);
  // The free ones were held: no turn about the axis, no slide along it (the data centroid kept its z).
  Point3 c = Point3::Zero();
  for (const Point3& p : measured) c += p;
  c /= static_cast<double>(measured.size());
  EXPECT_LT(std::abs((to_cad * c - c).z()), 1e-9);
  // Each step turns about no axis parallel to z; the steps' compositions do, to second order in the tilt
  // (0.3° and 0.2° here: about 1e-6 rad), against the 1° (0.017 rad) turn the data cannot see.
  EXPECT_LT(std::abs(geometry::to_twist(to_cad)(2)), 2e-6);
}

TEST(Icp, PointsBeyondTheFaceAreReportedAndNotUsed) {
  const cad::Model model = single_face_model(nurbs::make_plane_patch({0, 0, 0}, {100, 0, 0}, {0, 100, 0}));
  const cad::ModelLocator locator(model);
  std::vector<Point3> measured;
  for (int i = 0; i <= 20; ++i) {
    for (int j = 0; j <= 20; ++j) measured.emplace_back(5.0 * i + 0.01 * j, 5.5 * j - 5.0, 0.2 + 0.001 * i);
  }
  const RegistrationResult r = register_points(locator, measured);
  ASSERT_TRUE(r.converged()) << r.stop_reason;
  int beyond = 0;
  for (std::size_t k = 0; k < measured.size(); ++k) {
    const geometry::RigidTransform to_cad = r.transform.inverse();
    const Point3 x = to_cad * measured[k];
    const bool outside = x.y() < -1e-9 || x.y() > 100.0 + 1e-9 || x.x() > 100.0 + 1e-9;
    if (outside) {
      ++beyond;
      EXPECT_TRUE(r.matches[k].on_edge) << k;
      EXPECT_FALSE(r.matches[k].inlier) << k;
      EXPECT_EQ(r.matches[k].weight, 0.0);
    } else {
      EXPECT_LT(std::abs(r.matches[k].distance), 1e-9) << k;
    }
  }
  EXPECT_GT(beyond, 20);
  EXPECT_EQ(r.used + beyond, static_cast<int>(measured.size()));
}

TEST(Icp, TooFewPointsAndNonFinitePointsAreReported) {
  const cad::Model model = single_face_model(freeform());
  const cad::ModelLocator locator(model);
  EXPECT_EQ(register_points(locator, std::vector<Point3>{}).status, Status::TooFewPoints);
  std::vector<Point3> three = points_on(model.faces[0].surface, 3, 0.1, 9);
  const RegistrationResult r = register_points(locator, three);
  EXPECT_EQ(r.status, Status::TooFewPoints);
  EXPECT_NE(r.stop_reason.find("only 3 of 3"), std::string::npos) << r.stop_reason;
  ASSERT_EQ(r.matches.size(), 3u);

  std::vector<Point3> pts = moved(kMisalignment, points_on(model.faces[0].surface, 500, 0.05, 10));
  pts[17] = Point3(std::nan(""), 0.0, 0.0);
  const RegistrationResult s = register_points(locator, pts);
  ASSERT_TRUE(s.converged()) << s.stop_reason;
  EXPECT_FALSE(s.matches[17].inlier);
  EXPECT_EQ(s.matches[17].status, nurbs::ClosestPointStatus::NumericalError);
  EXPECT_EQ(s.used, 499);
}

TEST(Icp, PointToPointApproachesTheTruthAndPointToPlaneIsFaster) {
  const cad::Model model = single_face_model(freeform());
  const cad::ModelLocator locator(model);
  const std::vector<Point3> nominal = points_on(model.faces[0].surface, 3000, 0.03, 12);
  const std::vector<Point3> measured = moved(kMisalignment, nominal);
  RegistrationOptions o;
  o.metric = Metric::PointToPoint;
  o.criteria.max_iterations = 300;
  const RegistrationResult p2p = register_points(locator, measured, o);
  const RegistrationResult p2l = register_points(locator, measured);
  const double e2p = largest_disagreement(p2p.transform, kMisalignment, nominal);
  std::cout << "[ measured ] point-to-point: " << p2p.iterations << " iterations, largest error " << e2p
            << " mm; point-to-plane: " << p2l.iterations << " iterations\n";
  EXPECT_LT(e2p, 1e-4);
  EXPECT_LT(p2l.iterations, p2p.iterations);
}

}  // namespace
}  // namespace probecomp::registration
