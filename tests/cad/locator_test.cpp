// Closest points on trimmed multi-face models against OpenCASCADE's exhaustive point-to-shape distance
// (BRepExtrema_DistShapeShape, which respects trims), and OpenCASCADE's face classifier for "inside the trim".

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepClass_FaceClassifier.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <TopoDS_Compound.hxx>
#include <gtest/gtest.h>

#include <iostream>
#include <tbb/task_arena.h>

#include <limits>
#include <random>
#include <type_traits>

#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/plan.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/simulation/random.hpp"
#include "support/data_files.hpp"
#include "support/occt_files.hpp"

namespace probecomp::cad {
namespace {

// The locators refer to their model and face: built from a temporary they would dangle, so they cannot be.
static_assert(std::is_constructible_v<ModelLocator, const Model&>);
static_assert(!std::is_constructible_v<ModelLocator, Model&&>);
static_assert(!std::is_constructible_v<ModelLocator, Model>);
static_assert(!std::is_constructible_v<TrimmedFaceLocator, Face&&>);
static_assert(!std::is_copy_constructible_v<compensation::PreparedModel>);

using test::kCadDir;

// Points around the model: planned points pushed off along the normal by up to ±3 mm and sideways by up to
// 2 mm, so that many feet land on trim edges and on neighbouring faces.
std::vector<Point3> points_around(const Model& model, std::size_t n, std::uint64_t seed) {
  const BoundingBox box = [&] {
    BoundingBox b;
    for (const Face& f : model.faces) {
      const BoundingBox fb = nurbs::bounding_box(f.surface);
      b.extend(fb.min);
      b.extend(fb.max);
    }
    return b;
  }();
  const std::vector<PlannedPoint> plan = plan_points(model, box.diagonal() / 60.0, {});
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, plan.size() - 1);
  std::uniform_real_distribution<double> off(-3.0, 3.0), side(-2.0, 2.0);
  std::vector<Point3> out;
  for (std::size_t k = 0; k < n; ++k) {
    const PlannedPoint& p = plan[pick(rng)];
    const Vector3 aside = simulation::draw_vector(side, rng);  // before `off`: the order gcc drew them in one expression
    out.push_back(p.point + off(rng) * p.normal + aside);
  }
  return out;
}

class ProjectOnCadFile : public ::testing::TestWithParam<const char*> {};

TEST_P(ProjectOnCadFile, EqualsOpenCascadeExhaustiveDistanceInsideTrims) {
  const std::filesystem::path path = kCadDir / GetParam();
  const Model model = read_model(path);
  const ModelLocator locator(model);
  const TopoDS_Shape shape = testing::read_with_occt(path);
  // The reference is the faces alone: some files also hold free curves and points, which are not surfaces.
  const std::vector<TopoDS_Face> faces = testing::faces_of(shape);
  TopoDS_Compound all_faces;
  BRep_Builder builder;
  builder.MakeCompound(all_faces);
  for (const TopoDS_Face& f : faces) builder.Add(all_faces, f);

  const std::vector<Point3> queries = points_around(model, 150, 11);
  const std::vector<ModelPoint> ours = locator.closest_points(queries);
  double worst = -1.0;
  int on_edges = 0, closer_than_occt = 0;
  double worst_edge_tolerance = 0.0;
  for (std::size_t k = 0; k < queries.size(); ++k) {
    ASSERT_TRUE(ours[k].ok()) << k;
    const Point3& q = queries[k];
    BRepExtrema_DistShapeShape dist(BRepBuilderAPI_MakeVertex(gp_Pnt(q.x(), q.y(), q.z())).Vertex(), all_faces);
    ASSERT_TRUE(dist.IsDone());
    // Ours may be closer (OpenCASCADE's extrema stop at its own tolerance) but then the foot point must be on
    // the face, which the classifier below checks; ours farther is a miss.
    // Where a file's edge curves and pcurves disagree, its edges carry that gap as their tolerance; we follow
    // the pcurves (the face's boundary on its surface) and OpenCASCADE the 3D curves, so allow it there.
    const double edge_tolerance = BRep_Tool::MaxTolerance(faces[static_cast<std::size_t>(ours[k].face)], TopAbs_EDGE);
    const double excess = std::abs(ours[k].distance) - dist.Value();
    worst = std::max(worst, excess);
    closer_than_occt += excess < -1e-9;
    if (ours[k].on_trim_edge) worst_edge_tolerance = std::max(worst_edge_tolerance, edge_tolerance);
    const Face& found = model.faces[static_cast<std::size_t>(ours[k].face)];
    EXPECT_LE(excess, ours[k].on_trim_edge ? std::max(1e-9, edge_tolerance) : found.exact ? 1e-9 : 1e-5) << "point " << k << " face " << ours[k].face << " ours " << ours[k].distance
                                      << " occt " << dist.Value() << " at " << q.transpose();
    on_edges += ours[k].on_trim_edge;
    // The foot point lies on its face, inside the trim (or on its boundary), by OpenCASCADE's classifier.
    const Point3& p = ours[k].point;
    BRepClass_FaceClassifier inside(faces[static_cast<std::size_t>(ours[k].face)], gp_Pnt(p.x(), p.y(), p.z()), 1e-6);
    EXPECT_NE(inside.State(), TopAbs_OUT) << "point " << k << " face " << ours[k].face;
  }
  std::cout << GetParam() << ": " << queries.size() << " points, worst (ours - occt) = " << worst << " mm, ours closer on "
            << closer_than_occt << ", " << on_edges << " on trim edges (largest edge tolerance there "
            << worst_edge_tolerance << " mm)\n";
}
INSTANTIATE_TEST_SUITE_P(CadFiles, ProjectOnCadFile,
                         ::testing::Values("asitus_wavy-cube.stp", "gismo_hammer.iges", "iges_spec_surf128.igs",
                                           "iges_spec_nentity.igs", "asitus_repatch-hpdc.stp"),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& c : n) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return n;
                         });

