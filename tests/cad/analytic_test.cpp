// Closed-form closest points on elementary faces against references computed without them: the NURBS solver on the
// same face (a global search with Newton), OpenCASCADE's GeomAPI_ProjectPointOnSurf on the file's own elementary
// surface, and closed forms (the distance to a cylinder is |ρ − R|); the map to the NURBS parameters against the
// NURBS's own evaluation and derivatives.

#include <BRep_Tool.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Geom_Surface.hxx>
#include <gtest/gtest.h>

#include <map>
#include <numbers>
#include <random>

#include "probecomp/cad/analytic.hpp"
#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/model.hpp"
#include "probecomp/cad/offset_model.hpp"
#include "probecomp/nurbs/constructors.hpp"
#include "support/data_files.hpp"
#include "support/occt_files.hpp"

namespace probecomp::cad {
namespace {

using test::kCadDir;
constexpr double kPi = std::numbers::pi;

// Random points within `reach` of the surface's control-net box, and some far off.
std::vector<Point3> points_near(const nurbs::Surface& s, std::size_t n, double reach, std::uint64_t seed) {
  const BoundingBox box = nurbs::bounding_box(s);
  std::mt19937_64 rng(seed);
  std::vector<Point3> out;
  for (std::size_t k = 0; k < n; ++k) {
    const double scale = k % 10 == 0 ? 10.0 : 1.0;
    Point3 p;
    for (int i = 0; i < 3; ++i) {
      const double lo = box.min[i] - scale * reach, hi = box.max[i] + scale * reach;
      p[i] = std::uniform_real_distribution<double>(lo, hi)(rng);
    }
    out.push_back(p);
  }
  return out;
}

// The analytic face's answer against the NURBS solver's on the same (untrimmed) surface: never farther (the
// closed form is exact), and the solver never farther by more than its Newton tolerance; u, v, the tangents and the
// point agree with the NURBS evaluated there.
void expect_matches_solver(const AnalyticFace& face, const nurbs::Surface& s, const std::vector<Point3>& queries,
                           const std::string& what) {
  const nurbs::ClosestPointSolver solver(s);
  const double size = nurbs::bounding_box(s).diagonal();
  double worst_excess = 0.0, worst_gap = 0.0;
  for (std::size_t k = 0; k < queries.size(); ++k) {
    const nurbs::ClosestPointResult ours = face.closest_point(queries[k]);
    const nurbs::ClosestPointResult ref = solver.closest_point(queries[k]);
    ASSERT_TRUE(ours.ok() && ref.ok()) << what << " query " << k;
    EXPECT_NEAR(ours.distance, (queries[k] - ours.point).norm(), 1e-12 * size);
    worst_excess = std::max(worst_excess, ours.distance - ref.distance);
    worst_gap = std::max(worst_gap, ref.distance - ours.distance);
    const nurbs::SurfaceD1 d = nurbs::derivatives_d1(s, ours.u, ours.v);
    EXPECT_LE((d.S - ours.point).norm(), 1e-9) << what << " query " << k;
    EXPECT_LE((d.Su - ours.Su).norm(), 1e-9 * std::max(1.0, d.Su.norm())) << what << " query " << k;
    EXPECT_LE((d.Sv - ours.Sv).norm(), 1e-9 * std::max(1.0, d.Sv.norm())) << what << " query " << k;
  }
  EXPECT_LE(worst_excess, 1e-9) << what << ": the closed form is farther than the solver's point";
  EXPECT_LE(worst_gap, 1e-7) << what << ": the solver is farther than the closed form";
}

TEST(AnalyticFace, CylinderSectionOfTheKernelMatchesItsNurbsBothWaysRound) {
  const Point3 c(3, -2, 5);
  const Vector3 x = Vector3(1, 1, 0).normalized(), y = Vector3(-1, 1, 1).normalized();
  const Vector3 z = x.cross(y);
  // 250°: three arcs with unequal weights (A7.1), u in [0, 1] rather than the angle.
  const nurbs::Surface s = nurbs::make_cylinder_section(c, x, y, 12.0, 0.3, 0.3 + 250.0 * kPi / 180.0, 40.0);
  const ElementarySurface right{ElementaryKind::Cylinder, c, x, y, z, 12.0};
  // The same cylinder in a left-handed frame (y reversed): its angle runs against u, its normal against S_u × S_v.
  const ElementarySurface left{ElementaryKind::Cylinder, c, x, -y, z, 12.0};
  for (const ElementarySurface& e : {right, left}) {
    const std::shared_ptr<const AnalyticFace> face = make_analytic_face(e, s);
    ASSERT_NE(face, nullptr);
    const std::vector<Point3> queries = points_near(s, 400, 15.0, 3);
    expect_matches_solver(*face, s, queries, "cylinder section");
    // The distance to the cylinder is |ρ − 12| where the foot is not clamped (closed form, not the code's own).
    for (const Point3& q : queries) {
      const nurbs::ClosestPointResult r = face->closest_point(q);
      if (r.status != nurbs::ClosestPointStatus::Converged) continue;
      const Vector3 d = q - c;
      const double rho = (d - d.dot(z) * z).norm();
      EXPECT_NEAR(r.distance, std::abs(rho - 12.0), 1e-12 * 50.0);
    }
    // The offset outward (S_u × S_v away from the axis) is the cylinder of radius 12 + 2, at the same (u, v).
    const std::optional<AnalyticFace> offset = face->offset(2.0);
    ASSERT_TRUE(offset.has_value());
    EXPECT_EQ(offset->surface().radius, 14.0);
    const Point3 S = nurbs::evaluate(s, 0.4, 0.7);
    const auto [a, b] = e.parameters(S);
    const nurbs::ClosestPointResult at = offset->at(a, b);
    const nurbs::SurfaceD1 base = nurbs::derivatives_d1(s, 0.4, 0.7);
    EXPECT_NEAR(at.u, 0.4, 1e-12);
    EXPECT_NEAR(at.v, 0.7, 1e-12);
    EXPECT_LE((at.point - (base.S + 2.0 * base.Su.cross(base.Sv).normalized())).norm(), 1e-12 * 50.0);
  }
  // A map that is not the NURBS's (a cylinder of another radius) is refused.
  EXPECT_EQ(make_analytic_face(ElementarySurface{ElementaryKind::Cylinder, c, x, y, z, 12.001}, s), nullptr);
  // So is a free-form direction where a straight one is expected.
  EXPECT_EQ(make_analytic_face(ElementarySurface{ElementaryKind::Plane, c, x, y, z}, s), nullptr);
}

TEST(AnalyticFace, PlanePatchOfHigherDegreeIsRefusedAndOfDegreeOneMatches) {
  const Point3 o(1, 2, 3);
  const Vector3 x(1, 0, 0), y(0, 0.6, 0.8);
  const nurbs::Surface s = nurbs::make_plane_patch(o, 8.0 * x, 5.0 * y);
  const ElementarySurface plane{ElementaryKind::Plane, o, x, y, x.cross(y)};
  const std::shared_ptr<const AnalyticFace> face = make_analytic_face(plane, s);
  ASSERT_NE(face, nullptr);
  expect_matches_solver(*face, s, points_near(s, 300, 4.0, 5), "plane patch");
  // A query above the middle: its foot is straight below, at the exact distance.
  const nurbs::ClosestPointResult r = face->closest_point(o + 4.0 * x + 2.5 * y + 0.75 * x.cross(y));
  EXPECT_EQ(r.status, nurbs::ClosestPointStatus::Converged);
  EXPECT_NEAR(r.u, 0.5, 1e-15);
  EXPECT_NEAR(r.v, 0.5, 1e-15);
  EXPECT_NEAR(r.distance, 0.75, 1e-15);
  // Degree 2 in u (the same plane, elevated) is not the straight degree-1 direction the map is made for.
  EXPECT_EQ(make_analytic_face(plane, nurbs::make_plane_patch(o, 8.0 * x, 5.0 * y, 2, 1)), nullptr);
}

class AnalyticFacesOfCadFile : public ::testing::TestWithParam<const char*> {};

// Every elementary face of a real file gets its closed form, and each face's closest points equal the NURBS
// solver's and OpenCASCADE's projection onto the file's own surface (bounded to the face's parameter range).
TEST_P(AnalyticFacesOfCadFile, EveryElementaryFaceGetsOneThatMatchesTheSolverAndOpenCascade) {
  const std::filesystem::path path = kCadDir / GetParam();
  const Model model = read_model(path);
  const std::vector<TopoDS_Face> reference = testing::faces_of(testing::read_with_occt(path));
  ASSERT_EQ(reference.size(), model.faces.size());
  std::map<std::string, int> kinds;
  int with = 0, without = 0, elementary_in_file = 0;
  double worst_vs_occt = 0.0;
  for (std::size_t k = 0; k < model.faces.size(); ++k) {
    const Face& face = model.faces[k];
    const GeomAbs_SurfaceType type = GeomAdaptor_Surface(BRep_Tool::Surface(reference[k])).GetType();
    elementary_in_file += type == GeomAbs_Plane || type == GeomAbs_Cylinder || type == GeomAbs_Cone ||
                          type == GeomAbs_Sphere || type == GeomAbs_Torus;
    const bool elementary = face.source_type == "plane" || face.source_type == "cylinder" || face.source_type == "cone" ||
                            face.source_type == "sphere" || face.source_type == "torus";
    if (!elementary) {
      EXPECT_EQ(face.analytic, nullptr) << "face " << k << " " << face.source_type;
      continue;
    }
    if (!face.analytic) {
      ++without;
      ADD_FAILURE() << "face " << k << " (" << face.source_type << ") has no closed form";
      continue;
    }
    ++with;
    ++kinds[to_string(face.analytic->surface().kind)];
    EXPECT_EQ(to_string(face.analytic->surface().kind), face.source_type);
    // A handful of faces of each file in full (the solver's search costs a few ms a face); every face below.
    const std::vector<Point3> queries = points_near(face.surface, k % 8 == 0 ? 40 : 6, 3.0, 100 + k);
    if (k % 8 == 0) expect_matches_solver(*face.analytic, face.surface, queries, "face " + std::to_string(k));
    const Handle(Geom_Surface) occt = BRep_Tool::Surface(reference[k]);
    for (const Point3& q : queries) {
      const nurbs::ClosestPointResult ours = face.analytic->closest_point(q);
      if (ours.status != nurbs::ClosestPointStatus::Converged) continue;  // OpenCASCADE's bounds are in its own u, v
      GeomAPI_ProjectPointOnSurf projector(gp_Pnt(q.x(), q.y(), q.z()), occt);
      ASSERT_GT(projector.NbPoints(), 0);
      // Unbounded, OpenCASCADE's nearest extremum can only be as near or nearer (another part of the surface).
      worst_vs_occt = std::max(worst_vs_occt, projector.LowerDistance() - ours.distance);
    }
  }
  std::cout << GetParam() << ": " << with << " elementary faces with a closed form, " << without << " without (";
  for (const auto& [kind, n] : kinds) std::cout << n << " " << kind << " ";
  std::cout << "); OpenCASCADE farther than ours by at most " << worst_vs_occt << " mm\n";
  EXPECT_EQ(with, elementary_in_file);
  EXPECT_LE(worst_vs_occt, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(CadFiles, AnalyticFacesOfCadFile,
                         ::testing::Values("asitus_repatch-hpdc.stp", "asitus_tail_section_asm.stp", "asitus_wavy-cube.stp"),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& c : n) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return n;
                         });

// The model locator with the closed forms against the same locator with them removed (every face then searched by
// the NURBS solver): the same distances, faces and trim-edge flags, with and without hints.
TEST(AnalyticFace, ModelLocatorGivesTheSameFeetWithAndWithoutClosedForms) {
  const Model model = read_model(kCadDir / "asitus_repatch-hpdc.stp");
  Model plain = model;
  for (Face& f : plain.faces) f.analytic = nullptr;
  const ModelLocator fast(model), slow(plain);
  BoundingBox box;
  for (const Face& f : model.faces) {
    box.extend(nurbs::bounding_box(f.surface).min);
    box.extend(nurbs::bounding_box(f.surface).max);
  }
  std::mt19937_64 rng(17);
  std::vector<Point3> queries;
  for (int k = 0; k < 400; ++k) {
    Point3 p;
    for (int i = 0; i < 3; ++i) p[i] = std::uniform_real_distribution<double>(box.min[i] - 5.0, box.max[i] + 5.0)(rng);
    queries.push_back(p);
  }
  const std::vector<ModelPoint> a = fast.closest_points(queries), b = slow.closest_points(queries);
  // The same queries moved by 0.05 mm, searched from the previous feet (ICP's hinted searches).
  std::vector<Point3> moved = queries;
  for (Point3& p : moved) p += Vector3(0.03, -0.04, 0.0);
  const std::vector<ModelPoint> ha = fast.closest_points(moved, a, ModelLocator::HintedSearch::Exact);
  const std::vector<ModelPoint> hb = slow.closest_points(moved, b, ModelLocator::HintedSearch::Exact);
  int analytic_feet = 0;
  for (std::size_t k = 0; k < queries.size(); ++k) {
    ASSERT_TRUE(a[k].ok() && b[k].ok()) << k;
    EXPECT_NEAR(std::abs(a[k].distance), std::abs(b[k].distance), 1e-7) << "query " << k;
    EXPECT_LE(std::abs(a[k].distance), std::abs(b[k].distance) + 1e-9) << "query " << k;
    EXPECT_NEAR(std::abs(ha[k].distance), std::abs(hb[k].distance), 1e-7) << "moved query " << k;
    if (std::abs(std::abs(a[k].distance) - std::abs(b[k].distance)) < 1e-9 && a[k].face == b[k].face) {
      EXPECT_LE((a[k].normal - b[k].normal).norm(), 1e-6) << "query " << k;
      EXPECT_EQ(a[k].on_trim_edge, b[k].on_trim_edge) << "query " << k;
    }
    analytic_feet += model.faces[static_cast<std::size_t>(a[k].face)].analytic != nullptr;
  }
  std::cout << analytic_feet << " of " << queries.size() << " feet on faces with a closed form\n";
  EXPECT_GT(analytic_feet, 100);
}

// The offset model keeps the closed forms, offset exactly: a point d beyond the base face along its outward
// normal is on the offset face, at the same (u, v) and distance 0; one d + 0.1 mm beyond is 0.1 mm from it.
TEST(AnalyticFace, OffsetModelFacesAreTheExactOffsets) {
  const Model model = read_model(kCadDir / "asitus_repatch-hpdc.stp");
  const double r = 1.5;
  const OffsetModel offset = offset_model(model, r);
  int checked = 0;
  for (std::size_t k = 0; k < model.faces.size(); ++k) {
    const Face& base = model.faces[k];
    const Face& off = offset.model.faces[k];
    if (!base.analytic) continue;
    if (!off.analytic) {
      // Only where the offset degenerates (a radius on the inside smaller than r) may it be missing.
      EXPECT_FALSE(offset.faces[k].ok()) << "face " << k << " " << base.source_type;
      continue;
    }
    const nurbs::Domain d = base.surface.domain();
    for (const double s : {0.25, 0.5, 0.75}) {
      const double u = d.u0 + s * (d.u1 - d.u0), v = d.v0 + (1.0 - s) * (d.v1 - d.v0);
      const nurbs::UnitNormal n = nurbs::unit_normal(base.surface, u, v);
      if (n.status != nurbs::UnitNormal::Status::OK) continue;
      const Vector3 outward = base.outward * n.n;
      const Point3 S = nurbs::evaluate(base.surface, u, v);
      const nurbs::ClosestPointResult on = off.analytic->closest_point(S + r * outward);
      EXPECT_LE(on.distance, 1e-9) << "face " << k;
      EXPECT_NEAR(on.u, u, 1e-9 * (1.0 + std::abs(u))) << "face " << k;
      EXPECT_NEAR(on.v, v, 1e-9 * (1.0 + std::abs(v))) << "face " << k;
      const nurbs::ClosestPointResult beyond = off.analytic->closest_point(S + (r + 0.1) * outward);
      EXPECT_NEAR(beyond.distance, 0.1, 1e-9) << "face " << k;
      ++checked;
    }
  }
  EXPECT_GT(checked, 200);
}

}  // namespace
}  // namespace probecomp::cad
