// offset_model on real CAD files: each face point moved by the offset distance along the face's outward normal
// (an independent route: the nominal face's own geometry) lies on the offset model.

#include "probecomp/cad/offset_model.hpp"

#include <gtest/gtest.h>

#include <random>

#include "probecomp/cad/locator.hpp"
#include "support/data_files.hpp"

namespace probecomp::cad {
namespace {

using test::kCadDir;

class OffsetCadFile : public ::testing::TestWithParam<const char*> {};

TEST_P(OffsetCadFile, FacePointsMovedAlongTheOutwardNormalLieOnTheOffsetModel) {
  const Model model = read_model(kCadDir / GetParam());
  constexpr double r = 1.0;
  const OffsetModel offset = offset_model(model, r);
  ASSERT_EQ(offset.model.faces.size(), model.faces.size());
  for (std::size_t k = 0; k < offset.faces.size(); ++k) {
    if (!offset.faces[k].ok()) {
      // A face that curves more tightly than the radius towards the outside cannot be offset: it must say so.
      EXPECT_EQ(offset.faces[k].status, fitting::OffsetResult::Status::FoldsOver)
          << "face " << k << " (" << model.faces[k].source_type << ", " << model.faces[k].surface.num_u() << "x"
          << model.faces[k].surface.num_v() << "): " << fitting::to_string(offset.faces[k].status) << ", deviation "
          << offset.faces[k].deviation << " mm after " << offset.faces[k].rounds << " fits, "
          << offset.faces[k].surface.num_u() << "x" << offset.faces[k].surface.num_v() << " control points";
      EXPECT_LE(offset.faces[k].min_radius_towards_offset, r);
    }
  }
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> t(0.0, 1.0);
  double worst = 0.0;
  for (std::size_t k = 0; k < model.faces.size(); ++k) {
    if (!offset.faces[k].ok()) continue;
    const Face& face = model.faces[k];
    const nurbs::Domain d = face.surface.domain();
    for (int m = 0; m < 200; ++m) {
      const double u = d.u0 + (d.u1 - d.u0) * t(rng), v = d.v0 + (d.v1 - d.v0) * t(rng);
      if (face.trimmed() && !face.trim->contains(u, v)) continue;
      const nurbs::UnitNormal n = nurbs::unit_normal(face.surface, u, v);
      if (n.status != nurbs::UnitNormal::Status::OK) continue;
      const Point3 centre = nurbs::evaluate(face.surface, u, v) + r * face.outward * n.n;
      const nurbs::ClosestPointResult on =
          nurbs::refine_closest_point(offset.model.faces[k].surface, centre, u, v);
      ASSERT_TRUE(on.ok());
      worst = std::max(worst, on.distance);
    }
  }
  EXPECT_LE(worst, 1e-4);
  RecordProperty("worst_gap_mm", std::to_string(worst));
  RecordProperty("failed_faces", offset.failed());
}

INSTANTIATE_TEST_SUITE_P(CadFiles, OffsetCadFile,
                         ::testing::Values("iges_spec_surf128.igs", "gismo_hammer.iges", "asitus_wavy-cube.stp",
                                           "asitus_repatch-hpdc.stp"));

}  // namespace
}  // namespace probecomp::cad