// The search with one face left out (a tip's second contact) against OpenCASCADE's distance to all the other faces:
// the face nearest each point is left out, and within a limit nothing farther is reported.
TEST(ModelLocator, ClosestPointOnOtherFacesEqualsOpenCascadeWithoutThatFace) {
  const std::filesystem::path path = kCadDir / "asitus_wavy-cube.stp";
  const Model model = read_model(path);
  const ModelLocator locator(model);
  const std::vector<TopoDS_Face> faces = testing::faces_of(testing::read_with_occt(path));
  const std::vector<Point3> queries = points_around(model, 40, 7);
  for (std::size_t k = 0; k < queries.size(); ++k) {
    const Point3& q = queries[k];
    const ModelPoint nearest = locator.closest_point(q);
    ASSERT_TRUE(nearest.ok());
    TopoDS_Compound others;
    BRep_Builder builder;
    builder.MakeCompound(others);
    for (std::size_t f = 0; f < faces.size(); ++f) {
      if (static_cast<int>(f) != nearest.face) builder.Add(others, faces[f]);
    }
    BRepExtrema_DistShapeShape dist(BRepBuilderAPI_MakeVertex(gp_Pnt(q.x(), q.y(), q.z())).Vertex(), others);
    ASSERT_TRUE(dist.IsDone());
    const ModelPoint other = locator.closest_point_on_other_faces(q, nearest.face, std::numeric_limits<double>::infinity());
    ASSERT_TRUE(other.ok()) << k;
    EXPECT_NE(other.face, nearest.face);
    EXPECT_NEAR(std::abs(other.distance), dist.Value(), 1e-6) << "point " << k;
    EXPECT_GE(std::abs(other.distance), std::abs(nearest.distance) - 1e-12);
    const ModelPoint none = locator.closest_point_on_other_faces(q, nearest.face, 0.5 * dist.Value());
    EXPECT_EQ(none.face, -1) << "point " << k;
  }
}

