// Characteristics judged on compensated points against closed-form truth: a plate whose actual shape is twisted
// (one corner raised by h: z = h·s·t over the unit square of its parameters) measured against its flat nominal. The
// least-squares plane of z = h·s·t on a symmetric grid is h(s + t)/2 − h/4, so its form deviation is
// h(s − ½)(t − ½) and the flatness (a surface profile without datums) is h/2 over the grid's extreme points.

#include "probecomp/inspection/characteristics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "probecomp/error.hpp"
#include "probecomp/simulation/measure.hpp"
#include "support/data_files.hpp"

namespace probecomp::inspection {
namespace {

cad::Model plate(double raised_corner) {
  const nurbs::KnotVector U = nurbs::KnotVector::uniform(1, 1), V = nurbs::KnotVector::uniform(1, 1);
  cad::Model m;
  m.file_units = "mm";
  m.faces.push_back(cad::Face{.surface = nurbs::Surface(U, V, std::vector<Point3>{Point3(0, 0, 0), Point3(0, 40, 0), Point3(60, 0, 0),
                                                                                  Point3(60, 40, raised_corner)})});
  return m;
}

struct Measured {
  cad::Model nominal = plate(0.0);
  compensation::CompensationResult result;
  double grid_extent = 0.0;  // s and t of the grid's outer points run over [a, 1 − a]
};

// A 9 × 7 grid over the twisted plate (h = `h`), σ = 0.3 µm, compensated against the flat plate.
Measured measure(double h) {
  Measured out;
  const cad::Model actual = plate(h);
  std::vector<simulation::ProgrammedPoint> plan;
  out.grid_extent = 0.1;
  for (int i = 0; i < 9; ++i) {
    for (int j = 0; j < 7; ++j) {
      const double s = 0.1 + 0.8 * i / 8.0, t = 0.1 + 0.8 * j / 6.0;
      plan.push_back({Point3(60.0 * s, 40.0 * t, 0.0), Vector3::UnitZ(), 0});
    }
  }
  const std::vector<simulation::Touch> touches =
      simulation::simulate_touches(cad::ModelLocator(actual), plan, {.probe_radius = 1.0, .noise_sigma = 0.0003, .seed = 5});
  std::vector<Point3> centres;
  std::vector<Vector3> normals;
  for (std::size_t k = 0; k < touches.size(); ++k) {
    centres.push_back(touches[k].measured);
    normals.push_back(plan[k].normal);
  }
  compensation::CompensateOptions options;
  options.probe_radius = 1.0;
  out.result = compensation::compensate(out.nominal, centres, normals, options);
  return out;
}

Specification flatness(double t) {
  Specification s;
  s.characteristics.push_back({.name = "F1", .faces = {0}, .tolerance = t, .outside = {}, .datums = {}});
  return s;
}

TEST(Characteristics, AFlatnessIsTheTwistsHalfHeightAndItsDecisionFollowsTheZone) {
  constexpr double h = 0.04;
  const Measured m = measure(h);
  // The grid's extreme points sit at s, t = 0.1 and 0.9: h(s − ½)(t − ½) spans ±0.16 h, a width of 0.32 h.
  const double truth = 2.0 * 0.16 * h;
  const CharacteristicResult wide = evaluate(flatness(0.03), m.nominal, m.result).characteristics.at(0);
  std::printf("flatness %.2f um (truth %.2f um), u %.2f um, %d points, min %.2f max %.2f um: %s\n", wide.value * 1e3,
              truth * 1e3, wide.u * 1e3, wide.points, wide.min * 1e3, wide.max * 1e3, to_string(wide.decision));
  EXPECT_EQ(wide.points, 63);
  EXPECT_NEAR(wide.value, truth, 0.002);
  EXPECT_NEAR(wide.min, -0.16 * h, 0.001);
  EXPECT_NEAR(wide.max, 0.16 * h, 0.001);
  EXPECT_EQ(wide.decision, Decision::Conforms);
  // The decision's coverage factor keeps all 63 points' intervals right together with 95 % (Šidák): per point
  // 1 − 0.95^(1/63), split over two sides: k = 3.348 (normal quantile, as tabulated).
  EXPECT_NEAR(wide.coverage, 3.348, 0.001);
  // A zone narrower than the form by more than U: does not conform.
  EXPECT_EQ(evaluate(flatness(0.008), m.nominal, m.result).characteristics.at(0).decision, Decision::DoesNotConform);
  // A zone exactly the measured value: its extreme point sits on the limit, its ±U across it.
  EXPECT_EQ(evaluate(flatness(wide.value), m.nominal, m.result).characteristics.at(0).decision, Decision::Indeterminate);
}

// A point of large u (a contact whose normal the data could not confirm carries u up to r) holds the decision back
// however well inside the others are; the value and its 2u are the widest point's and do not show it, so the reason
// names how many points cross a limit, the largest U and its row (1-based, as the output's rows).
TEST(Characteristics, AnIndeterminateDecisionSaysWhichPointsHoldItBack) {
  Measured m = measure(0.04);
  const std::size_t doubtful = 17;
  m.result.points[doubtful].uncertainty = 1.0;  // r of a 2 mm stylus
  const CharacteristicResult f = evaluate(flatness(0.03), m.nominal, m.result).characteristics.at(0);
  ASSERT_EQ(f.decision, Decision::Indeterminate);
  ASSERT_EQ(f.undecided.size(), 1u);
  EXPECT_EQ(f.undecided.front(), doubtful);
  EXPECT_LT(f.u, 0.01);  // the widest point's, not the doubtful one's
  char expected[120];
  std::snprintf(expected, sizeof expected, "1 of its points' d +- U cross a limit of the zone; the largest U %.4f mm, row %zu",
                f.coverage * 1.0, doubtful + 1);
  EXPECT_EQ(f.reason, expected);
}

// Each point as the flatness judged it: its deviation from the best-fitted plane is the closed form at its place.
TEST(Characteristics, EachPointsDeviationIsTheClosedFormAtItsPlace) {
  constexpr double h = 0.04;
  const Measured m = measure(h);
  const CharacteristicResult f = evaluate(flatness(0.03), m.nominal, m.result).characteristics.at(0);
  ASSERT_EQ(f.judged.size(), 63u);
  double worst = 0.0, lowest = 1.0, highest = -1.0;
  for (std::size_t n = 0; n < f.judged.size(); ++n) {
    const JudgedPoint& p = f.judged[n];
    if (n > 0) EXPECT_GT(p.row, f.judged[n - 1].row);
    const double s = 0.1 + 0.8 * static_cast<double>(p.row / 7) / 8.0, t = 0.1 + 0.8 * static_cast<double>(p.row % 7) / 6.0;
    worst = std::max(worst, std::abs(p.deviation - h * (s - 0.5) * (t - 0.5)));
    EXPECT_GT(p.U, 0.0);
    lowest = std::min(lowest, p.deviation);
    highest = std::max(highest, p.deviation);
  }
  std::printf("largest |deviation - h(s - 1/2)(t - 1/2)| %.3f um\n", worst * 1e3);
  EXPECT_LT(worst, 0.001);
  EXPECT_EQ(lowest, f.min);
  EXPECT_EQ(highest, f.max);
  // The point farthest from the zone's middle (0 here) sets the value, and its U is k times the value's u / 2.
  const auto far = std::max_element(f.judged.begin(), f.judged.end(), [](const JudgedPoint& a, const JudgedPoint& b) {
    return std::abs(a.deviation) < std::abs(b.deviation);
  });
  EXPECT_DOUBLE_EQ(2.0 * std::abs(far->deviation), f.value);
  EXPECT_DOUBLE_EQ(far->U, f.coverage * f.u / 2.0);
}

TEST(Characteristics, WithADatumWithoutFacesOrTooFewPointsTheyAreNotEvaluatedWithTheReason) {
  const Measured m = measure(0.02);
  Specification s = flatness(0.05);
  s.characteristics[0].datums = {"A"};
  s.unusable_datums["A"] = "datum A is set by 3 datum targets (points or lines) the file does not place on a face";
  const CharacteristicResult with_datums = evaluate(s, m.nominal, m.result).characteristics.at(0);
  EXPECT_EQ(with_datums.decision, Decision::NotEvaluated);
  EXPECT_EQ(with_datums.reason, s.unusable_datums["A"]);
  // Six trusted points cannot show a form past the six motions of a best fit.
  compensation::CompensationResult few = m.result;
  for (std::size_t k = 6; k < few.points.size(); ++k) few.points[k].status = compensation::PointStatus::Outlier;
  const CharacteristicResult sparse = evaluate(flatness(0.05), m.nominal, few).characteristics.at(0);
  EXPECT_EQ(sparse.decision, Decision::NotEvaluated);
  EXPECT_EQ(sparse.points, 6);
  EXPECT_NE(sparse.reason.find("6 trusted points"), std::string::npos) << sparse.reason;
}

TEST(Characteristics, ABadSpecificationIsRefusedNamingTheFileAndTheCause) {
  const cad::Model model = plate(0.0);
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "probecomp_spec_test.json";
  auto refused = [&](const std::string& text, const std::string& cause) {
    std::ofstream(path) << text;
    try {
      (void)read_specification(path, model);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(cause), std::string::npos) << e.what();
    }
  };
  refused("{", "not JSON");
  refused(R"({"characteristics": [{"faces": [0]}]})", "no \"tolerance\"");
  refused(R"({"characteristics": [{"faces": [0], "tolerance": -1}]})", "must be positive");
  refused(R"({"characteristics": [{"faces": [3], "tolerance": 0.1}]})", "face 3 is not in the model");
  refused(R"({"characteristics": [{"faces": [0], "tolerance": 0.1, "datums": ["A"]}]})", "datum A is not defined");
  refused(R"({"characteristics": [{"type": "position", "faces": [0], "tolerance": 0.1}]})", "unknown type");
  refused(R"({"datums": {"A": {}}, "characteristics": []})", "datum A: no \"faces\"");
  refused(R"({"datums": {"A": {"faces": [7]}}, "characteristics": []})", "datum A: face 7 is not in the model");
  refused(R"({"datums": {"A": {"faces": [0], "fit": "minimum-zone"}}, "characteristics": []})", "unknown fit \"minimum-zone\"");
  refused(R"({"datums": {"A": {"faces": [0]}}, "alignment": ["Z"], "characteristics": []})", "alignment: datum Z is not defined");
  refused(R"({"datums": {"A": {"faces": [0]}}, "alignment": [], "characteristics": []})", "alignment: no datums");
  refused(R"({"datums": {"A": {"faces": [0], "targets": [[1, 2]]}}, "characteristics": []})", "datum A: a target's point must be [x, y, z]");
  refused(R"({"datums": {"A": {"faces": [0], "targets": [{"point": [1, 2, 0], "direction": [0, 1, 0]}]}}, "characteristics": []})",
          "datum A: a line target needs \"point\", \"direction\" and \"length\"");
  refused(R"({"datums": {"A": {"faces": [0], "targets": [{"point": [1, 2, 0], "direction": [0, 0, 0], "length": 5}]}}, "characteristics": []})",
          "datum A: a line target's direction must not be zero");
  refused(R"({"datums": {"A": {"faces": [0], "targets": [{"point": [1, 2, 0], "direction": [0, 1, 0], "length": 0}]}}, "characteristics": []})",
          "datum A: a line target's length must be positive");
  refused(R"({"datums": {"A": {"faces": [0], "targets": []}}, "characteristics": []})", "datum A: \"targets\" must be a list");
  std::ofstream(path) << R"({"datums": {"A": {"faces": [0], "fit": "tangent", "targets": [[1, 2, 0], [3, 4, 0.5], {"point": [1, 1, 0], "direction": [0, 2, 0], "length": 3}]}}, "alignment": ["A"], "characteristics": [{"name": "P", "faces": [0], "tolerance": 0.1, "outside": 0.02, "datums": ["A"]}]})";
  const Specification s = read_specification(path, model);
  ASSERT_EQ(s.characteristics.size(), 1u);
  EXPECT_EQ(s.characteristics[0].name, "P");
  EXPECT_DOUBLE_EQ(*s.characteristics[0].outside, 0.02);
  ASSERT_EQ(s.datums.size(), 1u);
  EXPECT_EQ(s.datums[0].name, "A");
  ASSERT_EQ(s.datums[0].targets.size(), 3u);
  EXPECT_EQ(s.datums[0].targets[1].label, "A2");
  EXPECT_EQ(s.datums[0].targets[1].point, Point3(3, 4, 0.5));
  EXPECT_EQ(s.datums[0].targets[1].direction, Vector3::Zero());
  EXPECT_EQ(s.datums[0].targets[2].label, "A3");
  EXPECT_EQ(s.datums[0].targets[2].direction, Vector3(0, 1, 0));  // made unit
  EXPECT_EQ(s.datums[0].targets[2].length, 3.0);
  EXPECT_EQ(s.datums[0].faces, std::vector<int>{0});
  EXPECT_EQ(s.datums[0].fit, DatumFit::Tangent);
  EXPECT_EQ(s.alignment, std::vector<std::string>{"A"});
  std::filesystem::remove(path);
}

// NIST FTC-06's PMI as characteristics: its 11 profiles of surface (with their datums) and 3 flatnesses (none); its
// 13 positions and perpendicularities are not characteristics of this step, and are counted.
TEST(Characteristics, FromPmiTakesTheProfilesAndFlatnesses) {
  const std::filesystem::path file = test::kCadDir / "nist_ftc_06_asme1_ap242-e2.stp";
  const cad::Model model = cad::read_model(file);
  int skipped = 0;
  const Specification s = from_pmi(cad::read_pmi(file, model), skipped);
  EXPECT_EQ(s.characteristics.size(), 14u);
  EXPECT_EQ(skipped, 13);
  int flatness = 0;
  for (const CharacteristicSpec& c : s.characteristics) {
    EXPECT_GT(c.tolerance, 0.0);
    EXPECT_FALSE(c.faces.empty());
    if (c.name.starts_with("flatness")) {
      ++flatness;
      EXPECT_TRUE(c.datums.empty());
      EXPECT_NEAR(c.tolerance, 0.254, 1e-9);
    } else {
      EXPECT_FALSE(c.datums.empty()) << c.name;
    }
  }
  EXPECT_EQ(flatness, 3);
}

}  // namespace
}  // namespace probecomp::inspection
