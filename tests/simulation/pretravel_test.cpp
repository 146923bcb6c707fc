// The simulated probe's pre-travel (issue 52, DESIGN.md §8): p(d) = p₀ + b·cos²θ + a·sin²θ·cos(n(φ − φ₀)) against
// its closed form at directions where θ and φ are known by construction, and the simulator reporting the centre
// p(d) on along the travel d = −normal, the touched centre itself unchanged.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "probecomp/cad/locator.hpp"
#include "probecomp/simulation/measure.hpp"
#include "probecomp/simulation/pretravel.hpp"
#include "support/prismatic_parts.hpp"

namespace {

using namespace probecomp;

// Closed forms evaluated in double precision: a few ulps of the millimetre values, and of coordinates up to 60 mm
// (7e-15 mm each) where a reported centre is differenced with the touched one.
constexpr double kExact = 1e-15;
constexpr double kCoordinates = 1e-13;
constexpr double kPretravelDegree = std::numbers::pi / 180.0;

constexpr double kP0 = 0.010, kAxial = 0.003, kLobes = 0.004;  // mm

simulation::Pretravel probe() { return {.constant = kP0, .axial = kAxial, .lobes = kLobes}; }

TEST(Pretravel, AVerticalTouchFromAboveTakesTheConstantPlusTheAxialTerm) {
  // θ = 0: cos²θ = 1, sin²θ = 0, whatever the azimuth.
  EXPECT_NEAR(probe()(-Vector3::UnitZ()), kP0 + kAxial, kExact);
  // From below, θ = 180°: the same cos²θ.
  EXPECT_NEAR(probe()(Vector3::UnitZ()), kP0 + kAxial, kExact);
}

TEST(Pretravel, AHorizontalTouchAlongTheFirstStylusAxisTakesTheConstantPlusALobe) {
  // A stylus pointing down: the first axis of its frame is +x, so d = +x has θ = 90°, φ = 0.
  EXPECT_NEAR(probe()(Vector3::UnitX()), kP0 + kLobes, kExact);
  // d = −x: φ = 180°, cos(3·180°) = −1.
  EXPECT_NEAR(probe()(-Vector3::UnitX()), kP0 - kLobes, kExact);
  // The length of d does not matter.
  EXPECT_NEAR(probe()(Vector3(7.0, 0.0, 0.0)), kP0 + kLobes, kExact);
}

TEST(Pretravel, ThreeLobesPutAValleyAtSixtyDegreesOfAzimuth) {
  // φ = 60°, n = 3: cos(180°) = −1, horizontal (θ = 90°).
  const Vector3 d(std::cos(60.0 * kPretravelDegree), std::sin(60.0 * kPretravelDegree), 0.0);
  EXPECT_NEAR(probe()(d), kP0 - kLobes, kExact);
  // Four lobes: cos(240°) = −1/2.
  simulation::Pretravel four = probe();
  four.lobe_count = 4;
  EXPECT_NEAR(four(d), kP0 - 0.5 * kLobes, kExact);
}

TEST(Pretravel, TheAzimuthIsRightHandedAboutTheStylus) {
  // About a stylus pointing down (−z), right-handed turns +x towards −y. With φ₀ = 10°, φ = +40° gives
  // cos(3·30°) = 0 and φ = −40° gives cos(−150°) = −√3/2; the two differ only if the sense is fixed.
  simulation::Pretravel p = probe();
  p.phase = 10.0;
  const Vector3 plus(std::cos(40.0 * kPretravelDegree), -std::sin(40.0 * kPretravelDegree), 0.0);  // φ = +40°
  const Vector3 minus(std::cos(40.0 * kPretravelDegree), std::sin(40.0 * kPretravelDegree), 0.0);  // φ = −40°
  EXPECT_NEAR(p(plus), kP0, kExact);
  EXPECT_NEAR(p(minus), kP0 - std::sqrt(3.0) / 2.0 * kLobes, kExact);
}

TEST(Pretravel, ATiltedStylusMeasuresItsAnglesFromItsOwnAxis) {
  // A stylus tilted 45° in the xz plane: s = (1, 0, −1)/√2. Its frame's first axis is x made normal to s,
  // e1 = (1, 0, 1)/√2, and e2 = s × e1 = (0, −1, 0) (worked by hand).
  simulation::Pretravel p = probe();
  p.stylus = Vector3(1.0, 0.0, -1.0);
  p.phase = 10.0;
  const Vector3 s = Vector3(1.0, 0.0, -1.0) / std::sqrt(2.0), e1 = Vector3(1.0, 0.0, 1.0) / std::sqrt(2.0),
                e2(0.0, -1.0, 0.0);
  EXPECT_NEAR(p(s), kP0 + kAxial, kExact);
  // θ = 90°, φ = φ₀ + 0: along e1 rotated by the phase, the lobe's peak.
  EXPECT_NEAR(p(std::cos(10.0 * kPretravelDegree) * e1 + std::sin(10.0 * kPretravelDegree) * e2), kP0 + kLobes, kExact);
  // θ = 30°, φ = 50°: cos²θ = 3/4, sin²θ = 1/4, cos(3·40°) = −1/2.
  const double theta = 30.0 * kPretravelDegree, phi = 50.0 * kPretravelDegree;
  const Vector3 d = std::cos(theta) * s + std::sin(theta) * (std::cos(phi) * e1 + std::sin(phi) * e2);
  EXPECT_NEAR(p(d), kP0 + 0.75 * kAxial - 0.125 * kLobes, kExact);
}

TEST(Pretravel, TheMachineReportsTheTouchedCentrePlusThePretravelAlongTheTravel) {
  // The 60 × 40 × 20 mm block (its hole at (40, 20) kept clear of), touched on five faces along their normals.
  const cad::Model block = probecomp::testing::block_with_hole();
  const cad::ModelLocator locator(block);
  constexpr double r = 1.0;
  struct Row {
    simulation::ProgrammedPoint programmed;
    double p;  // p(−normal) in closed form
  };
  const std::vector<Row> rows = {
      {{Point3(10, 10, 20), Vector3::UnitZ()}, kP0 + kAxial},    // from above: θ = 0
      {{Point3(20, 30, 20), Vector3::UnitZ()}, kP0 + kAxial},
      {{Point3(10, 10, 0), -Vector3::UnitZ()}, kP0 + kAxial},    // from below: θ = 180°
      {{Point3(0, 20, 10), -Vector3::UnitX()}, kP0 + kLobes},    // travel +x: φ = 0
      {{Point3(60, 10, 10), Vector3::UnitX()}, kP0 - kLobes},    // travel −x: φ = 180°
      {{Point3(30, 0, 10), -Vector3::UnitY()}, kP0},             // travel ±y: φ = ∓90°, cos(∓270°) = 0
      {{Point3(20, 40, 10), Vector3::UnitY()}, kP0},
  };
  std::vector<simulation::ProgrammedPoint> plan;
  for (const Row& row : rows) plan.push_back(row.programmed);

  const auto plain = simulation::simulate_touches(locator, plan, {.probe_radius = r});
  const auto lobed = simulation::simulate_touches(locator, plan, {.probe_radius = r, .pretravel = probe()});
  const auto noisy = simulation::simulate_touches(locator, plan, {.probe_radius = r, .noise_sigma = 0.001, .seed = 3});
  const auto both = simulation::simulate_touches(locator, plan,
                                                 {.probe_radius = r, .noise_sigma = 0.001, .seed = 3, .pretravel = probe()});
  double worst = 0.0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    ASSERT_EQ(lobed[k].status, simulation::Touch::Status::OK) << k;
    const Vector3 d = -rows[k].programmed.normal;
    // The touched centre is the truth, pre-travel or not: r out from the face along its normal.
    const Point3 centre = rows[k].programmed.point + r * rows[k].programmed.normal;
    EXPECT_LT((lobed[k].centre - centre).norm(), 1e-9) << k;
    EXPECT_EQ(plain[k].measured, plain[k].centre) << k;
    const Vector3 reported = lobed[k].measured - lobed[k].centre;
    worst = std::max(worst, (reported - rows[k].p * d).norm());
    EXPECT_LT((reported - rows[k].p * d).norm(), kCoordinates) << k;
    // The noise is drawn as without pre-travel, and adds to it.
    EXPECT_LT(((both[k].measured - noisy[k].measured) - rows[k].p * d).norm(), kCoordinates) << k;
    EXPECT_EQ(both[k].centre, noisy[k].centre) << k;
  }
  std::printf("measured - centre - p(d) d: at most %.1e mm over %zu touches\n", worst, rows.size());
}

}  // namespace
