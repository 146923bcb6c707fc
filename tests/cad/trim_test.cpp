// Membership in a face's trim: a constructed loop whose curves meet only to a file's tolerance, and every
// face of the die-cast sample along its domain's edge lines (where a closest-point search clamps) against
// OpenCASCADE's face classifier, between the corners.

#include <BRepClass_FaceClassifier.hxx>
#include <gtest/gtest.h>

#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/model.hpp"
#include "probecomp/cad/trim.hpp"
#include "support/occt_files.hpp"

namespace probecomp::cad {
namespace {

nurbs::Curve line(double u0, double v0, double u1, double v1) {
  return nurbs::Curve(nurbs::KnotVector({0.0, 0.0, 1.0, 1.0}, 1), std::vector<Point3>{Point3(u0, v0, 0.0), Point3(u1, v1, 0.0)});
}

BoundaryCurve boundary(nurbs::Curve c) {
  BoundaryCurve b{std::move(c), {}, false};
  b.t = boundary_samples(b.uv, 1e-6);
  return b;
}

// The region u in [0.5, 1], v in [0, 1], as a file may give it: the left curve starts 1e-9 below v = 0 and the
// bottom one 1e-9 above. A ray along v = 0 from the left of the region passes through the gap between them.
TEST(Trim, ALoopThatMeetsOnlyToATolerancePassesRaysThroughItsGaps) {
  const Trim trim({boundary(line(0.5, -1e-9, 0.5, 1.0)), boundary(line(0.5, 1e-9, 1.0, 1e-9)),
                   boundary(line(1.0, 1e-9, 1.0, 1.0)), boundary(line(0.5, 1.0, 1.0, 1.0))});
  EXPECT_FALSE(trim.contains(0.2, 0.0));  // on the line of the bottom edge, left of the region
  EXPECT_FALSE(trim.contains(0.2, 0.5));
  EXPECT_FALSE(trim.contains(1.2, 0.0));
  EXPECT_TRUE(trim.contains(0.7, 0.5));
  EXPECT_TRUE(trim.contains(0.7, 1e-8));
}

// Each face's domain edge lines u = u_min, u_max and v = v_min, v_max, sampled: our trim's verdict against
// OpenCASCADE's face classifier. Points within 1 µm of the face's boundary are left out
// (either answer is right there).
TEST(Trim, DomainEdgeLinesOfTheDieCastSampleAgreeWithOpenCascade) {
  const std::filesystem::path path = std::filesystem::path(PROBECOMP_TEST_CAD_DIR) / "asitus_repatch-hpdc.stp";
  const Model model = read_model(path);
  const std::vector<TopoDS_Face> faces = testing::faces_of(testing::read_with_occt(path));
  ASSERT_EQ(faces.size(), model.faces.size());
  constexpr int kSamples = 24;
  int checked = 0, disagree = 0;
  for (std::size_t f = 0; f < model.faces.size(); ++f) {
    const Face& face = model.faces[f];
    if (!face.trimmed()) continue;
    const TrimmedFaceLocator locator(face);
    const nurbs::Surface& s = face.surface;
    const double u[2] = {s.U().front(), s.U().back()}, v[2] = {s.V().front(), s.V().back()};
    for (int k = 1; k < kSamples; ++k) {  // not the corners: OpenCASCADE's classifier is unsure where loops have gaps
      const double a = static_cast<double>(k) / kSamples;
      const double uv[4][2] = {{u[0], v[0] + a * (v[1] - v[0])},
                               {u[1], v[0] + a * (v[1] - v[0])},
                               {u[0] + a * (u[1] - u[0]), v[0]},
                               {u[0] + a * (u[1] - u[0]), v[1]}};
      for (const auto& [pu, pv] : uv) {
        const Point3 p = nurbs::evaluate(s, pu, pv);
        if (locator.closest_point_on_boundary(p, 1e-3).distance < 1e-3) continue;
        // A B-spline face keeps the file's parametrisation, so OpenCASCADE classifies the same (u, v) on its own
        // pcurves; an analytic face is converted, so the 3D point is classified (projected on its surface).
        BRepClass_FaceClassifier occt;
        if (face.source_type == "bspline") {
          occt.Perform(faces[f], gp_Pnt2d(pu, pv), 1e-9);
        } else {
          occt.Perform(faces[f], gp_Pnt(p.x(), p.y(), p.z()), 1e-6);
        }
        if (occt.State() == TopAbs_ON) continue;
        ++checked;
        const bool ours = face.trim->contains(pu, pv);
        if (ours != (occt.State() == TopAbs_IN)) {
          ++disagree;
          ADD_FAILURE() << "face " << f << " (u, v) = (" << pu << ", " << pv << "): ours " << ours << ", OpenCASCADE "
                        << (occt.State() == TopAbs_IN ? "in" : "out");
        }
      }
    }
  }
  EXPECT_GT(checked, 1000);
  EXPECT_EQ(disagree, 0) << "of " << checked;
}

}  // namespace
}  // namespace probecomp::cad
