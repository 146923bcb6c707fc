// The simulator checked by an independent route (issue 7): OpenCASCADE evaluates the actual surfaces (converted to
// Geom_BSplineSurface) and projects each exact probe centre on them. A touch must put the centre on its
// programmed line, at distance r from the actual part (± 1e-9 mm), on the outside.

#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <Geom_BSplineSurface.hxx>
#include <gp_Pnt.hxx>
#include <gp_Vec.hxx>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/model.hpp"
#include "probecomp/cad/plan.hpp"
#include "probecomp/occt/convert.hpp"
#include "probecomp/simulation/deformation.hpp"
#include "probecomp/simulation/freeform_case.hpp"
#include "probecomp/simulation/measure.hpp"
#include "probecomp/studies/cylinder_study.hpp"

namespace {

using namespace probecomp;

constexpr double kTouchTolerance = 1e-9;  // mm, the issue's

struct Checked {
  int touched = 0;
  double worst_line = 0.0, worst_distance = 0.0, worst_contact = 0.0;
};

// Every touch against OpenCASCADE's projection on the touched face's actual surface.
Checked check_touches(const cad::Model& actual, const std::vector<simulation::ProgrammedPoint>& plan,
                      const std::vector<simulation::Touch>& touches, double r) {
  Checked c;
  std::vector<Handle(Geom_BSplineSurface)> occt;
  // One projector per face, initialised once and reused (its search grid is built in Init).
  std::vector<GeomAPI_ProjectPointOnSurf> projectors(actual.faces.size());
  for (std::size_t f = 0; f < actual.faces.size(); ++f) {
    occt.push_back(occt::to_occt(actual.faces[f].surface));
    double u0, u1, v0, v1;
    occt.back()->Bounds(u0, u1, v0, v1);
    projectors[f].Init(occt.back(), u0, u1, v0, v1);
  }
  for (std::size_t k = 0; k < touches.size(); ++k) {
    const simulation::Touch& t = touches[k];
    if (t.status != simulation::Touch::Status::OK) continue;
    ++c.touched;
    EXPECT_EQ(t.measured, t.centre) << "no noise asked for";
    // On the programmed line: the centre minus the programmed point is along the programmed normal.
    const Vector3 along = t.centre - plan[k].point;
    c.worst_line = std::max(c.worst_line, along.cross(plan[k].normal.normalized()).norm());
    EXPECT_GT(along.dot(plan[k].normal), -r) << k;
    const cad::Face& face = actual.faces.at(static_cast<std::size_t>(t.face));
    GeomAPI_ProjectPointOnSurf& projector = projectors[static_cast<std::size_t>(t.face)];
    projector.Perform(gp_Pnt(t.centre.x(), t.centre.y(), t.centre.z()));
    EXPECT_GT(projector.NbPoints(), 0) << k;
    if (projector.NbPoints() == 0) continue;
    c.worst_distance = std::max(c.worst_distance, std::abs(projector.LowerDistance() - r));
    const gp_Pnt foot = projector.NearestPoint();
    c.worst_contact = std::max(c.worst_contact, (Point3(foot.X(), foot.Y(), foot.Z()) - t.contact).norm());
    // Outside: the centre lies on the side of the face's outward normal (OpenCASCADE's D1 cross product).
    double u = 0.0, v = 0.0;
    projector.LowerDistanceParameters(u, v);
    gp_Pnt p;
    gp_Vec du, dv;
    occt[static_cast<std::size_t>(t.face)]->D1(u, v, p, du, dv);
    const gp_Vec n = du.Crossed(dv) * static_cast<double>(face.outward);
    EXPECT_GT(Vector3(n.X(), n.Y(), n.Z()).dot(t.centre - Point3(foot.X(), foot.Y(), foot.Z())), 0.0) << k;
  }
  std::printf("%d touches: off the line by at most %.1e mm, |distance - r| at most %.1e mm (OpenCASCADE), contact "
              "within %.1e mm of OpenCASCADE's foot point\n",
              c.touched, c.worst_line, c.worst_distance, c.worst_contact);
  return c;
}

TEST(Simulation, FreeformTouchesAreOnTheLineAtTheTipRadiusOutsideTheActualPart) {
  const simulation::FreeformCase c = simulation::paper_freeform_case();
  const cad::Model actual = simulation::actual_model(c.nominal, c.deformation, c.placement);
  const cad::ModelLocator locator(actual);
  const auto plan = simulation::grid_plan(c.nominal.faces.front(), 40, 20);
  const auto touches = simulation::simulate_touches(locator, plan, {.probe_radius = c.probe_radius});
  const Checked k = check_touches(actual, plan, touches, c.probe_radius);
  EXPECT_EQ(k.touched, static_cast<int>(plan.size()));
  EXPECT_LT(k.worst_line, 1e-12);
  EXPECT_LE(k.worst_distance, kTouchTolerance);
  EXPECT_LT(k.worst_contact, 1e-6);
}

TEST(Simulation, DeformedMisalignedCylinderTouchesAreOnTheLineAtTheTipRadius) {
  studies::CylinderStudyOptions o;
  const cad::Model nominal = studies::cylinder_part(o.part);
  const cad::Model actual = simulation::actual_model(
      nominal, studies::cylinder_deformation(o, 1.5), geometry::from_pose({.rx = 0.5, .t = Vector3(0.1, 0.2, 0.5)}));
  const cad::ModelLocator locator(actual);
  const auto plan = simulation::grid_plan(nominal.faces.front(), 30, 30, o.margin);
  const auto touches = simulation::simulate_touches(locator, plan, {.probe_radius = 1.0});
  const Checked k = check_touches(actual, plan, touches, 1.0);
  EXPECT_EQ(k.touched, static_cast<int>(plan.size()));
  EXPECT_LE(k.worst_distance, kTouchTolerance);
  EXPECT_LT(k.worst_contact, 1e-6);
}

TEST(Simulation, MultiFaceStepPartWithABumpTouchesAreOnTheLineAtTheTipRadius) {
  const cad::Model nominal = cad::read_model(std::filesystem::path(PROBECOMP_TEST_CAD_DIR) / "asitus_wavy-cube.stp");
  std::vector<simulation::ProgrammedPoint> plan;
  for (const auto& p : cad::plan_points(nominal, 0.05, {2, 3, 5})) plan.push_back({p.point, p.normal, p.face});
  simulation::Deformation d;
  d.bumps.push_back({.centre = plan[plan.size() / 2].point, .amplitude = 0.01, .width = 0.1});
  const cad::Model actual = simulation::actual_model(nominal, d, geometry::from_pose({.rz = 0.2, .t = Vector3(0.002, 0, 0)}));
  const cad::ModelLocator locator(actual);
  const auto touches = simulation::simulate_touches(locator, plan, {.probe_radius = 0.1});
  const Checked k = check_touches(actual, plan, touches, 0.1);
  EXPECT_GE(k.touched, static_cast<int>(0.8 * static_cast<double>(plan.size())));
  EXPECT_LE(k.worst_distance, kTouchTolerance);
  EXPECT_LT(k.worst_contact, 1e-6);
}

TEST(Simulation, NoiseIsTheSameWhateverTheOrderOfTouchesAndHasTheAskedSigma) {
  const simulation::FreeformCase c = simulation::paper_freeform_case();
  const cad::ModelLocator locator(c.nominal);
  const auto plan = simulation::grid_plan(c.nominal.faces.front(), 60, 40);
  const auto exact = simulation::simulate_touches(locator, plan, {.probe_radius = 1.0});
  const auto noisy = simulation::simulate_touches(locator, plan, {.probe_radius = 1.0, .noise_sigma = 0.01, .seed = 5});
  const auto again = simulation::simulate_touches(locator, plan, {.probe_radius = 1.0, .noise_sigma = 0.01, .seed = 5});
  double ss = 0.0;
  for (std::size_t k = 0; k < plan.size(); ++k) {
    ASSERT_EQ(noisy[k].measured, again[k].measured);
    ASSERT_EQ(noisy[k].centre, exact[k].centre);
    ss += (noisy[k].measured - noisy[k].centre).squaredNorm();
  }
  const double sigma = std::sqrt(ss / (3.0 * static_cast<double>(plan.size())));
  EXPECT_NEAR(sigma, 0.01, 0.01 * 4.0 / std::sqrt(2.0 * 3.0 * static_cast<double>(plan.size())));  // 4 standard errors
}

TEST(Deformation, TheActualSurfaceFollowsTheDisplacementAndIsSmooth) {
  // A degree-1 direction (the cylinder's rulings) is raised to cubic, so the deformed surface has no creases:
  // its normal turns continuously across every knot.
  studies::CylinderStudyOptions o;
  const cad::Model nominal = studies::cylinder_part(o.part);
  const simulation::Deformation d = studies::cylinder_deformation(o, 1.0);
  const nurbs::Surface s = simulation::deformed_surface(nominal.faces[0].surface, 1, d);
  EXPECT_GE(s.q(), 3);
  double worst = 0.0, worst_turn = 0.0;
  cad::Model model;
  model.faces.push_back(nominal.faces[0]);
  model.faces[0].surface = s;
  const cad::ModelLocator locator(model);
  for (int a = 0; a <= 50; ++a) {
    for (int b = 0; b <= 50; ++b) {
      const double u = a / 50.0, v = b / 50.0;
      const Point3 x0 = nurbs::evaluate(nominal.faces[0].surface, u, v);
      const Vector3 n0 = nurbs::unit_normal(nominal.faces[0].surface, u, v).n;
      // The actual point over x0 along n0 (the surfaces share parameters only approximately): project.
      const Point3 target = x0 + d.displacement(x0) * n0;
      const cad::ModelPoint f = locator.closest_point(target);
      worst = std::max(worst, f.distance);
    }
  }
  for (double v : s.V().breakpoints()) {
    if (v <= 0.0 || v >= 1.0) continue;
    const Vector3 left = nurbs::unit_normal(s, 0.5, v - 1e-9).n, right = nurbs::unit_normal(s, 0.5, v + 1e-9).n;
    worst_turn = std::max(worst_turn, std::acos(std::min(1.0, left.dot(right))));
  }
  EXPECT_LT(worst, 2e-5);       // mm: the fit's tolerance (1e-5) and the step from x0 + d·n0 to the nearest point
  EXPECT_LT(worst_turn, 1e-6);  // radians: no crease at the knots
}

}  // namespace
