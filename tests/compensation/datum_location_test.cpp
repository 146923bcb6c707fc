// A part located by its datum features alone (compensation::RegisterOptions::datum_faces): a block whose three
// non-datum faces stand 0.9 mm proud, measured 3 mm and 4° off with no initial transform. The best fit of all the
// points is pulled half-way to them and refused as doubtful; located by its bottom, front and left faces (3-2-1) the
// part comes back where it was placed, and the proud faces read their 0.9 mm. Truth: the placement and the moves the
// simulation was given (the block is OpenCASCADE's; its faces offset exactly, being planes).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/offset_model.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/error.hpp"
#include "probecomp/simulation/measure.hpp"
#include "support/prismatic_parts.hpp"

namespace probecomp::compensation {
namespace {

constexpr double kProud = 0.9;  // mm, outward, on the top, right and back faces

struct Measured {
  cad::Model nominal = testing::block_with_hole();
  testing::BlockWithHoleFaces f = testing::faces_of_block_with_hole(nominal);
  geometry::RigidTransform placement =
      Eigen::Translation3d(3.0, -2.0, 1.5) * Eigen::AngleAxisd(4.0 * M_PI / 180, Vector3(2, -1, 3).normalized());
  std::vector<Point3> centres;
  std::vector<Vector3> normals;
  std::vector<int> faces;     // the nominal face each touch was programmed on
  std::vector<double> moves;  // its face's outward move, mm
};

const Measured& measured() {
  static const Measured m = [] {
    Measured m;
    std::map<int, double> moved{{m.f.top, kProud}, {m.f.right, kProud}, {m.f.back, kProud}};
    cad::Model actual = m.nominal;
    for (const auto& [f, move] : moved) {
      cad::Model one;
      one.faces = {m.nominal.faces[static_cast<std::size_t>(f)]};
      actual.faces[static_cast<std::size_t>(f)] = cad::offset_model(one, move).model.faces.front();
    }
    // Grids 4 mm and more inside each face's edges, the hole's rim kept clear.
    std::vector<simulation::ProgrammedPoint> plan;
    const auto add = [&](const Point3& p, const Vector3& n, int face) {
      plan.push_back({m.placement * p, m.placement.linear() * n, face});
    };
    for (double x = 5; x <= 55; x += 5) {
      for (double y = 5; y <= 35; y += 5) {
        if (std::hypot(x - 40, y - 20) < 7) continue;
        add(Point3(x, y, 0), -Vector3::UnitZ(), m.f.bottom);
        add(Point3(x, y, 20), Vector3::UnitZ(), m.f.top);
      }
      for (double z = 4; z <= 16; z += 4) {
        add(Point3(x, 0, z), -Vector3::UnitY(), m.f.front);
        add(Point3(x, 40, z), Vector3::UnitY(), m.f.back);
      }
    }
    for (double y = 5; y <= 35; y += 5) {
      for (double z = 4; z <= 16; z += 4) {
        add(Point3(0, y, z), -Vector3::UnitX(), m.f.left);
        add(Point3(60, y, z), Vector3::UnitX(), m.f.right);
      }
    }
    const cad::Model placed = simulation::actual_model(actual, {}, m.placement);
    const std::vector<simulation::Touch> touches = simulation::simulate_touches(
        cad::ModelLocator(placed), plan, {.probe_radius = 1.0, .noise_sigma = 0.002, .seed = 11});
    for (std::size_t i = 0; i < touches.size(); ++i) {
      if (touches[i].status != simulation::Touch::Status::OK) continue;
      m.centres.push_back(touches[i].measured);
      m.normals.push_back(plan[i].normal);
      m.faces.push_back(plan[i].face);
      m.moves.push_back(moved.contains(plan[i].face) ? moved.at(plan[i].face) : 0.0);
    }
    return m;
  }();
  return m;
}

CompensateOptions options_with(std::vector<int> datum_faces) {
  CompensateOptions o;
  o.probe_radius = 1.0;
  o.datum_faces = std::move(datum_faces);
  return o;
}

TEST(DatumLocation, WithoutDatumsAPartThatDeviatesByAboutItsRadiusIsRefusedAsDoubtful) {
  const Measured& m = measured();
  ASSERT_EQ(m.centres.size(), 288u);  // every programmed touch made
  try {
    (void)compensate(m.nominal, m.centres, m.normals, options_with({}));
    FAIL() << "a best fit pulled half-way to the proud faces was accepted";
  } catch (const RegistrationError& e) {
    EXPECT_NE(std::string(e.what()).find("doubtful"), std::string::npos) << e.what();
  }
}

TEST(DatumLocation, ThreeTwoOnePlanesLocateThePartAndTheOtherFacesReadTheirMoves) {
  const Measured& m = measured();
  const CompensationResult r = compensate(m.nominal, m.centres, m.normals, options_with({m.f.bottom, m.f.front, m.f.left}));
  ASSERT_FALSE(r.registration.located_by.empty());
  const bool noted = std::any_of(r.registration.notes.begin(), r.registration.notes.end(), [](const std::string& n) {
    return n.find("located by the") != std::string::npos && n.find("datum features") != std::string::npos;
  });
  EXPECT_TRUE(noted);
  // Only the datum faces' points located it.
  for (std::size_t k = 0; k < m.centres.size(); ++k) {
    const bool on_datum = m.faces[k] == m.f.bottom || m.faces[k] == m.f.front || m.faces[k] == m.f.left;
    EXPECT_EQ(r.registration.located_by[k] != 0, on_datum) << "row " << k;
  }
  // Where it put the part: the block's corners within 3 µm of the placement (σ = 2 µm on about 220 datum touches).
  double worst_corner = 0.0;
  for (const double x : {0.0, 60.0}) {
    for (const double y : {0.0, 40.0}) {
      for (const double z : {0.0, 20.0}) {
        const Point3 c(x, y, z);
        worst_corner = std::max(worst_corner, (r.registration.transform * c - m.placement * c).norm());
      }
    }
  }
  EXPECT_LT(worst_corner, 0.003);
  // Every row comes back, on the face it was touched on, with its face's move as its deviation.
  ASSERT_EQ(r.points.size(), m.centres.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < r.points.size(); ++k) {
    const CompensatedPoint& p = r.points[k];
    ASSERT_EQ(p.status, PointStatus::Ok) << "row " << k;
    ASSERT_EQ(p.face, m.nominal.faces[static_cast<std::size_t>(m.faces[k])].index) << "row " << k;
    worst = std::max(worst, std::abs(p.deviation - m.moves[k]));
  }
  EXPECT_LT(worst, 0.010);
  std::printf("[ measured ] corners within %.4f mm of the placement; largest |deviation - move| %.4f mm\n", worst_corner,
              worst);
}

TEST(DatumLocation, DatumsThatLeaveMotionsFreeDoNotLocateThePartAndTheRefusalSaysSo) {
  const Measured& m = measured();
  try {
    (void)compensate(m.nominal, m.centres, m.normals, options_with({m.f.bottom}));
    FAIL() << "a plane alone was taken to locate the part";
  } catch (const RegistrationError& e) {
    EXPECT_NE(std::string(e.what()).find("fixes 3 of the 6 motions only"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace probecomp::compensation