TEST(ModelLocator, SameResultWithOneAndTwoThreads) {
  const Model model = read_model(kCadDir / "gismo_hammer.iges");
  const ModelLocator locator(model);
  const std::vector<Point3> queries = points_around(model, 2000, 5);
  std::vector<ModelPoint> one, two;
  tbb::task_arena(1).execute([&] { one = locator.closest_points(queries); });
  tbb::task_arena(2).execute([&] { two = locator.closest_points(queries); });
  for (std::size_t k = 0; k < queries.size(); ++k) {
    EXPECT_EQ(one[k].face, two[k].face);
    EXPECT_EQ(one[k].u, two[k].u);
    EXPECT_EQ(one[k].v, two[k].v);
    EXPECT_EQ(one[k].distance, two[k].distance);
  }
}

// Queries near the model and each moved by up to `step` mm per coordinate: ICP's points before and after an update.
struct MovedQueries {
  std::vector<Point3> before, after;
};
MovedQueries moved_queries(const Model& model, std::uint64_t seed, double step) {
  MovedQueries q{points_around(model, 3000, seed), {}};
  std::mt19937_64 rng(seed + 1);
  std::uniform_real_distribution<double> d(-step, step);
  for (const Point3& p : q.before) q.after.push_back(p + simulation::draw_vector(d, rng));
  return q;
}

// The same distance as the unhinted search everywhere, and the same face but for ties at an edge.
void expect_same_answers(const std::vector<ModelPoint>& plain, const std::vector<ModelPoint>& hinted) {
  ASSERT_EQ(plain.size(), hinted.size());
  int same_face = 0;
  for (std::size_t k = 0; k < plain.size(); ++k) {
    ASSERT_EQ(plain[k].ok(), hinted[k].ok()) << k;
    if (!plain[k].ok()) continue;
    EXPECT_NEAR(std::abs(hinted[k].distance), std::abs(plain[k].distance), 1e-9) << k;
    same_face += hinted[k].face == plain[k].face;
  }
  EXPECT_GT(same_face, 0.99 * static_cast<double>(plain.size()));
}

TEST(ModelLocator, AHintFromANearbyQueryGivesTheSameAnswer) {
  // As in ICP: each point's foot before a small motion is the hint for its foot after it. The hinted search
  // is exact, so it must agree with the unhinted one: same distance, and the same point where it is unique.
  const Model model = read_model(kCadDir / "gismo_hammer.iges");
  const ModelLocator locator(model);
  const MovedQueries q = moved_queries(model, 8, 0.3);
  const std::vector<ModelPoint> hints = locator.closest_points(q.before);
  expect_same_answers(locator.closest_points(q.after), locator.closest_points(q.after, hints));
}

TEST(ModelLocator, FeetUpdatedInPlaceEqualTheUnhintedSearch) {
  // ICP's exact pass: each foot, found before a small motion, is replaced by the closest point after it. Its own
  // cell is not searched again (ClosestPointSolver's `known`), so the answer must still be the unhinted search's.
  const Model model = read_model(kCadDir / "gismo_hammer.iges");
  const ModelLocator locator(model);
  const MovedQueries q = moved_queries(model, 11, 0.05);
  std::vector<ModelPoint> feet = locator.closest_points(q.before);
  locator.update_closest_points(q.after, feet, ModelLocator::HintedSearch::Exact);
  expect_same_answers(locator.closest_points(q.after), feet);
  std::vector<ModelPoint> wrong(q.after.size() - 1);
  EXPECT_THROW(locator.update_closest_points(q.after, wrong), std::invalid_argument);
}

