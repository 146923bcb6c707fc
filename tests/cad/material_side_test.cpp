// The choice of each face's material side, on cases with a known answer.

#include "probecomp/cad/material_side.hpp"

#include <gtest/gtest.h>

#include "probecomp/cad/locator.hpp"
#include "registration/support.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::cad {
namespace {

using probecomp::testing::probe;
using probecomp::testing::Probed;
using probecomp::testing::single_face_model;

const geometry::RigidTransform kMisalignment = geometry::from_pose({.rx = -0.5, .ry = 0.8, .rz = 0.4, .t = Vector3(-0.7, 0.4, 0.6)});

TEST(MaterialSide, FromTheDataAndFromTheApproachNormals) {
  const nurbs::Surface s = testing::random_rational_surface(22, {.nu = 8, .nv = 8, .height = 6.0});
  const Probed p = probe(kMisalignment, s, 1.0, -1, 30);  // probed from the −(S_u × S_v) side
  for (bool with_normals : {false, true}) {
    cad::Model m = single_face_model(s, +1, false);  // the file's orientation is the wrong one
    std::optional<std::span<const Vector3>> normals;
    if (with_normals) normals = std::span<const Vector3>(p.approach);
    // The initial transform is the nominal pose: the misalignment (about 1 mm) is unknown at this stage.
    const std::vector<MaterialSide> sides = decide_material_side(m, p.centres, normals, geometry::RigidTransform::Identity());
    ASSERT_EQ(sides.size(), 1u);
    EXPECT_EQ(sides[0].outward, -1);
    EXPECT_EQ(m.faces[0].outward, -1);
    EXPECT_EQ(sides[0].source, with_normals ? MaterialSource::ApproachNormals : MaterialSource::Data);
    EXPECT_GT(sides[0].agreeing, 0.9 * sides[0].points);
    if (!with_normals) {
      EXPECT_GT(sides[0].median_distance, 0.0);  // r = 1 mm give or take the misalignment
    }
  }
  // A face from a solid keeps its side whatever the points say.
  cad::Model solid = single_face_model(s, +1, true);
  const std::vector<MaterialSide> sides = decide_material_side(solid, p.centres, std::nullopt, geometry::RigidTransform::Identity());
  EXPECT_EQ(sides[0].source, MaterialSource::Solid);
  EXPECT_EQ(solid.faces[0].outward, +1);
}

TEST(MaterialSide, AGivenLocatorDecidesAndThenAnswersWithTheDecidedSide) {
  // The pipeline makes one locator of the nominal model for the vote and for everything after: the vote flips the
  // face, and the same locator's normals and distances then follow the decided side.
  const nurbs::Surface s = testing::random_rational_surface(22, {.nu = 8, .nv = 8, .height = 6.0});
  const Probed p = probe(kMisalignment, s, 1.0, -1, 30);  // probed from the −(S_u × S_v) side
  cad::Model m = single_face_model(s, +1, false);
  const ModelLocator locator(m);
  const ModelPoint before = locator.closest_point(p.centres[100]);
  const std::vector<MaterialSide> sides =
      decide_material_side(m, locator, p.centres, std::nullopt, geometry::RigidTransform::Identity());
  EXPECT_EQ(sides[0].outward, -1);
  EXPECT_EQ(sides[0].source, MaterialSource::Data);
  const ModelPoint after = locator.closest_point(p.centres[100]);
  EXPECT_LT(before.distance, 0.0);  // on the side the file called inside
  EXPECT_NEAR(after.distance, -before.distance, 1e-12);
  EXPECT_LT((after.normal + before.normal).norm(), 1e-12);
  cad::Model other = single_face_model(s, +1, false);
  EXPECT_THROW((void)decide_material_side(other, locator, p.centres, std::nullopt, geometry::RigidTransform::Identity()),
               std::invalid_argument);
}

TEST(MaterialSide, ManyPointsVoteByASubsetUnlessAFaceHasTooFewVotesThere) {
  // 360 000 points on one face: a spread subset decides it. With a second face far away and only 400 points on it
  // (about 70 in the subset), all points vote, as without the subset.
  const nurbs::Surface s = testing::random_rational_surface(22, {.nu = 8, .nv = 8, .height = 6.0});
  const Probed big = probe(kMisalignment, s, 1.0, -1, 600);
  Eigen::Isometry3d away = Eigen::Isometry3d::Identity();
  away.translation() = Vector3(0, 0, 200);
  const nurbs::Surface t = nurbs::transformed(s, away);
  const Probed small = probe(kMisalignment, t, 1.0, +1, 20);
  for (bool with_small : {false, true}) {
    cad::Model m = single_face_model(s, +1, false);
    std::vector<Point3> centres = big.centres;
    if (with_small) {
      m.faces.push_back(m.faces[0]);
      m.faces[1].index = 1;
      m.faces[1].surface = t;
      centres.insert(centres.end(), small.centres.begin(), small.centres.end());
    }
    const std::vector<MaterialSide> sides = decide_material_side(m, centres, std::nullopt, geometry::RigidTransform::Identity());
    EXPECT_EQ(sides[0].outward, -1);
    EXPECT_EQ(sides[0].source, MaterialSource::Data);
    EXPECT_GT(sides[0].agreeing, 0.99 * sides[0].points);
    if (!with_small) {
      EXPECT_LE(sides[0].points, 72000);  // the subset's votes: every 5th point
      continue;
    }
    EXPECT_EQ(sides[0].points + sides[1].points, static_cast<int>(centres.size()));  // every point voted
    EXPECT_EQ(sides[1].points, 400);
    EXPECT_EQ(sides[1].outward, +1);
    EXPECT_EQ(sides[1].source, MaterialSource::Data);
  }
}

TEST(MaterialSide, TenThousandPointsVoteByAQuarterOfThem) {
  // 10 000 points on one face: a spread quarter (every 4th point) decides it, as the data would all together.
  const nurbs::Surface s = testing::random_rational_surface(22, {.nu = 8, .nv = 8, .height = 6.0});
  const Probed p = probe(kMisalignment, s, 1.0, -1, 100);
  cad::Model m = single_face_model(s, +1, false);
  const std::vector<MaterialSide> sides = decide_material_side(m, p.centres, std::nullopt, geometry::RigidTransform::Identity());
  EXPECT_EQ(sides[0].outward, -1);
  EXPECT_EQ(sides[0].source, MaterialSource::Data);
  EXPECT_GE(sides[0].points, 1000);
  EXPECT_LE(sides[0].points, 2500);
  EXPECT_GT(sides[0].agreeing, 0.99 * sides[0].points);
}

}  // namespace
}  // namespace probecomp::cad
