// Face outlines against closed forms: an untrimmed plane patch's four sides and iso-parameter lines, and a real
// trimmed model's outline within its faces' boxes.

#include "probecomp/cad/outline.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "probecomp/nurbs/constructors.hpp"
#include "support/data_files.hpp"

namespace probecomp::cad {
namespace {

using test::kCadDir;

TEST(FaceOutline, APlanePatchHasItsFourSidesAndItsIsolines) {
  const Face face{.index = 0, .name = "", .source_type = "plane",
                  .surface = nurbs::make_plane_patch(Point3(1, 2, 3), Vector3(8, 0, 0), Vector3(0, 4, 0)), .trim = nullptr};
  const std::vector<Polyline> lines = face_outline(face, {.isolines = 3, .samples_per_line = 5});
  ASSERT_EQ(lines.size(), 4u + 6u);
  for (const Polyline& l : lines) {
    ASSERT_EQ(l.size(), 5u);
    for (const Point3& p : l) {
      EXPECT_NEAR(p.z(), 3.0, 1e-12);
      EXPECT_GE(p.x(), 1.0 - 1e-12);
      EXPECT_LE(p.x(), 9.0 + 1e-12);
      EXPECT_GE(p.y(), 2.0 - 1e-12);
      EXPECT_LE(p.y(), 6.0 + 1e-12);
    }
  }
  // The sides u = 0 and u = 1 run along y at x = 1 and x = 9; the isolines at u = 1/4, 1/2, 3/4 at x = 3, 5, 7.
  EXPECT_NEAR(lines[0].front().x(), 1.0, 1e-12);
  EXPECT_NEAR(lines[1].front().x(), 9.0, 1e-12);
  EXPECT_NEAR(lines[4].front().x(), 3.0, 1e-12);
  EXPECT_NEAR(lines[6].front().x(), 5.0, 1e-12);
  EXPECT_NEAR(lines[8].front().x(), 7.0, 1e-12);
  EXPECT_NEAR(lines[5].front().y(), 3.0, 1e-12);  // v = 1/4
}

TEST(FaceOutline, ATrimmedModelsOutlineLiesWithinItsFaces) {
  const Model model = Model::load(kCadDir / "asitus_repatch-hpdc.stp");
  std::size_t trimmed = 0;
  for (const Face& f : model.faces) {
    if (!f.trimmed()) continue;
    ++trimmed;
    const BoundingBox box = nurbs::bounding_box(f.surface);  // the control net's box holds the surface
    for (const Polyline& l : face_outline(f)) {
      EXPECT_GE(l.size(), 2u);
      for (const Point3& p : l) {
        ASSERT_TRUE(p.allFinite());
        EXPECT_TRUE(box.contains(p, 1e-6));
      }
    }
  }
  EXPECT_GT(trimmed, 10u);

}

}  // namespace
}  // namespace probecomp::cad
