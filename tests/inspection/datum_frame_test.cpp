// Datum reference frames against closed forms, on a block with a hole that OpenCASCADE builds (60 × 40 × 20 mm, hole
// of radius 5 at (40, 20) along z). The "measured" contact points are the actual part's, placed by a known pose; the
// registration's transform handed over is deliberately not that pose, since a frame must not depend on it.
//   A  the bottom (z = 0)       B  the front (y = 0)       C  the left end (x = 0)       D  the hole
// Every figure expected below is the exact geometry of the actual part in the frame, derived in the comments.

#include "probecomp/inspection/datum_frame.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "probecomp/inspection/characteristics.hpp"
#include "probecomp/registration/constraints.hpp"
#include "support/prismatic_parts.hpp"

namespace probecomp::inspection {
namespace {

using geometry::RigidTransform;

// The model first (bases are built in their order), then its faces.
struct BlockModel {
  cad::Model model = testing::block_with_hole();
};
struct Block : BlockModel, testing::BlockWithHoleFaces {
  Block() : testing::BlockWithHoleFaces(testing::faces_of_block_with_hole(model)) {}
};

const Block& block() {
  static const Block b;
  return b;
}

// The actual part's points, in its own frame, by face: the nominal points each map to their actual place.
struct Part {
  std::function<Point3(const Point3&)> bottom = [](const Point3& p) { return p; };
  std::function<Point3(const Point3&)> left = [](const Point3& p) { return p; };
  std::function<Point3(const Point3&)> hole = [](const Point3& p) { return p; };
};

// The actual pose of the part on the machine, and a registration 0.05° and 10 µm away from it.
RigidTransform actual_pose() {
  return Eigen::Translation3d(0.4, -0.3, 0.2) * Eigen::AngleAxisd(0.3 * M_PI / 180, Vector3(1, 2, 3).normalized());
}
RigidTransform registered_pose() {
  return actual_pose() * Eigen::Translation3d(0.01, 0.0, -0.01) * Eigen::AngleAxisd(0.05 * M_PI / 180, Vector3::UnitZ());
}

void add(compensation::CompensationResult& r, const Point3& actual, int face, double u) {
  compensation::CompensatedPoint p;
  p.status = compensation::PointStatus::Ok;
  p.face = face;
  p.contact = actual_pose() * actual;
  p.uncertainty = u;
  r.points.push_back(p);
}

// Grids on every face (away from the hole), `u` on each point.
compensation::CompensationResult measure(const Part& part, double u = 0.001) {
  const Block& b = block();
  compensation::CompensationResult r;
  r.registration.transform = registered_pose();
  for (double x = 5; x <= 55; x += 5) {
    for (double y = 5; y <= 35; y += 5) {
      if (std::hypot(x - 40, y - 20) < 7) continue;
      add(r, part.bottom(Point3(x, y, 0)), b.bottom, u);
      add(r, Point3(x, y, 20), b.top, u);
    }
  }
  for (double z = 4; z <= 16; z += 4) {
    for (double x = 5; x <= 55; x += 5) {
      add(r, Point3(x, 0, z), b.front, u);
      add(r, Point3(x, 40, z), b.back, u);
    }
    for (double y = 5; y <= 35; y += 5) {
      add(r, part.left(Point3(0, y, z)), b.left, u);
      add(r, Point3(60, y, z), b.right, u);
    }
    for (int k = 0; k < 12; ++k) {
      const double phi = 2 * M_PI * k / 12;
      add(r, part.hole(Point3(40 + 5 * std::cos(phi), 20 + 5 * std::sin(phi), z)), b.hole, u);
    }
  }
  return r;
}

// The signed deviations (+ outside the material) of a face's points in the frame of `datums`: its profile's min and
// max, with the motions the frame leaves free best-fitted as the characteristic does.
CharacteristicResult profile(const compensation::CompensationResult& r, int face, std::vector<std::string> datums) {
  const Block& b = block();
  Specification spec;
  spec.datums = {{"A", {b.bottom}}, {"B", {b.front}}, {"C", {b.left}}, {"D", {b.hole}}, {"T", {b.top}}};
  spec.characteristics = {{.name = "P", .faces = {face}, .tolerance = 0.1, .outside = {}, .datums = std::move(datums)}};
  return evaluate(spec, b.model, r).characteristics.at(0);
}

// The same of `face` of another part, in the frame of one datum on its face `datum_face`.
CharacteristicResult profile_to(const cad::Model& model, const compensation::CompensationResult& r, int datum_face,
                                int face) {
  Specification spec;
  spec.datums = {{"D", {datum_face}}};
  spec.characteristics = {{.name = "P", .faces = {face}, .tolerance = 0.1, .outside = {}, .datums = {"D"}}};
  return evaluate(spec, model, r).characteristics.at(0);
}

TEST(DatumFrame, APrimaryPlaneTiltedUnderThePartTiltsTheTopInItsFrame) {
  // The bottom's actual points lie on z = s(x − 30): the frame turns the part by θ = atan s about y through (30, ·, 0)
  // to lay that plane on z = 0, so the top's point (x, y, 20) goes to z' = 20 cos θ − (x − 30) sin θ.
  constexpr double s = 1e-3;
  Part part;
  part.bottom = [](const Point3& p) { return Point3(p.x(), p.y(), s * (p.x() - 30)); };
  const compensation::CompensationResult r = measure(part);
  const double theta = std::atan(s);
  const auto d = [&](double x) { return 20 * std::cos(theta) - (x - 30) * std::sin(theta) - 20; };
  for (const std::vector<std::string>& datums : {std::vector<std::string>{"A"}, {"A", "B", "C"}, {"A", "C", "B"}}) {
    const CharacteristicResult c = profile(r, block().top, datums);
    SCOPED_TRACE(datums.size());
    ASSERT_NE(c.decision, Decision::NotEvaluated) << c.reason;
    EXPECT_NEAR(c.min, d(55), 1e-7);
    EXPECT_NEAR(c.max, d(5), 1e-7);
    EXPECT_NEAR(c.value, 2 * std::max(std::abs(d(5)), std::abs(d(55))), 1e-7);
  }
  // Form alone (no datums) sees the top as flat.
  EXPECT_LT(profile(r, block().top, {}).value, 1e-7);
  const DatumFrame frame = establish_frame({{"A", {block().bottom}}}, block().model, r);
  ASSERT_TRUE(frame.ok()) << frame.reason;
  EXPECT_EQ(frame.datums.at(0).fixes, 3);
  EXPECT_EQ(frame.fixed(), 3);
  EXPECT_LT(frame.datums.at(0).rms, 1e-8);
}

TEST(DatumFrame, DatumsAreTakenInTheirOrder) {
  // The left end's actual points lie on x = t(y − 20), turned about z. As tertiary (A|B|C) it fixes only the
  // translation along x, by its points' mean x, 0: the right end stays where it is. As secondary (A|C|B) it fixes the
  // turn about z too, γ = atan t, so the right end's point (60, y) goes to x' = 60 cos γ − (y − 20) sin γ.
  constexpr double t = 2e-3;
  Part part;
  part.left = [](const Point3& p) { return Point3(t * (p.y() - 20), p.y(), p.z()); };
  const compensation::CompensationResult r = measure(part);
  const CharacteristicResult abc = profile(r, block().right, {"A", "B", "C"});
  ASSERT_NE(abc.decision, Decision::NotEvaluated) << abc.reason;
  EXPECT_NEAR(abc.min, 0.0, 1e-7);
  EXPECT_NEAR(abc.max, 0.0, 1e-7);
  const double gamma = std::atan(t);
  const auto d = [&](double y) { return 60 * std::cos(gamma) - (y - 20) * std::sin(gamma) - 60; };
  const CharacteristicResult acb = profile(r, block().right, {"A", "C", "B"});
  ASSERT_NE(acb.decision, Decision::NotEvaluated) << acb.reason;
  EXPECT_NEAR(acb.min, d(35), 1e-7);
  EXPECT_NEAR(acb.max, d(5), 1e-7);
  const DatumFrame frame = establish_frame({{"A", {block().bottom}}, {"B", {block().front}}, {"C", {block().left}}},
                                           block().model, r);
  ASSERT_TRUE(frame.ok()) << frame.reason;
  EXPECT_EQ(frame.datums.at(0).fixes, 3);
  EXPECT_EQ(frame.datums.at(1).fixes, 2);
  EXPECT_EQ(frame.datums.at(2).fixes, 1);
  EXPECT_EQ(frame.fixed(), 6);
  // The whole output aligned to A|C|B: every right-end row's deviation is the turned end's, d(y).
  const DatumFrame acb_frame = establish_frame({{"A", {block().bottom}}, {"C", {block().left}}, {"B", {block().front}}},
                                         block().model, r);
  ASSERT_TRUE(acb_frame.ok()) << acb_frame.reason;
  const compensation::CompensationResult out = aligned(r, acb_frame, block().model);
  int rows = 0;
  for (const compensation::CompensatedPoint& p : out.points) {
    if (p.face != block().right) continue;
    const Point3 on_part = actual_pose().inverse() * p.contact;
    EXPECT_NEAR(p.deviation, d(on_part.y()), 1e-7);
    ++rows;
  }
  EXPECT_EQ(rows, 28);
}

// The least and largest deviation of points turned by the θ that minimises Σ d(p, θ)² (golden-section search; the
// sum is convex over these small angles).
std::pair<double, double> best_turned(const std::vector<Point3>& points, const std::function<double(const Point3&, double)>& d) {
  const auto sum = [&](double theta) {
    double s = 0;
    for (const Point3& p : points) s += d(p, theta) * d(p, theta);
    return s;
  };
  double lo = -0.01, hi = 0.01;
  const double g = (std::sqrt(5.0) - 1) / 2;
  while (hi - lo > 1e-13) {
    const double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
    (sum(a) < sum(b) ? hi : lo) = sum(a) < sum(b) ? b : a;
  }
  const double theta = 0.5 * (lo + hi);
  double least = INFINITY, largest = -INFINITY;
  for (const Point3& p : points) {
    least = std::min(least, d(p, theta));
    largest = std::max(largest, d(p, theta));
  }
  return {least, largest};
}

TEST(DatumFrame, AHoleAsSecondaryDatumCentresItsAxisWhateverItsSize) {
  // The hole is 5 µm larger in radius than drawn and its axis is at (40.02, 19.99): A|D moves the part by
  // (−0.02, +0.01), so the right end (outward +x) is 0.02 mm inside the material and the back (outward +y) 0.01 mm
  // outside. The turn θ about the hole's axis is left free, and best-fitted to each face's own points (least squares):
  // it takes the right end's point (59.98, y + 0.01) and the back's (x − 0.02, 40.01) round (40, 20), trading
  // against their offsets (best_turned).
  Part part;
  part.hole = [](const Point3& p) -> Point3 {  // a Point3, not an Eigen expression of the local `radial`
    const Vector3 radial = Vector3(p.x() - 40, p.y() - 20, 0).normalized();
    return Point3(40.02, 19.99, p.z()) + 5.005 * radial;
  };
  const compensation::CompensationResult r = measure(part);
  std::vector<Point3> right_points, back_points;
  for (double z = 4; z <= 16; z += 4) {
    for (double y = 5; y <= 35; y += 5) right_points.push_back(Point3(59.98, y + 0.01, z));
    for (double x = 5; x <= 55; x += 5) back_points.push_back(Point3(x - 0.02, 40.01, z));
  }
  const auto right_d = [](const Point3& p, double theta) {
    return 40 + std::cos(theta) * (p.x() - 40) - std::sin(theta) * (p.y() - 20) - 60;
  };
  const auto back_d = [](const Point3& p, double theta) {
    return 20 + std::sin(theta) * (p.x() - 40) + std::cos(theta) * (p.y() - 20) - 40;
  };
  const CharacteristicResult right = profile(r, block().right, {"A", "D"});
  ASSERT_NE(right.decision, Decision::NotEvaluated) << right.reason;
  EXPECT_NEAR(right.min, best_turned(right_points, right_d).first, 1e-7);
  EXPECT_NEAR(right.max, best_turned(right_points, right_d).second, 1e-7);
  const CharacteristicResult back = profile(r, block().back, {"A", "D"});
  EXPECT_NEAR(back.min, best_turned(back_points, back_d).first, 1e-7);
  EXPECT_NEAR(back.max, best_turned(back_points, back_d).second, 1e-7);
  const DatumFrame frame = establish_frame({{"A", {block().bottom}}, {"D", {block().hole}}}, block().model, r);
  ASSERT_TRUE(frame.ok()) << frame.reason;
  EXPECT_EQ(frame.datums.at(1).fixes, 2);
  EXPECT_EQ(frame.fixed(), 5);
  ASSERT_TRUE(frame.datums.at(1).size_change.has_value());
  EXPECT_NEAR(*frame.datums.at(1).size_change, 0.005, 1e-8);
  EXPECT_LT(frame.datums.at(1).rms, 1e-8);
  // Their directions on the nominal (QIF's DatumPrecedence): the bottom's outward normal, the hole's axis (z either way).
  ASSERT_TRUE(frame.datums.at(0).axis && frame.datums.at(1).axis);
  EXPECT_LT((*frame.datums.at(0).axis - Vector3(0, 0, -1)).norm(), 1e-12);
  EXPECT_LT(frame.datums.at(1).axis->cross(Vector3::UnitZ()).norm(), 1e-12);
  // As the primary datum, an axis fixes four motions.
  const DatumFrame alone = establish_frame({{"D", {block().hole}}}, block().model, r);
  ASSERT_TRUE(alone.ok()) << alone.reason;
  EXPECT_EQ(alone.fixed(), 4);
}

// A cone as the primary datum (a countersink): it fixes its axis and its place along it, five motions, not the turn
// about its axis. The pocket is 0.02, −0.01 and 0.015 mm off in x, y and z: in its frame the part moves back by that,
// so the flat top (outward +z) is 0.015 mm inside the material everywhere, and the cone's points lie on the nominal.
TEST(DatumFrame, ACountersinkAsDatumFixesFiveMotionsAndCentresThePart) {
  const cad::Model model = testing::block_with_countersink();
  const auto radius_at = [](double z) { return 4.0 + (z - 12.0) * 5.0 / 9.0; };
  const int cone = testing::face_through(model, Point3(30.0 + radius_at(16.0), 20.0, 16.0));
  const int top = testing::face_through(model, Point3(5, 5, 20));
  const Vector3 off(0.02, -0.01, 0.015);
  compensation::CompensationResult r;
  r.registration.transform = registered_pose();
  for (double z = 13; z <= 19; z += 2) {
    for (int k = 0; k < 12; ++k) {
      const double phi = 2 * M_PI * k / 12;
      add(r, Point3(30, 20, z) + radius_at(z) * Vector3(std::cos(phi), std::sin(phi), 0) + off, cone, 0.001);
    }
  }
  for (double x = 5; x <= 55; x += 5) {
    for (double y = 5; y <= 35; y += 5) {
      if (std::hypot(x - 30, y - 20) > 10) add(r, Point3(x, y, 20), top, 0.001);
    }
  }
  const DatumFrame frame = establish_frame({{"K", {cone}}}, model, r);
  ASSERT_TRUE(frame.ok()) << frame.reason;
  EXPECT_EQ(frame.fixed(), 5);
  EXPECT_FALSE(frame.datums.at(0).size_change.has_value());  // a cone's size is its place along its axis
  EXPECT_LT(frame.datums.at(0).rms, 1e-8);
  const CharacteristicResult c = profile_to(model, r, cone, top);
  ASSERT_NE(c.decision, Decision::NotEvaluated) << c.reason;
  EXPECT_NEAR(c.min, -0.015, 1e-7);
  EXPECT_NEAR(c.max, -0.015, 1e-7);
}

// A torus as the primary datum (a boss's rounded top edge, R = 13, r = 12 about z at height 18): as the cone, it
// fixes five motions. The fillet is 0.01, 0.02 and −0.012 mm off: in its frame the flat top is 0.012 mm outside.
TEST(DatumFrame, AFilletAsDatumFixesFiveMotionsAndCentresThePart) {
  const cad::Model model = testing::filleted_boss();
  const auto on_fillet = [](double u, double v) {
    return Point3((13 + 12 * std::cos(v)) * std::cos(u), (13 + 12 * std::cos(v)) * std::sin(u), 18 + 12 * std::sin(v));
  };
  const int fillet = testing::face_through(model, on_fillet(0.3, 0.7));
  const int top = testing::face_through(model, Point3(2, 3, 30));
  const Vector3 off(0.01, 0.02, -0.012);
  compensation::CompensationResult r;
  r.registration.transform = registered_pose();
  for (int i = 0; i < 12; ++i) {
    for (const double v : {0.3, 0.7, 1.1}) add(r, on_fillet(2 * M_PI * i / 12, v) + off, fillet, 0.001);
  }
  for (double x = -8; x <= 8; x += 4) {
    for (double y = -8; y <= 8; y += 4) add(r, Point3(x, y, 30), top, 0.001);
  }
  const DatumFrame frame = establish_frame({{"F", {fillet}}}, model, r);
  ASSERT_TRUE(frame.ok()) << frame.reason;
  EXPECT_EQ(frame.fixed(), 5);
  EXPECT_LT(frame.datums.at(0).rms, 1e-8);
  const CharacteristicResult c = profile_to(model, r, fillet, top);
  ASSERT_NE(c.decision, Decision::NotEvaluated) << c.reason;
  EXPECT_NEAR(c.min, 0.012, 1e-7);
  EXPECT_NEAR(c.max, 0.012, 1e-7);
}

TEST(DatumFrame, ThreeTwoOnePointsFixEveryMotion) {
  // The paper's step 1: three points on the bottom, two on the front, one on the left end. The actual part's bottom
  // is 0.01 mm up, its front 0.02 mm back (−y) and its left end 0.005 mm in (+x): the frame shifts it by
  // (−0.005, +0.02, −0.01), so its top is 0.01 mm in, its back 0.02 mm out and its right end 0.005 mm in.
  const Block& b = block();
  compensation::CompensationResult r;
  r.registration.transform = registered_pose();
  for (const Point3& p : {Point3(5, 5, 0.01), Point3(55, 5, 0.01), Point3(20, 35, 0.01)}) add(r, p, b.bottom, 0.001);
  for (const Point3& p : {Point3(5, -0.02, 10), Point3(55, -0.02, 10)}) add(r, p, b.front, 0.001);
  add(r, Point3(0.005, 20, 10), b.left, 0.001);
  for (double y = 5; y <= 35; y += 10) {
    for (double z = 4; z <= 16; z += 4) add(r, Point3(60, y, z), b.right, 0.001);
  }
  const DatumFrame frame = establish_frame({{"A", {b.bottom}}, {"B", {b.front}}, {"C", {b.left}}}, b.model, r);
  ASSERT_TRUE(frame.ok()) << frame.reason;
  EXPECT_EQ(frame.datums.at(0).fixes, 3);
  EXPECT_EQ(frame.datums.at(1).fixes, 2);
  EXPECT_EQ(frame.datums.at(2).fixes, 1);
  const CharacteristicResult right = profile(r, b.right, {"A", "B", "C"});
  ASSERT_NE(right.decision, Decision::NotEvaluated) << right.reason;
  EXPECT_NEAR(right.min, -0.005, 1e-7);
  EXPECT_NEAR(right.max, -0.005, 1e-7);
}

// The top's profile in A|B|C, A on the bottom by `targets`, B the front, C the left.
Specification top_in_abc(const std::vector<Target>& targets) {
  const Block& b = block();
  Specification spec;
  spec.datums = {{.name = "A", .faces = {b.bottom}, .fit = DatumFit::LeastSquares, .targets = targets},
                 {"B", {b.front}}, {"C", {b.left}}};
  spec.characteristics = {{.name = "P", .faces = {b.top}, .tolerance = 0.1, .outside = {}, .datums = {"A", "B", "C"}}};
  return spec;
}

// `spec` (top_in_abc) on `r`: the top 0.01 mm in, A fitted to `a_points` touches that fix 3 motions.
void expect_top_a_hundredth_in(const Specification& spec, const compensation::CompensationResult& r, int a_points) {
  const Inspection judged = evaluate(spec, block().model, r);
  const CharacteristicResult& top = judged.characteristics.at(0);
  ASSERT_NE(top.decision, Decision::NotEvaluated) << top.reason;
  EXPECT_NEAR(top.min, -0.01, 1e-7);
  EXPECT_NEAR(top.max, -0.01, 1e-7);
  const DatumFrame& frame = judged.frames.at("A|B|C");
  EXPECT_EQ(frame.datums.at(0).points, a_points);
  EXPECT_EQ(frame.datums.at(0).fixes, 3);
}

// Datum A by three point targets on the bottom (A1–A3), which is 0.05 mm up everywhere but at them, where it is
// 0.01 mm up: A is the plane through the three touches alone, so in A|B|C the top lies 0.01 mm in (a fit of the
// whole bottom would put it about 0.05 mm in). A target no trusted point touches keeps the frame from being set up.
TEST(DatumFrame, PointTargetsTakeOnlyTheTouchesAtThem) {
  const Block& b = block();
  const std::vector<Target> targets{{"A1", Point3(5, 5, 0)}, {"A2", Point3(55, 5, 0)}, {"A3", Point3(20, 35, 0)}};
  Part part;
  part.bottom = [&](const Point3& p) {
    for (const Target& t : targets) {
      if ((p - t.point).norm() < 1e-9) return Point3(p + Vector3(0, 0, 0.01));
    }
    return Point3(p + Vector3(0, 0, 0.05));
  };
  const compensation::CompensationResult r = measure(part);
  Specification spec = top_in_abc(targets);
  expect_top_a_hundredth_in(spec, r, 3);

  // A3 moved 2.5 mm off the nearest touch.
  spec.datums[0].targets[2].point = Point3(22.5, 35, 0);
  const CharacteristicResult off = evaluate(spec, b.model, r).characteristics.at(0);
  EXPECT_EQ(off.decision, Decision::NotEvaluated);
  EXPECT_NE(off.reason.find("datum A: no trusted point within 1 mm of its target A3 (22.500, 35.000, 0.000)"),
            std::string::npos) << off.reason;
}

// Datum A by two line targets across the bottom (A1 at x = 5, A2 at x = 55, along y over its 40 mm), the bottom 0.01
// mm up along them and 0.05 mm up elsewhere: A is the plane on the touches along the lines alone (two lines fix its
// height and both tilts), so in A|B|C the top lies 0.01 mm in. A line no trusted point touches is named.
TEST(DatumFrame, LineTargetsTakeOnlyTheTouchesAlongThem) {
  const Block& b = block();
  const std::vector<Target> targets{{"A1", Point3(5, 20, 0), Vector3::UnitY(), 20.0},
                                    {"A2", Point3(55, 20, 0), Vector3::UnitY(), 20.0}};
  Part part;
  part.bottom = [&](const Point3& p) {
    const bool on_line = std::abs(p.x() - 5) < 1e-9 || std::abs(p.x() - 55) < 1e-9;
    return Point3(p + Vector3(0, 0, on_line ? 0.01 : 0.05));
  };
  const compensation::CompensationResult r = measure(part);
  Specification spec = top_in_abc(targets);
  expect_top_a_hundredth_in(spec, r, 14);  // the grid's 7 touches along each line

  // A2 moved to x = 22.5, 2.5 mm from the nearest touches.
  spec.datums[0].targets[1].point = Point3(22.5, 20, 0);
  const CharacteristicResult off = evaluate(spec, b.model, r).characteristics.at(0);
  EXPECT_EQ(off.decision, Decision::NotEvaluated);
  EXPECT_NE(off.reason.find("datum A: no trusted point within 1 mm of its line target A2 (20.000 mm either side of "
                            "(22.500, 20.000, 0.000) along (0.0000, 1.0000, 0.0000))"),
            std::string::npos) << off.reason;
}

TEST(DatumFrame, ItsUncertaintyIsThatOfTheLeastSquaresPlane) {
  // n points with standard uncertainty u on the bottom: the least-squares plane's height at (x, y) has the variance
  // u²(1/n + gᵀS⁻¹g), g = (x − x̄, y − ȳ), S the points' scatter matrix Σ gᵢgᵢᵀ, and the top's
  // deviation at (x, y) moves with it.
  const Block& b = block();
  constexpr double u = 0.002;
  compensation::CompensationResult r;
  r.registration.transform = registered_pose();
  std::vector<Point3> grid;
  for (double x = 6; x <= 30; x += 6) {
    for (double y = 8; y <= 32; y += 12) {
      grid.push_back(Point3(x, y, 0));
      add(r, grid.back(), b.bottom, u);
    }
  }
  const DatumFrame frame = establish_frame({{"A", {b.bottom}}}, b.model, r);
  ASSERT_TRUE(frame.ok()) << frame.reason;
  // The frame leaves the motions in the plane where the registration put them: the points' x and y as it sees them.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (Point3& p : grid) {
    p = frame.transform.inverse() * (actual_pose() * p);
    mean += p.head<2>() / static_cast<double>(grid.size());
  }
  Eigen::Matrix2d S = Eigen::Matrix2d::Zero();
  for (const Point3& p : grid) S += (p.head<2>() - mean) * (p.head<2>() - mean).transpose();
  registration::Constraints c;
  c.centre = frame.centre;
  c.length = frame.length;
  c.covariance = frame.covariance;
  for (const Point3& top : {Point3(6, 8, 20), Point3(55, 35, 20), Point3(18, 20, 20)}) {
    const Eigen::Vector2d g = top.head<2>() - mean;
    const double expected = u * u * (1.0 / static_cast<double>(grid.size()) + g.dot(S.inverse() * g));
    EXPECT_NEAR(registration::normal_variance(c, top, Vector3::UnitZ()), expected, 1e-6 * expected);
  }
}

TEST(DatumFrame, ATangentPlaneRestsOnTheOutermostPoints) {
  // The bottom is dished: its points lie at z = −k r², r from (30, 20), lowest (outermost) at the grid's four
  // corners, r² = 25² + 15². A tangent datum rests the part on them (a surface plate's contact: horizontal by
  // symmetry, every point inside the material), so the top, 20 mm above, is k·850 out. Least squares puts the
  // datum on the points' least-squares plane z = a + bx + cy instead (solved here by QR): the top's point (x, y) is
  // −(a + bx + cy) out, to first order in the plane's slopes (about 1e-6: the rest is below 1e-9 mm).
  constexpr double k = 1e-5;
  Part part;
  part.bottom = [](const Point3& p) { return Point3(p.x(), p.y(), -k * (std::pow(p.x() - 30, 2) + std::pow(p.y() - 20, 2))); };
  const compensation::CompensationResult r = measure(part);
  const Block& b = block();
  std::vector<Point3> grid;
  for (double x = 5; x <= 55; x += 5) {
    for (double y = 5; y <= 35; y += 5) {
      if (std::hypot(x - 40, y - 20) >= 7) grid.push_back(part.bottom(Point3(x, y, 0)));
    }
  }
  Eigen::MatrixXd M(grid.size(), 3);
  Eigen::VectorXd z(grid.size());
  for (std::size_t i = 0; i < grid.size(); ++i) {
    M.row(static_cast<Eigen::Index>(i)) << 1.0, grid[i].x(), grid[i].y();
    z(static_cast<Eigen::Index>(i)) = grid[i].z();
  }
  const Eigen::Vector3d plane = M.colPivHouseholderQr().solve(z);
  double ls_min = INFINITY, ls_max = -INFINITY;
  for (const Point3& p : grid) {
    const double d = -(plane(0) + plane(1) * p.x() + plane(2) * p.y());
    ls_min = std::min(ls_min, d);
    ls_max = std::max(ls_max, d);
  }
  Specification spec;
  spec.datums = {{"A", {b.bottom}, DatumFit::Tangent}, {"L", {b.bottom}}};
  spec.characteristics = {{.name = "T", .faces = {b.top}, .tolerance = 0.1, .outside = {}, .datums = {"A"}},
                          {.name = "L", .faces = {b.top}, .tolerance = 0.1, .outside = {}, .datums = {"L"}}};
  const Inspection judged = evaluate(spec, b.model, r);
  const CharacteristicResult& tangent = judged.characteristics.at(0);
  const CharacteristicResult& least_squares = judged.characteristics.at(1);
  ASSERT_NE(tangent.decision, Decision::NotEvaluated) << tangent.reason;
  EXPECT_NEAR(tangent.min, k * 850, 1e-7);
  EXPECT_NEAR(tangent.max, k * 850, 1e-7);
  EXPECT_NEAR(least_squares.min, ls_min, 1e-7);
  EXPECT_NEAR(least_squares.max, ls_max, 1e-7);
  const DatumResult& a = judged.datums.at(0).datum;
  EXPECT_EQ(a.fit, DatumFit::Tangent);
  EXPECT_EQ(a.fixes, 3);
  // The tangent datum rests on four points: the datum's share of the top's u is theirs, not the mean of 72.
  const DatumFrame frame = establish_frame({spec.datums[0]}, b.model, r);
  ASSERT_TRUE(frame.ok()) << frame.reason;
  registration::Constraints c;
  c.centre = frame.centre;
  c.length = frame.length;
  c.covariance = frame.covariance;
  const DatumFrame ls = establish_frame({spec.datums[1]}, b.model, r);
  registration::Constraints cl = c;
  cl.covariance = ls.covariance;
  EXPECT_GT(registration::normal_variance(c, Point3(30, 20, 20), Vector3::UnitZ()),
            2 * registration::normal_variance(cl, Point3(30, 20, 20), Vector3::UnitZ()));
}

// A cylinder datum after plane A, fitted tangent and by least squares: it fixes the two translations A left, its
// size change is `sizes` (tangent, least squares), and the actual axis point `on_axis` lands on the nominal axis
// at `centre` (x and y).
void expect_cylinder_datum(const cad::Model& model, const compensation::CompensationResult& r, int plane, int cylinder,
                           std::pair<double, double> sizes, const Point3& on_axis, const Point3& centre) {
  for (const DatumFit fit : {DatumFit::Tangent, DatumFit::LeastSquares}) {
    const DatumFrame frame = establish_frame({{"A", {plane}}, {"D", {cylinder}, fit}}, model, r);
    ASSERT_TRUE(frame.ok()) << frame.reason;
    EXPECT_EQ(frame.datums.at(1).fixes, 2);
    ASSERT_TRUE(frame.datums.at(1).size_change.has_value());
    EXPECT_NEAR(*frame.datums.at(1).size_change, fit == DatumFit::Tangent ? sizes.first : sizes.second, 1e-8)
        << to_string(fit);
    const Point3 axis = frame.transform.inverse() * (actual_pose() * on_axis);
    EXPECT_NEAR(axis.x(), centre.x(), 1e-8) << to_string(fit);
    EXPECT_NEAR(axis.y(), centre.y(), 1e-8) << to_string(fit);
  }
}

TEST(DatumFrame, ATangentHoleIsItsLargestInscribedCylinder) {
  // The hole's radius is 5.005 + 0.003 cos 3φ about (40.02, 19.99): its twelve points per height reach in to 5.002
  // at φ = 60°, 180° and 300°, three contacts 120° apart, so the largest inscribed cylinder is centred on the axis
  // with radius 5.002 (least squares: 5.005). Either moves the part by (−0.02, +0.01).
  Part part;
  part.hole = [](const Point3& p) -> Point3 {
    const double phi = std::atan2(p.y() - 20, p.x() - 40);
    return Point3(40.02, 19.99, p.z()) + (5.005 + 0.003 * std::cos(3 * phi)) * Vector3(std::cos(phi), std::sin(phi), 0);
  };
  const compensation::CompensationResult r = measure(part);
  // The hole's axis goes to (40, 20): the actual axis point (40.02, 19.99, 10) lands there.
  expect_cylinder_datum(block().model, r, block().bottom, block().hole, {0.002, 0.005}, Point3(40.02, 19.99, 10),
                        Point3(40, 20, 10));
}

TEST(DatumFrame, APinsTangentDatumIsItsSmallestCircumscribedCylinder) {
  // A pin of radius 4 whose actual radius is 4.002 + 0.003 cos 3φ about (20.01, 19.98): its twelve points per height
  // reach out to 4.005 at φ = 0°, 120° and 240°, three contacts 120° apart, so the smallest circumscribed cylinder is
  // centred on the axis with radius 4.005 (least squares: 4.002). Either centres the axis at (20, 20).
  const cad::Model model = testing::block_with_pin();
  const int bottom = testing::face_through(model, Point3(5, 5, 0));
  const int pin = testing::face_through(model, Point3(24, 20, 15));
  compensation::CompensationResult r;
  r.registration.transform = registered_pose();
  for (double x = 5; x <= 35; x += 10) {
    for (double y = 5; y <= 35; y += 10) add(r, Point3(x, y, 0), bottom, 0.001);
  }
  for (double z = 12; z <= 20; z += 4) {
    for (int k = 0; k < 12; ++k) {
      const double phi = 2 * M_PI * k / 12;
      const double radius = 4.002 + 0.003 * std::cos(3 * phi);
      add(r, Point3(20.01 + radius * std::cos(phi), 19.98 + radius * std::sin(phi), z), pin, 0.001);
    }
  }
  expect_cylinder_datum(model, r, bottom, pin, {0.005, 0.002}, Point3(20.01, 19.98, 15), Point3(20, 20, 15));
}

TEST(DatumFrame, AFrameThatCannotBeSetUpSaysWhy) {
  const Block& b = block();
  const compensation::CompensationResult r = measure(Part{});
  // The top, parallel to the bottom, fixes nothing the bottom left free.
  const DatumFrame parallel = establish_frame({{"A", {b.bottom}}, {"T", {b.top}}}, b.model, r);
  EXPECT_FALSE(parallel.ok());
  EXPECT_NE(parallel.reason.find("points fix no motion the datums before it left free"), std::string::npos) << parallel.reason;
  compensation::CompensationResult no_left = r;
  std::erase_if(no_left.points, [&](const compensation::CompensatedPoint& p) { return p.face == b.left; });
  const CharacteristicResult c = profile(no_left, b.right, {"A", "B", "C"});
  EXPECT_EQ(c.decision, Decision::NotEvaluated);
  EXPECT_EQ(c.reason, "datum reference frame A|B|C: datum C: no trusted point on its faces");
}

}  // namespace
}  // namespace probecomp::inspection
