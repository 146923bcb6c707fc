// The two registration routes, on a case with a known answer.

#include "probecomp/registration/routes.hpp"

#include "probecomp/compensation/conventional.hpp"

#include <gtest/gtest.h>

#include <iostream>

#include "registration/support.hpp"
#include "support/test_surfaces.hpp"

namespace probecomp::registration {
namespace {

using testing::largest_disagreement;
using testing::probe;
using testing::Probed;
using testing::single_face_model;

const geometry::RigidTransform kRoutesMisalignment = geometry::from_pose({.rx = -0.5, .ry = 0.8, .rz = 0.4, .t = Vector3(-0.7, 0.4, 0.6)});

TEST(Routes, RawCentresAgainstTheOffsetModelRecoverTheMotion) {
  // The material is on the −(S_u × S_v) side of this face, and the file says so.
  cad::Model nominal = single_face_model(testing::random_rational_surface(21, {.nu = 8, .nv = 8, .height = 6.0}), -1);
  const Probed p = probe(kRoutesMisalignment, nominal.faces[0].surface, 1.0, -1, 60);
  const cad::OffsetModel offset = cad::offset_model(nominal, 1.0, {.tolerance = 1e-5});
  ASSERT_EQ(offset.failed(), 0);
  const RegistrationResult r = register_to_offset_model(offset, p.centres);
  ASSERT_TRUE(r.converged()) << r.stop_reason;
  const RegistrationResult c = compensation::register_conventional(nominal, p.centres, p.approach, 1.0);
  ASSERT_TRUE(c.converged()) << c.stop_reason;
  // The offset surface is a fit to 1e-5 mm: the motion comes back to about that.
  EXPECT_LT(largest_disagreement(r.transform, kRoutesMisalignment, p.contacts), 2e-5);
  std::cout << "[ measured ] proposed: largest point error " << largest_disagreement(r.transform, kRoutesMisalignment, p.contacts)
            << " mm; conventional: " << largest_disagreement(c.transform, kRoutesMisalignment, p.contacts) << " mm\n";
  // The conventional route, with approach normals from the unperturbed model, is off by the compensation
  // error r·(1 − cos θ) along the actual normal and r·sin θ across it: it is worse but converges.
  EXPECT_GT(largest_disagreement(c.transform, kRoutesMisalignment, p.contacts),
            5.0 * largest_disagreement(r.transform, kRoutesMisalignment, p.contacts));
}

// Issue 21: centres of tips of three radii against the model offset by the smallest. Each centre's target lies
// its radius's difference farther out; with it, the motion comes back as well as with one tip, and without it
// (every centre taken for the smallest tip) it does not.
TEST(Routes, CentresOfSeveralTipRadiiRecoverTheMotionAgainstTheSmallestTipsOffset) {
  cad::Model nominal = single_face_model(testing::random_rational_surface(21, {.nu = 8, .nv = 8, .height = 6.0}), -1);
  const double radii[] = {0.5, 1.0, 2.0};
  const Probed one = probe(kRoutesMisalignment, nominal.faces[0].surface, 1.0, -1, 60);
  Probed p = one;
  std::vector<double> beyond(p.centres.size());
  for (std::size_t k = 0; k < p.centres.size(); ++k) {
    const double r = radii[k % 3];
    // The contact, moved out along the actual (placed) normal by this tip's radius.
    p.centres[k] = p.contacts[k] + r * (kRoutesMisalignment.linear() * p.approach[k]);
    beyond[k] = r - 0.5;
  }
  const cad::OffsetModel offset = cad::offset_model(nominal, 0.5, {.tolerance = 1e-5});
  ASSERT_EQ(offset.failed(), 0);
  const cad::ModelLocator locator(offset.model);
  const RegistrationResult r = register_to_offset_model(offset, locator, p.centres, {}, beyond);
  ASSERT_TRUE(r.converged()) << r.stop_reason;
  EXPECT_LT(largest_disagreement(r.transform, kRoutesMisalignment, p.contacts), 2e-5);
  for (const PointMatch& m : r.matches) ASSERT_LT(std::abs(m.distance), 2e-5);  // from each point's own target
  const RegistrationResult wrong = register_to_offset_model(offset, locator, p.centres);
  EXPECT_GT(largest_disagreement(wrong.transform, kRoutesMisalignment, p.contacts), 0.01);
  std::cout << "[ measured ] three tip radii: largest point error " << largest_disagreement(r.transform, kRoutesMisalignment, p.contacts)
            << " mm; taken for one radius: " << largest_disagreement(wrong.transform, kRoutesMisalignment, p.contacts) << " mm\n";
}

}  // namespace
}  // namespace probecomp::registration