TEST(ModelLocator, PatchesFromALocalSearchAreThoseOfTheSurfaceAtEachFoot) {
  // ICP's local search hands out each foot's osculating paraboloid from Newton's own derivatives. Against the patch
  // made from a fresh evaluation at the foot, on a real file's faces (free-form and elementary, trimmed): the same
  // distance and parameters predicted for a point 0.05 mm along the face, or an invalid patch where Newton's foot did
  // not stand (a closed form, another face, a trim boundary), which ICP then makes itself.
  for (const char* file : {"gismo_hammer.iges", "asitus_wavy-cube.stp"}) {
    const Model model = read_model(kCadDir / file);
    const ModelLocator locator(model);
    const MovedQueries q = moved_queries(model, 13, 0.05);
    std::vector<ModelPoint> feet = locator.closest_points(q.before);
    std::vector<nurbs::OsculatingPatch> patches(q.after.size());
    locator.update_closest_points(q.after, feet, ModelLocator::HintedSearch::Local, patches);
    int valid = 0, compared = 0;
    for (std::size_t k = 0; k < feet.size(); ++k) {
      if (!patches[k].valid()) continue;
      ++valid;
      ASSERT_TRUE(feet[k].ok()) << k;
      const Face& face = model.faces[static_cast<std::size_t>(feet[k].face)];
      EXPECT_FALSE(face.analytic) << k;  // a closed form carries no second derivatives
      const nurbs::OsculatingPatch fresh =
          nurbs::OsculatingPatch::at(nurbs::derivatives_d2(face.surface, feet[k].u, feet[k].v), feet[k].normal);
      if (!fresh.valid()) continue;
      ++compared;
      // A point 0.05 mm along the face's tangent plane and 0.01 mm off it.
      const Vector3 t = feet[k].normal.unitOrthogonal();
      const Point3 x = feet[k].point + 0.05 * t + 0.01 * feet[k].normal;
      const nurbs::OsculatingPatch::Prediction a = patches[k].predict(feet[k].point, feet[k].normal, x);
      const nurbs::OsculatingPatch::Prediction b = fresh.predict(feet[k].point, feet[k].normal, x);
      EXPECT_NEAR(a.distance, b.distance, 1e-9) << k;
      EXPECT_NEAR(a.du, b.du, 1e-6 * (std::abs(b.du) + std::abs(b.dv))) << k;
      EXPECT_NEAR(a.dv, b.dv, 1e-6 * (std::abs(b.du) + std::abs(b.dv))) << k;
      EXPECT_LT((a.gradient - b.gradient).norm(), 1e-6) << k;
    }
    int elementary = 0;
    for (const ModelPoint& m : feet) {
      elementary += m.ok() && model.faces[static_cast<std::size_t>(m.face)].analytic != nullptr;
    }
    std::cout << "[ measured ] " << file << ": " << valid << " of " << feet.size() << " patches from Newton, " << compared
              << " compared; " << elementary << " feet on elementary faces\n";
    EXPECT_GT(valid, static_cast<int>(feet.size() - elementary) / 2) << file;
    std::vector<nurbs::OsculatingPatch> wrong(q.after.size() - 1);
    EXPECT_THROW(locator.update_closest_points(q.after, feet, ModelLocator::HintedSearch::Local, wrong),
                 std::invalid_argument);
  }
}

TEST(ModelLocator, SignedDistanceIsPositiveOutsideASolid) {
  // repatch-hpdc is a closed solid: points pushed out along the outward normal are outside the material.
  const Model model = read_model(kCadDir / "asitus_wavy-cube.stp");
  const ModelLocator locator(model);
  const std::vector<PlannedPoint> plan = plan_points(model, 0.2, {2});  // the bicubic face
  ASSERT_FALSE(plan.empty());
  for (const PlannedPoint& p : plan) {
    const ModelPoint out = locator.closest_point(p.point + 0.05 * p.normal);
    const ModelPoint in = locator.closest_point(p.point - 0.05 * p.normal);
    EXPECT_NEAR(out.distance, 0.05, 1e-9);
    EXPECT_NEAR(in.distance, -0.05, 1e-9);
  }
}

}  // namespace
}  // namespace probecomp::cad
