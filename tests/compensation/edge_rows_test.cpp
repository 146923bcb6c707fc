// Rows whose tip touched a face's open edge (issue 49), against the simulator's truth: a panel measured on a grid and
// across one of its free edges, from 0.5 mm beyond it to 0.9 mm inside, the probe stopping at its first contact with
// the part (the rim, past the edge).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <numbers>

#include "probecomp/cad/trim.hpp"
#include "probecomp/simulation/measure.hpp"
#include "probecomp/simulation/shape_suite.hpp"
#include "probecomp/studies/comparison.hpp"
#include "support/light.hpp"

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
  for (const Placement& p : test::cases({Placement{0.052, 1.0, a, 7, true}, Placement{0.03, 0.4, a, 5, true},
                                        Placement{-0.045, 0.7, a, 9, true}, Placement{0.03, 0.3, b, 5, false},
                                        Placement{0.045, 0.2, b, 9, false}, Placement{0.052, 0.3, b, 11, false}})) {
    SCOPED_TRACE(::testing::Message() << p.angle << " rad, " << p.translation << " mm, plan follows: " << p.plan_follows_part);
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

// The panel with trimmed openings, as a sheet has them: a round hole or a rectangular notch cut into one side. A
// station is a point of an opening's edge in (u, v) and the direction, in (u, v), from it into the material.
struct Station {
  double u, v, du, dv;
};
struct TrimmedPanel {
  cad::Model model;
  std::vector<Station> stations;
  // Whether (u, v) is at least `margin` (as a fraction of the opening's size) clear of the opening.
  std::function<bool(double, double)> clear;
};

cad::BoundaryCurve boundary_of(nurbs::Curve c) {
  cad::BoundaryCurve b{std::move(c), {}, false};
  b.t = cad::boundary_samples(b.uv, 1e-7);
  return b;
}

nurbs::Curve uv_line(double u0, double v0, double u1, double v1) {
  return nurbs::Curve(nurbs::KnotVector({0.0, 0.0, 1.0, 1.0}, 1), std::vector<Point3>{Point3(u0, v0, 0), Point3(u1, v1, 0)});
}

// A round hole `radius` mm across at fractions (a, b) of the domain: its loop in (u, v) an exact ellipse (a rational
// quadratic circle, The NURBS Book section 7.5, scaled by the surface's speeds at the centre), nearly round on the
// part; 24 stations round it.
TrimmedPanel panel_with_hole(double a, double b, double radius) {
  TrimmedPanel out{simulation::base_model(simulation::BaseSurface::Panel), {}, {}};
  cad::Face& f = out.model.faces[0];
  const nurbs::Domain d = f.surface.domain();
  const double uc = d.u0 + a * (d.u1 - d.u0), vc = d.v0 + b * (d.v1 - d.v0);
  const nurbs::SurfaceD1 e = nurbs::derivatives_d1(f.surface, uc, vc);
  const double ru = radius / e.Su.norm(), rv = radius / e.Sv.norm();
  const double h = std::numbers::sqrt2 / 2.0;
  std::vector<Point3> P;
  const double cu[9] = {1, 1, 0, -1, -1, -1, 0, 1, 1}, cv[9] = {0, 1, 1, 1, 0, -1, -1, -1, 0};
  for (int k = 0; k < 9; ++k) P.emplace_back(uc + ru * cu[k], vc + rv * cv[k], 0.0);
  const nurbs::Curve circle(nurbs::KnotVector({0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1}, 2), P,
                            {1, h, 1, h, 1, h, 1, h, 1});
  f.trim = std::make_shared<const cad::Trim>(std::vector<cad::BoundaryCurve>{
      boundary_of(uv_line(d.u0, d.v0, d.u1, d.v0)), boundary_of(uv_line(d.u1, d.v0, d.u1, d.v1)),
      boundary_of(uv_line(d.u1, d.v1, d.u0, d.v1)), boundary_of(uv_line(d.u0, d.v1, d.u0, d.v0)), boundary_of(circle)});
  for (int j = 0; j < 24; ++j) {
    const double t = 2.0 * std::numbers::pi * j / 24.0;
    out.stations.push_back({uc + ru * std::cos(t), vc + rv * std::sin(t), ru * std::cos(t) / radius, rv * std::sin(t) / radius});
  }
  out.clear = [=](double u, double v) { return std::hypot((u - uc) / ru, (v - vc) / rv) > (radius + 2.0) / radius; };
  return out;
}

// A notch `width` × `depth` mm cut into the panel's v = v1 side about u = a of the domain; 8 stations along its
// bottom and 4 up each side, all at least 2 mm from its corners (where the tip meets two edges).
TrimmedPanel panel_with_notch(double a, double width, double depth) {
  TrimmedPanel out{simulation::base_model(simulation::BaseSurface::Panel), {}, {}};
  cad::Face& f = out.model.faces[0];
  const nurbs::Domain d = f.surface.domain();
  const double um = d.u0 + a * (d.u1 - d.u0);
  const nurbs::SurfaceD1 e = nurbs::derivatives_d1(f.surface, um, d.v1);
  const double su = 1.0 / e.Su.norm(), sv = 1.0 / e.Sv.norm();  // parameter per mm
  const double ua = um - 0.5 * width * su, ub = um + 0.5 * width * su, vn = d.v1 - depth * sv;
  f.trim = std::make_shared<const cad::Trim>(std::vector<cad::BoundaryCurve>{
      boundary_of(uv_line(d.u0, d.v0, d.u1, d.v0)), boundary_of(uv_line(d.u1, d.v0, d.u1, d.v1)),
      boundary_of(uv_line(d.u1, d.v1, ub, d.v1)), boundary_of(uv_line(ub, d.v1, ub, vn)),
      boundary_of(uv_line(ub, vn, ua, vn)), boundary_of(uv_line(ua, vn, ua, d.v1)),
      boundary_of(uv_line(ua, d.v1, d.u0, d.v1)), boundary_of(uv_line(d.u0, d.v1, d.u0, d.v0))});
  for (int j = 0; j < 8; ++j) out.stations.push_back({ua + (2.0 + (width - 4.0) * j / 7.0) * su, vn, 0.0, -sv});
  for (int j = 0; j < 4; ++j) {
    const double v = vn + (2.0 + (depth - 3.0) * j / 3.0) * sv;
    out.stations.push_back({ua, v, -su, 0.0});
    out.stations.push_back({ub, v, su, 0.0});
  }
  out.clear = [=](double u, double v) { return !(u > ua - 2.0 * su && u < ub + 2.0 * su && v > vn - 2.0 * sv); };
  return out;
}

struct OpeningCounts {
  int rim = 0, rim_good = 0, rim_flagged = 0, bad_ok = 0;
  double worst_ok = 0.0;  // mm
};

// The `ok` rows from row `ok_from` on that are more than 20 µm from their true contact (and the farthest), and from row
// `rim_from` on, the touches whose true contact is on an edge: those within 2u of the actual part (flagged `edge`,
// or, at the very edge where a face and its rim meet, `ok` with the contact on the face).
OpeningCounts count_rows(const studies::SimulatedMeasurement& m, const studies::MethodComparison& r, std::size_t ok_from,
                         std::size_t rim_from) {
  const cad::Model actual = simulation::actual_model(m.nominal, m.deformation, m.placement);
  const cad::ModelLocator located(actual);
  OpeningCounts n;
  for (std::size_t k = std::min(ok_from, rim_from); k < m.plan.size(); ++k) {
    const CompensatedPoint& c = r.cad.points[k];
    const simulation::Touch& t = r.touches[k];
    if (t.status == simulation::Touch::Status::Missed) continue;
    if (k >= ok_from && c.status == PointStatus::Ok) {
      const double e = (c.contact - t.contact).norm();
      n.worst_ok = std::max(n.worst_ok, e);
      n.bad_ok += e > 0.02;
    }
    if (k < rim_from || t.status != simulation::Touch::Status::Edge) continue;
    ++n.rim;
    const cad::ModelPoint foot = located.closest_point(c.contact);
    const bool within = foot.ok() && std::abs(foot.distance) <= 2.0 * c.uncertainty;
    n.rim_flagged += c.status == PointStatus::Edge && within;
    n.rim_good += (c.status == PointStatus::Edge || c.status == PointStatus::Ok) && within;
  }
  return n;
}

// The panel's grid clear of the opening, then 15 touches at each station from 0.5 mm over the opening to 0.9 mm into
// the material, approached along the surface's normal there. Placed 2° and 0.5 mm off, the plan following the part
// or in the CAD frame. Counts the touches whose true contact is on the opening's edge, those of them within 2u of the
// part (flagged `edge`, or, at the very edge where the face and its rim meet, `ok` with the contact on the face), and
// the `ok` rows more than 20 µm from their true contact.
OpeningCounts touch_across_opening(const TrimmedPanel& part, bool plan_follows_part) {
  const cad::Face& f = part.model.faces[0];
  auto at = [&](double u, double v) {
    const nurbs::SurfaceD1 e = nurbs::derivatives_d1(f.surface, u, v);
    return simulation::ProgrammedPoint{e.S, f.outward * e.Su.cross(e.Sv).normalized(), 0};
  };
  std::vector<simulation::ProgrammedPoint> plan;
  const nurbs::Domain d = f.surface.domain();
  for (int i = 0; i < 60; ++i) {
    for (int j = 0; j < 50; ++j) {
      const double u = d.u0 + (0.04 + 0.92 * i / 59.0) * (d.u1 - d.u0), v = d.v0 + (0.04 + 0.92 * j / 49.0) * (d.v1 - d.v0);
      if (part.clear(u, v)) plan.push_back(at(u, v));
    }
  }
  const std::size_t interior = plan.size();
  for (const Station& st : part.stations) {
    for (int k = 0; k <= 14; ++k) {
      const double s = -0.5 + 0.1 * k;  // mm into the material
      plan.push_back(at(st.u + s * st.du, st.v + s * st.dv));
    }
  }
  const geometry::RigidTransform placement(Eigen::Translation3d(0.3, -0.3, 0.25) *
                                           Eigen::AngleAxisd(0.035, Vector3(1, 0.4, 0.2).normalized()));
  if (plan_follows_part) {
    for (simulation::ProgrammedPoint& p : plan) {
      p.point = placement * p.point;
      p.normal = placement.linear() * p.normal;
    }
  }
  const studies::SimulatedMeasurement m{
      .nominal = part.model, .deformation = {}, .placement = placement, .plan = plan, .probe_radius = 1.0, .noise_sigma = 0.002, .seed = 13};
  const studies::MethodComparison r = studies::compare_methods(m, {.approach_normals = true});
  const OpeningCounts n = count_rows(m, r, interior, interior);
  std::printf("rim touches %d, within 2u %d (flagged %d); ok rows more than 20 um off %d (worst %.1f um)\n", n.rim,
              n.rim_good, n.rim_flagged, n.bad_ok, n.worst_ok * 1e3);
  return n;
}

// Both plans (following the part, in the CAD frame): at least `rim_touches` touches meet the opening's edge, 90 % of
// them within 2u of the part, and no ok row more than 20 µm from its true contact.
void expect_opening_edges_flagged(const TrimmedPanel& part, int rim_touches) {
  for (const bool follows : test::cases({true, false})) {
    SCOPED_TRACE(follows ? "plan follows the part" : "plan in the CAD frame");
    const OpeningCounts n = touch_across_opening(part, follows);
    EXPECT_GE(n.rim, rim_touches);
    EXPECT_GE(n.rim_good, 0.9 * n.rim);
    EXPECT_EQ(n.bad_ok, 0);
  }
}

TEST(EdgeRows, ATrimmedHolesEdgeIsFlaggedAndNoOkRowIsFarOff) {
  expect_opening_edges_flagged(panel_with_hole(0.55, 0.45, 6.0), 100);  // of 360 touches, about 5 a station
}

TEST(EdgeRows, ACutOutsEdgesAreFlaggedAndNoOkRowIsFarOff) {
  expect_opening_edges_flagged(panel_with_notch(0.4, 16.0, 10.0), 70);  // of 240 touches, about 5 a station
}

// A sheet part of four faces with open edges, as issue 49 found it: the panel, two walls `wall` mm high rising from
// its v edges on its outward side (a channel: the probe measures the walls' inner faces, which meet the panel in
// concave corners), and a skirt `skirt` mm deep turned down from its u1 edge (a convex edge). Each wall and the
// skirt is ruled exactly from the panel's edge curve (its control points moved along a fixed direction, weights
// kept). The walls' tops, the skirt's foot and the panel's u0 edge are open.
cad::Model panel_with_walls(double wall, double skirt) {
  cad::Model m = simulation::base_model(simulation::BaseSurface::Panel);
  const nurbs::Surface s = m.faces[0].surface;  // a copy: the faces grow below
  const nurbs::Domain d = s.domain();
  const nurbs::SurfaceD1 mid = nurbs::derivatives_d1(s, 0.5 * (d.u0 + d.u1), 0.5 * (d.v0 + d.v1));
  const Vector3 up = (m.faces[0].outward * mid.Su.cross(mid.Sv)).normalized();
  // The face ruled from the panel's boundary row (along u: j = 0 or the last; along v: i = 0 or the last) along `dir`.
  auto ruled = [&](bool along_u, int row, const Vector3& dir, const Vector3& inward, int index, const char* name) {
    const int n = along_u ? s.num_u() : s.num_v();
    std::vector<Point3> P;
    std::vector<double> w;
    for (int i = 0; i < n; ++i) {
      const int a = along_u ? i : row, b = along_u ? row : i;
      for (int j = 0; j < 2; ++j) {
        P.push_back(s.control_point(a, b) + j * dir);
        w.push_back(s.weight(a, b));
      }
    }
    nurbs::Surface face(along_u ? s.U() : s.V(), nurbs::KnotVector({0.0, 0.0, 1.0, 1.0}, 1), P, w);
    const nurbs::Domain fd = face.domain();
    const nurbs::SurfaceD1 e = nurbs::derivatives_d1(face, 0.5 * (fd.u0 + fd.u1), 0.5);
    const int outward = e.Su.cross(e.Sv).dot(inward) > 0.0 ? 1 : -1;
    m.faces.push_back(cad::Face{.index = index, .name = name, .source_type = "bspline", .surface = std::move(face),
                                .trim = nullptr, .outward = outward, .material_known = false, .exact = true});
  };
  const Vector3 sv = mid.Sv.normalized(), su = mid.Su.normalized();
  ruled(true, 0, wall * up, sv, 1, "wall v0");
  ruled(true, s.num_v() - 1, wall * up, -sv, 2, "wall v1");
  ruled(false, s.num_u() - 1, -skirt * up, su, 3, "skirt");
  return m;
}

// Grids on the four faces, then 15 touches at each of 20 stations along each open edge, from 0.5 mm beyond it to
// 0.9 mm inside, approached along the face's normal there; 2° and 0.5 mm off. Of the touches whose true contact is on
// an open edge, at least 90 % within 2u of the part; no `ok` row anywhere more than 20 µm from its true contact.
TEST(EdgeRows, AnOpenShellsEdgesAreFlaggedAndNoOkRowIsFarOff) {
  const cad::Model part = panel_with_walls(15.0, 10.0);
  std::vector<simulation::ProgrammedPoint> plan;
  auto at = [&](int f, double u, double v) {
    const cad::Face& face = part.faces[static_cast<std::size_t>(f)];
    const nurbs::SurfaceD1 e = nurbs::derivatives_d1(face.surface, u, v);
    return simulation::ProgrammedPoint{e.S, face.outward * e.Su.cross(e.Sv).normalized(), f};
  };
  // Grids 2 mm and more clear of every edge (the corners' double contacts are another test's).
  for (int f = 0; f < 4; ++f) {
    const cad::Face& face = part.faces[static_cast<std::size_t>(f)];
    const nurbs::Domain d = face.surface.domain();
    const int nu = f == 0 ? 50 : 40, nv = f == 0 ? 40 : 6;
    for (int i = 0; i < nu; ++i) {
      for (int j = 0; j < nv; ++j) {
        plan.push_back(at(f, d.u0 + (0.05 + 0.9 * i / (nu - 1)) * (d.u1 - d.u0), d.v0 + (0.2 + 0.6 * j / (nv - 1)) * (d.v1 - d.v0)));
      }
    }
  }
  const std::size_t interior = plan.size();
  // Open edges: each wall's top (v = 1), the skirt's foot (v = 1), the panel's u0 edge; s mm inside along -S_v (or S_u).
  struct OpenEdge {
    int face;
    bool along_u;  // the edge runs along u (at v = v1); else along v (at u = u0)
  };
  for (const OpenEdge& oe : {OpenEdge{1, true}, OpenEdge{2, true}, OpenEdge{3, true}, OpenEdge{0, false}}) {
    const cad::Face& face = part.faces[static_cast<std::size_t>(oe.face)];
    const nurbs::Domain d = face.surface.domain();
    for (int j = 0; j < 20; ++j) {
      const double a = 0.08 + 0.84 * j / 19.0;
      const double u = oe.along_u ? d.u0 + a * (d.u1 - d.u0) : d.u0, v = oe.along_u ? d.v1 : d.v0 + a * (d.v1 - d.v0);
      const nurbs::SurfaceD1 e = nurbs::derivatives_d1(face.surface, u, v);
      const Vector3 inside = oe.along_u ? Vector3(-e.Sv.normalized()) : Vector3(e.Su.normalized());
      const Vector3 normal = face.outward * e.Su.cross(e.Sv).normalized();
      for (int k = 0; k <= 14; ++k) {
        const double s = -0.5 + 0.1 * k;
        if (s < 0.0) {
          plan.push_back({e.S + s * inside, normal, oe.face});
        } else {
          const double len = oe.along_u ? e.Sv.norm() : e.Su.norm();
          plan.push_back(at(oe.face, oe.along_u ? u : u + s / len, oe.along_u ? v - s / len : v));
        }
      }
    }
  }
  const geometry::RigidTransform placement(Eigen::Translation3d(0.3, -0.3, 0.25) *
                                           Eigen::AngleAxisd(0.035, Vector3(1, 0.4, 0.2).normalized()));
  // The plan follows the part: left in the CAD frame, the touches beyond the walls' tops would miss it.
  std::vector<simulation::ProgrammedPoint> run = plan;
  for (simulation::ProgrammedPoint& p : run) {
    p.point = placement * p.point;
    p.normal = placement.linear() * p.normal;
  }
  const studies::SimulatedMeasurement m{
      .nominal = part, .deformation = {}, .placement = placement, .plan = run, .probe_radius = 1.0, .noise_sigma = 0.002, .seed = 17};
  const studies::MethodComparison r = studies::compare_methods(m, {.approach_normals = true});
  const OpeningCounts n = count_rows(m, r, 0, interior);
  int interior_ok = 0;
  double interior_ss = 0.0;
  for (std::size_t k = 0; k < interior; ++k) {
    if (r.touches[k].status == simulation::Touch::Status::Missed || r.cad.points[k].status != PointStatus::Ok) continue;
    ++interior_ok;
    interior_ss += r.cad_error[k] * r.cad_error[k];
  }
  std::printf("open shell: rim touches %d, within 2u %d (flagged %d); ok rows more than 20 um off %d (worst %.1f um); "
              "interior ok rows %d of %zu, rms error %.2f um\n",
              n.rim, n.rim_good, n.rim_flagged, n.bad_ok, n.worst_ok * 1e3, interior_ok, interior,
              std::sqrt(interior_ss / std::max(interior_ok, 1)) * 1e3);
  EXPECT_GE(n.rim, 250);  // of 1 200 touches, about 5 a station
  EXPECT_GE(n.rim_good, 0.9 * n.rim);
  EXPECT_EQ(n.bad_ok, 0);
}

}  // namespace
}  // namespace probecomp::compensation
