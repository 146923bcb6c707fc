// compensate_points' check of each fitted row's normal against the nominal part's (src/compensation/
// contact_points.cpp, kTurnedDegrees), on a flat plate whose fit is replaced by the same fit turned about a line
// across the plate: the contacts the nominal part gives are then known in closed form (straight below each centre,
// r away), and so is how far each row's contact is from them.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/nurbs/constructors.hpp"

namespace probecomp::compensation {
namespace {

constexpr double kRadius = 1.0;  // mm

// A 40 × 40 mm plate at z = 0, material below, touched from above on a 25 × 25 grid (centres at z = r, no noise).
struct Plate {
  cad::Model model;
  std::vector<Point3> raw;
  std::vector<Vector3> normals;
  Plate() {
    nurbs::Surface s = nurbs::make_plane_patch(Point3(0, 0, 0), Vector3(40, 0, 0), Vector3(0, 40, 0), 3, 3, 4, 4);
    model.faces.push_back(cad::Face{.index = 0, .name = "plate", .source_type = "plane", .surface = std::move(s),
                                    .trim = nullptr, .outward = 1, .material_known = false, .exact = true});
    for (int i = 0; i < 25; ++i) {
      for (int j = 0; j < 25; ++j) {
        raw.emplace_back(2.0 + 1.5 * i, 2.0 + 1.5 * j, kRadius);
        normals.emplace_back(0, 0, 1);
      }
    }
  }
  // The contact the nominal plate gives row k: r straight below its centre.
  [[nodiscard]] Point3 nominal_contact(std::size_t k) const { return raw[k] - kRadius * Vector3::UnitZ(); }
};

// The fitted centre surface turned by `degrees` about the line x = 20, z = r (along y).
nurbs::Surface turned(const nurbs::Surface& s, double degrees) {
  const Eigen::AngleAxisd R(degrees * std::numbers::pi / 180.0, Vector3::UnitY());
  const Point3 pivot(20.0, 0.0, kRadius);
  std::vector<HomogeneousPoint> Pw = s.homogeneous();
  for (HomogeneousPoint& h : Pw) {
    const Point3 P = h.head<3>() / h.w();
    h.head<3>() = h.w() * (pivot + R * (P - pivot));
  }
  return nurbs::Surface(s.U(), s.V(), std::move(Pw));
}

struct TurnedRun {
  std::vector<CompensatedPoint> points;
  std::vector<std::string> warnings;
};

TurnedRun compensate_with_fit_turned(const Plate& plate, double degrees) {
  const PreparedModel prepared = prepare_model(plate.model, kRadius, plate.raw, std::span<const Vector3>(plate.normals));
  const registration::RegistrationResult reg = register_centres(prepared, plate.raw);
  FitResult fits = fit_faces(prepared, plate.raw, reg);
  EXPECT_EQ(fits.faces.size(), 1u);
  EXPECT_TRUE(fits.faces.at(0).fit.has_value());
  if (degrees != 0.0) fits.faces[0].fit->surface = turned(fits.faces[0].fit->surface, degrees);
  TurnedRun run;
  run.points = compensate_points(prepared, plate.raw, reg, fits, &run.warnings);
  return run;
}

// Exact data on a plate: every contact on the plate straight below its centre, u under half a micrometre (0.1 µm:
// the fit's floor on exact data), nothing to warn about.
TEST(TurnedNormal, AnUnturnedFitRaisesNothing) {
  const Plate plate;
  const TurnedRun run = compensate_with_fit_turned(plate, 0.0);
  ASSERT_EQ(run.points.size(), plate.raw.size());
  for (std::size_t k = 0; k < run.points.size(); ++k) {
    const CompensatedPoint& c = run.points[k];
    ASSERT_EQ(c.status, PointStatus::Ok) << k;
    EXPECT_LE((c.contact - plate.nominal_contact(k)).norm(), 1e-6) << k;
    EXPECT_LE(c.uncertainty, 5e-4) << k;
  }
  EXPECT_TRUE(run.warnings.empty()) << run.warnings.front();
}

// Turned 60° (more than any deformation tilts a part's surface): each row stays, its u covers the distance between
// its contact and the nominal part's (r below the centre), and a warning says how far the normals are turned.
// Turned 30° (as a steep dent's slope), nothing is said.
TEST(TurnedNormal, AFitTurnedFurtherThanADeformationTurnsHoldsTheNominalContactInU) {
  const Plate plate;
  for (const double degrees : {30.0, 60.0}) {
    SCOPED_TRACE(::testing::Message() << degrees << " degrees");
    const TurnedRun run = compensate_with_fit_turned(plate, degrees);
    ASSERT_EQ(run.points.size(), plate.raw.size());
    double farthest = 0.0;
    for (std::size_t k = 0; k < run.points.size(); ++k) {
      const CompensatedPoint& c = run.points[k];
      ASSERT_EQ(c.status, PointStatus::Ok) << k;
      EXPECT_NEAR(std::acos(c.normal.z()) * 180.0 / std::numbers::pi, degrees, 1e-6) << k;
      const double apart = (c.contact - plate.nominal_contact(k)).norm();
      farthest = std::max(farthest, apart);
      if (degrees > 45.0) {
        EXPECT_GE(c.uncertainty, apart) << k;
      } else {
        EXPECT_LE(c.uncertainty, 1e-3) << k;  // the guard stays out of a steep but possible shape's way
      }
    }
    if (degrees > 45.0) {
      ASSERT_EQ(run.warnings.size(), 1u);
      EXPECT_NE(run.warnings[0].find("at 625 rows the fitted normal is turned up to 60°"), std::string::npos)
          << run.warnings[0];
      EXPECT_EQ(run.warnings[0].find("outliers"), std::string::npos) << run.warnings[0];
      EXPECT_GT(farthest, 1.0);  // the turned fit's contacts are millimetres from the nominal part's
    } else {
      EXPECT_TRUE(run.warnings.empty()) << run.warnings.front();
    }
  }
}

// Turned 120° and 180°: the fit is inside out (its normal points into the material), and every row is an outlier.
TEST(TurnedNormal, AFitInsideOutMakesEveryRowAnOutlier) {
  const Plate plate;
  for (const double degrees : {120.0, 180.0}) {
    SCOPED_TRACE(::testing::Message() << degrees << " degrees");
    const TurnedRun run = compensate_with_fit_turned(plate, degrees);
    ASSERT_EQ(run.points.size(), plate.raw.size());
    for (std::size_t k = 0; k < run.points.size(); ++k) {
      const CompensatedPoint& c = run.points[k];
      EXPECT_EQ(c.status, PointStatus::Outlier) << k;
      EXPECT_GE(c.uncertainty, (c.contact - plate.nominal_contact(k)).norm()) << k;
    }
    ASSERT_EQ(run.warnings.size(), 1u);
    EXPECT_NE(run.warnings[0].find("the 625 turned past 90° (the fit inside out) are outliers"), std::string::npos)
        << run.warnings[0];
  }
}

}  // namespace
}  // namespace probecomp::compensation
