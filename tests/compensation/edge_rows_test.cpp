// Rows whose tip touched a face's open edge (issue 49), against the simulator's truth: a panel measured on a grid and
// across one of its free edges, from 0.5 mm beyond it to 0.9 mm inside, the probe stopping at its first contact with
// the part (the rim, past the edge).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "probecomp/simulation/measure.hpp"
#include "probecomp/simulation/shape_suite.hpp"
#include "probecomp/studies/comparison.hpp"

namespace probecomp::compensation {
namespace {

// The panel's interior on a 60 × 50 grid, then 20 stations along its u = u0 edge, each 15 touches from 0.5 mm beyond
// the edge (along the edge's inward tangent, approached along the edge's normal) to 0.9 mm inside.
std::vector<simulation::ProgrammedPoint> plan_across_edge(const cad::Face& f, std::size_t& interior) {
  std::vector<simulation::ProgrammedPoint> plan = simulation::grid_plan(f, 60, 50);
  interior = plan.size();
  const nurbs::Domain d = f.surface.domain();
  for (int j = 0; j < 20; ++j) {
    const double v = d.v0 + (0.05 + 0.9 * j / 19.0) * (d.v1 - d.v0);
    const nurbs::SurfaceD1 e = nurbs::derivatives_d1(f.surface, d.u0, v);
    for (int k = 0; k <= 14; ++k) {
      const double s = -0.5 + 0.1 * k;  // mm inside the edge
      if (s < 0.0) {
        plan.push_back({e.S + s * e.Su.normalized(), f.outward * e.Su.cross(e.Sv).normalized(), 0});
      } else {
        const double u = d.u0 + s / e.Su.norm();
        const nurbs::SurfaceD1 e2 = nurbs::derivatives_d1(f.surface, u, v);
        plan.push_back({e2.S, f.outward * e2.Su.cross(e2.Sv).normalized(), 0});
      }
    }
  }
  return plan;
}

struct EdgeRowCounts {
  int edge_rows = 0, covered = 0, bad_ok = 0;
  int rim_touches = 0, rim_flagged_and_covered = 0;  // the touches whose true contact is on the rim
  double farthest = 0.0;
};

// The panel with a 0.1 mm bump reaching the edge (which moves the rim), placed `placement` off the CAD frame, measured
// with σ = 2 µm: the edge rows and how many are within 2u of the actual part, and the ok rows more than 20 µm from
// the true contact.
// With `plan_follows_part`, the plan is carried by the placement (a program run after a manual alignment touches
// the part where it is; the registration must still find the whole placement).
EdgeRowCounts edge_rows_of(const geometry::RigidTransform& placement, unsigned seed, bool plan_follows_part = false) {
  const cad::Model nominal = simulation::base_model(simulation::BaseSurface::Panel);
  std::size_t interior = 0;
  std::vector<simulation::ProgrammedPoint> plan = plan_across_edge(nominal.faces[0], interior);
  if (plan_follows_part) {
    for (simulation::ProgrammedPoint& p : plan) {
      p.point = placement * p.point;
      p.normal = placement.linear() * p.normal;
    }
  }
  simulation::ShapeCase bump;
  bump.features = {{.kind = simulation::FeatureSpec::Kind::Bump, .u = 0.1, .v = 0.5, .amplitude = 0.1, .size = 10.0}};
  const studies::SimulatedMeasurement m{
      .nominal = nominal,
      .deformation = simulation::deformation_of(bump, nominal),
      .placement = placement,
      .plan = plan,
      .probe_radius = 1.0,
      .noise_sigma = 0.002,
      .seed = seed};
  const studies::MethodComparison r = studies::compare_methods(m, {.approach_normals = true});
  const cad::Model actual = simulation::actual_model(nominal, m.deformation, m.placement);
  const cad::ModelLocator part(actual);
  EdgeRowCounts n;
  for (std::size_t k = interior; k < plan.size(); ++k) {
    const CompensatedPoint& c = r.cad.points[k];
    const simulation::Touch& t = r.touches[k];
    if (c.status == PointStatus::Ok && (c.contact - t.contact).norm() > 0.02) ++n.bad_ok;
    const bool on_rim = t.status == simulation::Touch::Status::Edge;
    n.rim_touches += on_rim;
    if (c.status != PointStatus::Edge) continue;
    const cad::ModelPoint foot = part.closest_point(c.contact);
    if (!foot.ok()) continue;
    ++n.edge_rows;
    const bool covered = std::abs(foot.distance) <= 2.0 * c.uncertainty;
    n.covered += covered;
    n.rim_flagged_and_covered += on_rim && covered;
    n.farthest = std::max(n.farthest, std::abs(foot.distance));
  }
  std::printf("edge rows %d, within 2u of the part %d, farthest %.1f um; ok rows more than 20 um off: %d; rim touches %d, "
              "flagged and within 2u %d\n",
              n.edge_rows, n.covered, n.farthest * 1e3, n.bad_ok, n.rim_touches, n.rim_flagged_and_covered);
  return n;
}

// The deformation's move of the rim is stated in u: before it was (u the registration's scale alone, 5 µm), 59 % of
// the edge rows were within 2u of the part, the farthest 38 µm off; then 93 %.
TEST(EdgeRows, ARimTheDeformationMovedIsStatedInU) {
  const EdgeRowCounts n = edge_rows_of(geometry::RigidTransform(Eigen::Translation3d(0.3, -0.2, 0.25) *
                                                                Eigen::AngleAxisd(0.02, Vector3(1, 1, 0.3).normalized())),
                                       3);
  EXPECT_GE(n.edge_rows, 140);  // of the 300 touches, the rim was touched 150 times
  EXPECT_GE(n.covered, 0.9 * n.edge_rows);
  EXPECT_EQ(n.bad_ok, 0);
}

// Further off, up to what issue 49 asks (3° and 1 mm). The plan either follows the part, as a program run after a
// manual alignment touches it, or stays in the CAD frame, so that the part's misalignment moves where each touch
// meets the rim. Of the touches whose true contact is on the rim, at least 90 % come back `edge` within 2u of the
// part, and no `ok` row is more than 20 µm from its true contact.
TEST(EdgeRows, FartherOffEveryRimTouchIsFlaggedAndNoOkRowIsFarOff) {
  struct Placement {
    double angle, translation;
    Vector3 axis;
    unsigned seed;
    bool plan_follows_part;
  };
  const Vector3 a(0.3, 1, 0.5), b(1, 1, 0.3);
  for (const Placement& p : {Placement{0.03, 0.4, a, 5, true}, Placement{0.052, 1.0, a, 7, true},
                             Placement{-0.045, 0.7, a, 9, true}, Placement{0.03, 0.3, b, 5, false},
                             Placement{0.045, 0.2, b, 9, false}, Placement{0.052, 0.3, b, 11, false}}) {
    SCOPED_TRACE(testing::Message() << p.angle << " rad, " << p.translation << " mm, plan follows: " << p.plan_follows_part);
    const double t = p.translation;
    const EdgeRowCounts n = edge_rows_of(geometry::RigidTransform(Eigen::Translation3d(t, -0.6 * t, 0.5 * t) *
                                                                  Eigen::AngleAxisd(p.angle, p.axis.normalized())),
                                         p.seed, p.plan_follows_part);
    EXPECT_GE(n.rim_touches, 100);  // of the 300 touches, 5 to 8 a station meet the rim
    EXPECT_GE(n.rim_flagged_and_covered, 0.9 * n.rim_touches);
    EXPECT_GE(n.covered, 0.9 * n.edge_rows);
    EXPECT_EQ(n.bad_ok, 0);
  }
}

}  // namespace
}  // namespace probecomp::compensation
