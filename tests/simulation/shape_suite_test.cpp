// The shape suite's deformation families against their closed forms, their actual surfaces against the intended
// shape, and the fixed list against what issue 48 asks of it (every family, base, sampling and noise level).

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "probecomp/cad/locator.hpp"
#include "probecomp/nurbs/surface.hpp"
#include "probecomp/simulation/deformation.hpp"
#include "probecomp/simulation/shape_suite.hpp"

namespace {

using namespace probecomp;

TEST(Deformation, CreaseIsTheSmoothedStepOfItsClosedForm) {
  simulation::Deformation d;
  d.creases.push_back({.origin = Point3(1, 2, 0), .direction = Vector3(0, 1, 0), .height = 0.2, .width = 2.0});
  EXPECT_NEAR(d.displacement(Point3(5, 2, 3)), 0.1, 1e-15);  // on the line: half the step, whatever x and z
  EXPECT_NEAR(d.displacement(Point3(0, 3, 0)), 0.1 * (1.0 + std::tanh(1.0)), 1e-15);  // w/2 across: 88 %
  EXPECT_NEAR(d.displacement(Point3(0, 1, 0)), 0.1 * (1.0 - std::tanh(1.0)), 1e-15);
  EXPECT_NEAR(d.displacement(Point3(0, 40, 0)), 0.2, 1e-15);
  EXPECT_NEAR(d.displacement(Point3(0, -40, 0)), 0.0, 1e-15);
  // Refined near the line (half the width), not far from it, where the step is flat.
  EXPECT_DOUBLE_EQ(d.feature_length(Point3(0, 2.5, 0)), 1.0);
  EXPECT_TRUE(std::isinf(d.feature_length(Point3(0, 40, 0))));
}

TEST(Deformation, TwistIsTheHyperbolicParaboloidOfItsClosedForm) {
  simulation::Deformation d;
  const Vector3 a = Vector3(1, 1, 0).normalized(), b = Vector3(-1, 1, 0).normalized();
  d.twists.push_back({.origin = Point3(0, 0, 1), .first = a, .second = b, .amplitude = 0.3, .length = 10.0});
  for (const Point3& x : {Point3(3, 4, 7), Point3(-2, 5, 0), Point3(10, 0, 1)}) {
    const double s = a.dot(x - Point3(0, 0, 1)), t = b.dot(x - Point3(0, 0, 1));
    EXPECT_NEAR(d.displacement(x), 0.3 * s * t / 100.0, 1e-15);
  }
  // Turned 45° from the axes it is a saddle: 0.3 (y² − x²) / 200.
  EXPECT_NEAR(d.displacement(Point3(4, 2, 1)), 0.3 * (4.0 - 16.0) / 200.0, 1e-15);
}

TEST(Deformation, ABandedWaveDependsOnlyOnTheDistanceAcrossItsBand) {
  simulation::Deformation d;
  d.sinusoids.push_back({.amplitude = 0.1, .wavelength = 8.0, .direction = Vector3::UnitX(), .origin = Point3::Zero(),
                         .window = 3.0, .phase = 90.0, .band = Vector3::UnitY()});
  // Along the band (x) the wave runs at full height; across it (y) the Gaussian window falls.
  EXPECT_NEAR(d.displacement(Point3(0, 0, 0)), 0.1, 1e-15);
  EXPECT_NEAR(d.displacement(Point3(40, 0, 0)), 0.1, 1e-12);  // five wavelengths on: a crest again
  EXPECT_NEAR(d.displacement(Point3(40, 3, 0)), 0.1 * std::exp(-0.5), 1e-12);
  EXPECT_NEAR(d.displacement(Point3(2, 3, 0)), 0.0, 1e-12);  // a quarter wave: a node
}

TEST(Deformation, ACreasedHoodFollowsTheIntendedShape) {
  // The actual surface is what the simulated probe touches: it must be the intended step to far below any noise.
  const cad::Model nominal = simulation::base_model(simulation::BaseSurface::Hood);
  simulation::ShapeCase c;
  c.base = simulation::BaseSurface::Hood;
  c.features.push_back({.kind = simulation::FeatureSpec::Kind::Crease, .u = 0.4, .v = 0.5, .angle = 30.0,
                        .amplitude = 0.3, .size = 3.0});
  const simulation::Deformation d = simulation::deformation_of(c, nominal);
  const nurbs::Surface& s0 = nominal.faces[0].surface;
  cad::Model model = nominal;
  model.faces[0].surface = simulation::deformed_surface(s0, 1, d);
  const cad::ModelLocator locator(model);
  double worst = 0.0;
  for (int a = 1; a < 60; ++a) {
    for (int b = 1; b < 60; ++b) {
      const Point3 x0 = nurbs::evaluate(s0, a / 60.0, b / 60.0);
      const Point3 target = x0 + d.displacement(x0) * nurbs::unit_normal(s0, a / 60.0, b / 60.0).n;
      worst = std::max(worst, locator.closest_point(target).distance);
    }
  }
  // mm: the fit's tolerance (1e-5 at its check points, a little more between them on a 5.7° flank): far below the
  // suite's micrometre bars.
  EXPECT_LT(worst, 5e-5);
  EXPECT_GT(model.faces[0].surface.num_u() * model.faces[0].surface.num_v(), 1000);  // refined along the crease
}

TEST(ShapeSuite, CoversEveryFamilyBaseSamplingAndNoiseLevel) {
  const std::vector<simulation::ShapeCase> suite = simulation::shape_suite();
  EXPECT_GE(suite.size(), 24u);
  std::set<std::string> names;
  std::set<simulation::BaseSurface> bases;
  std::set<simulation::Sampling> samplings;
  std::set<simulation::FeatureSpec::Kind> kinds;
  std::set<long> sigmas;
  bool dent = false, banded = false, whole_face_wave = false, saddle = false, without_normals = false;
  for (const simulation::ShapeCase& c : suite) {
    names.insert(c.name);
    bases.insert(c.base);
    samplings.insert(c.sampling);
    sigmas.insert(std::lround(c.noise_sigma * 1e4));
    without_normals |= c.sampling == simulation::Sampling::Random && !c.approach_normals;
    for (const simulation::FeatureSpec& f : c.features) {
      kinds.insert(f.kind);
      dent |= f.kind == simulation::FeatureSpec::Kind::Bump && f.amplitude < 0.0;
      banded |= f.kind == simulation::FeatureSpec::Kind::Wave && f.band;
      whole_face_wave |= f.kind == simulation::FeatureSpec::Kind::Wave && f.window == 0.0;
      saddle |= f.kind == simulation::FeatureSpec::Kind::Twist && f.angle == 45.0;
    }
  }
  EXPECT_EQ(names.size(), suite.size());
  EXPECT_EQ(bases.size(), 3u);
  EXPECT_EQ(samplings.size(), 3u);
  EXPECT_EQ(kinds.size(), 4u);
  EXPECT_TRUE(dent && banded && whole_face_wave && saddle && without_normals);
  EXPECT_EQ(sigmas, (std::set<long>{0, 15, 30, 45, 100}));  // σ = 0, 1.5, 3, 4.5, 10 µm
}

TEST(ShapeSuite, ScanLinesAreTheAskedSpacingApartAndDenseAlong) {
  simulation::ShapeCase c;
  c.base = simulation::BaseSurface::Panel;
  c.sampling = simulation::Sampling::ScanLines;
  c.points = 7000;
  c.line_spacing = 4.0;
  const cad::Model nominal = simulation::base_model(c.base);
  const std::vector<simulation::ProgrammedPoint> plan = simulation::plan_of(c, nominal);
  ASSERT_GE(plan.size(), 6000u);
  // Consecutive points along a line are close; a jump to the next line is about the spacing.
  int jumps = 0;
  double along = 0.0;
  for (std::size_t k = 1; k < plan.size(); ++k) {
    const double step = (plan[k].point - plan[k - 1].point).norm();
    if (step > 1.0) {
      ++jumps;
      EXPECT_NEAR(step, 4.0, 0.6) << k;
    } else {
      along = std::max(along, step);
    }
  }
  EXPECT_GE(jumps, 10);
  EXPECT_LT(along, 0.25);
}

TEST(ShapeSuite, DrawnCasesDifferAndAreReproducible) {
  const simulation::ShapeCase a = simulation::draw_shape_case(7, 0.003), b = simulation::draw_shape_case(7, 0.003);
  const simulation::ShapeCase c = simulation::draw_shape_case(8, 0.003);
  EXPECT_EQ(a.name, b.name);
  ASSERT_EQ(a.features.size(), b.features.size());
  for (std::size_t k = 0; k < a.features.size(); ++k) EXPECT_EQ(a.features[k].amplitude, b.features[k].amplitude);
  EXPECT_NE(a.rx, c.rx);
}

}  // namespace
