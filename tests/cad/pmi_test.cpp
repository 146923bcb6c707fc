// The NIST AP242 test parts' semantic PMI: tolerance counts by type and magnitudes as the files state them (the
// prototypes' figures, as OpenCASCADE's XDE reads them, and NIST's drawings: FTC-06's flatness 0.254 mm on single
// planes, its perpendicularities 0.3048 mm to A), the toleranced faces tied to the model's, and CTC-02's magnitudes,
// which OpenCASCADE 7.6 does not read, from the file's own text (or named, never given as 0).

#include "probecomp/cad/pmi.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>

#include "probecomp/cad/locator.hpp"
#include "support/data_files.hpp"
#include "support/light.hpp"

namespace probecomp::cad {
namespace {

using test::kCadDir;

std::map<ToleranceType, int> by_type(const Pmi& pmi) {
  std::map<ToleranceType, int> n;
  for (const GeometricTolerance& t : pmi.tolerances) ++n[t.type];
  return n;
}

TEST(Pmi, FtcSixHasItsTolerancesWithMagnitudesOnTheRightFaces) {
  const Model model = read_model(kCadDir / "nist_ftc_06_asme1_ap242-e2.stp");
  const Pmi pmi = read_pmi(kCadDir / "nist_ftc_06_asme1_ap242-e2.stp", model);
  ASSERT_EQ(pmi.tolerances.size(), 27u);
  const std::map<ToleranceType, int> n = by_type(pmi);
  EXPECT_EQ(n.at(ToleranceType::ProfileOfSurface), 11);
  EXPECT_EQ(n.at(ToleranceType::Position), 11);
  EXPECT_EQ(n.at(ToleranceType::Flatness), 3);
  EXPECT_EQ(n.at(ToleranceType::Perpendicularity), 2);
  EXPECT_TRUE(pmi.warnings.empty());
  for (const GeometricTolerance& t : pmi.tolerances) {
    ASSERT_TRUE(t.value.has_value());
    EXPECT_GT(*t.value, 0.1);
    EXPECT_LT(*t.value, 1.5);
    ASSERT_FALSE(t.faces.empty());
    for (int f : t.faces) ASSERT_LT(f, model.face_count());
    // A flatness is on one plane and has no datum; a perpendicularity is to A (first).
    if (t.type == ToleranceType::Flatness) {
      EXPECT_NEAR(*t.value, 0.254, 1e-9);  // 0.010 in
      ASSERT_EQ(t.faces.size(), 1u);
      EXPECT_EQ(model.faces[static_cast<std::size_t>(t.faces[0])].source_type, "plane");
      EXPECT_TRUE(t.datums.empty());
    }
    if (t.type == ToleranceType::Perpendicularity) {
      EXPECT_NEAR(*t.value, 0.3048, 1e-9);  // 0.012 in
      ASSERT_FALSE(t.datums.empty());
      EXPECT_EQ(t.datums[0], "A");
    }
  }
  // A position is on features of size: holes and bosses (cylinders, the cones and spheres of their ends), or a
  // slot or tab, a pair of planes; never a single plane or a free-form face.
  for (const GeometricTolerance& t : pmi.tolerances) {
    if (t.type != ToleranceType::Position) continue;
    for (int f : t.faces) {
      const std::string& type = model.faces[static_cast<std::size_t>(f)].source_type;
      EXPECT_TRUE(type == "cylinder" || type == "cone" || type == "sphere" || (type == "plane" && t.faces.size() >= 2))
          << "face " << f << ": " << type;
    }
  }
  for (const char* d : {"A", "B", "C", "D"}) EXPECT_NE(std::find(pmi.datums.begin(), pmi.datums.end(), d), pmi.datums.end()) << d;
  // Datums J and K are each two line targets, J1 and J2 on the two flanks of a V (planes whose normals are
  // (±0.906, 0.423, 0)), running up them along z: 1.25 in long, placed 0.65 in below the top, x = ±2.697 and ±3.803
  // in (the file's figures). Each line lies in its face.
  const ModelLocator on_face(model);
  for (const DatumFeature& d : pmi.datum_features) {
    if (d.name != "J" && d.name != "K") continue;
    SCOPED_TRACE(d.name);
    EXPECT_EQ(d.point_or_line_targets, 0);
    ASSERT_EQ(d.targets.size(), 2u);
    ASSERT_EQ(d.faces.size(), 2u);
    for (const DatumTarget& t : d.targets) {
      ASSERT_TRUE(t.line());
      EXPECT_NEAR(t.length, 31.75, 1e-9);
      EXPECT_NEAR(std::abs(t.direction.z()), 1.0, 1e-12);
      EXPECT_NEAR(t.point.z(), -16.51, 1e-9);
      EXPECT_NEAR(std::abs(t.point.x()), t.number == 1 ? 68.5038 : 96.5962, 1e-4);
      const Face& face = model.faces[static_cast<std::size_t>(t.face)];
      EXPECT_EQ(face.source_type, "plane");
      for (const double along : {-0.25, 0.25}) {
        const ModelPoint foot = on_face.closest_point(t.point + along * t.length * t.direction);
        EXPECT_EQ(foot.face, t.face);
        EXPECT_NEAR(foot.distance, 0.0, 1e-9);
      }
    }
  }
}

TEST(Pmi, EveryNistPartReadsItsTolerances) {
  struct Expected {
    const char* file;
    std::size_t tolerances, profiles;
  };
  for (const Expected& e : test::cases({Expected{"nist_stc_06_asme1_ap242-e3.stp", 25, 11}, Expected{"nist_ctc_04_asme1_ap242-e1.stp", 6, 3},
                                        Expected{"nist_stc_08_asme1_ap242-e3.stp", 29, 11}})) {
    SCOPED_TRACE(e.file);
    const Model model = read_model(kCadDir / e.file);
    const Pmi pmi = read_pmi(kCadDir / e.file, model);
    EXPECT_EQ(pmi.tolerances.size(), e.tolerances);
    EXPECT_EQ(static_cast<std::size_t>(by_type(pmi)[ToleranceType::ProfileOfSurface]), e.profiles);
    EXPECT_TRUE(pmi.warnings.empty());
    for (const GeometricTolerance& t : pmi.tolerances) EXPECT_TRUE(t.value.has_value());
  }
}

// CTC-02 stores its magnitudes in complex entities, which OpenCASCADE 7.6 reads as 0: every one is named as unread.
// CTC-02 stores every magnitude in a complex entity (LENGTH_MEASURE_WITH_UNIT() MEASURE_REPRESENTATION_ITEM()
// MEASURE_WITH_UNIT(LENGTH_MEASURE(v), #mm) ...), which OpenCASCADE 7.6 reads as 0: they come from the file's own
// text. The figures are the file's as read by hand: the flatness 0.05 mm; the 13 surface profiles 0.1, 0.5 (4 of them),
// 0.75, 0.8 (4) and 2.5 mm (3), the three of 2.5 mm unequally disposed with 0, 0.5 and 2.5 mm outside.
TEST(Pmi, MagnitudesInComplexEntitiesAreReadFromTheFilesOwnText) {
  const Model model = read_model(kCadDir / "nist_ctc_02_asme1_ap242-e2.stp");
  const Pmi pmi = read_pmi(kCadDir / "nist_ctc_02_asme1_ap242-e2.stp", model);
  ASSERT_EQ(pmi.tolerances.size(), 22u);
  EXPECT_EQ(by_type(pmi)[ToleranceType::ProfileOfSurface], 13);
  EXPECT_TRUE(pmi.warnings.empty()) << pmi.warnings.front();
  std::multiset<double> profiles, outside;
  for (const GeometricTolerance& t : pmi.tolerances) {
    ASSERT_TRUE(t.value.has_value()) << to_string(t.type);
    if (t.type == ToleranceType::Flatness) EXPECT_DOUBLE_EQ(*t.value, 0.05);
    if (t.type == ToleranceType::ProfileOfSurface) profiles.insert(*t.value);
    if (t.outside) {
      EXPECT_EQ(t.type, ToleranceType::ProfileOfSurface);
      EXPECT_DOUBLE_EQ(*t.value, 2.5);
      outside.insert(*t.outside);
    }
  }
  EXPECT_EQ(profiles, (std::multiset<double>{0.1, 0.5, 0.5, 0.5, 0.5, 0.75, 0.8, 0.8, 0.8, 0.8, 2.5, 2.5, 2.5}));
  EXPECT_EQ(outside, (std::multiset<double>{0.0, 0.5, 2.5}));
  // Datum targets (A1, A2, A3) give their datum once, in the frame's order.
  for (const GeometricTolerance& t : pmi.tolerances) {
    for (std::size_t i = 0; i < t.datums.size(); ++i) {
      for (std::size_t j = i + 1; j < t.datums.size(); ++j) EXPECT_NE(t.datums[i], t.datums[j]);
    }
  }
}

// The file's text read as written: CTC-02 with two magnitudes changed. Flatness.1's (#381) refers to a unit that is
// not in the file: that tolerance has none, and a warning names it (never a silent 0). Position.3's (#362, 0.05 mm)
// becomes 0.002 of an inch, a conversion-based unit of 25.4 mm: 0.0508 mm.
TEST(Pmi, MagnitudesAreReadInTheirUnitsOrNamedNotZero) {
  std::ifstream in(kCadDir / "nist_ctc_02_asme1_ap242-e2.stp", std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto replace = [&](const std::string& instance, const std::string& from, const std::string& to) {
    const std::size_t at = text.find(instance);
    ASSERT_NE(at, std::string::npos) << instance;
    const std::size_t where = text.find(from, at);
    ASSERT_NE(where, std::string::npos) << from;
    text.replace(where, from.size(), to);
  };
  replace("#381=(", "LENGTH_MEASURE(0.05),#22285)", "LENGTH_MEASURE(0.05),#999999)");
  replace("#362=(", "LENGTH_MEASURE(0.05),#22285)", "LENGTH_MEASURE(0.002),#999990)");
  const std::size_t end = text.rfind("ENDSEC;");
  ASSERT_NE(end, std::string::npos);
  text.insert(end, "#999990=(CONVERSION_BASED_UNIT('INCH',#999991) LENGTH_UNIT() NAMED_UNIT(*));\n"
                   "#999991=LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#22285);\n");
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "probecomp_pmi_unit_test.stp";
  std::ofstream(path, std::ios::binary) << text;
  const Model model = read_model(path);
  const Pmi pmi = read_pmi(path, model);
  std::filesystem::remove(path);
  ASSERT_EQ(pmi.tolerances.size(), 22u);
  ASSERT_EQ(pmi.warnings.size(), 1u);
  EXPECT_NE(pmi.warnings[0].find("(flatness, "), std::string::npos) << pmi.warnings[0];
  EXPECT_NE(pmi.warnings[0].find("its magnitude was not read"), std::string::npos) << pmi.warnings[0];
  std::multiset<double> positions;
  for (const GeometricTolerance& t : pmi.tolerances) {
    EXPECT_EQ(t.value.has_value(), t.type != ToleranceType::Flatness);
    if (t.type == ToleranceType::Position) positions.insert(*t.value);
  }
  EXPECT_EQ(positions.size(), 4u);
  EXPECT_NEAR(*positions.begin(), 0.0508, 1e-12);
  EXPECT_EQ(*std::next(positions.begin()), 0.15);
}

TEST(Pmi, IgesAndStepWithoutPmiHaveNone) {
  const Model hammer = read_model(kCadDir / "gismo_hammer.iges");
  EXPECT_TRUE(read_pmi(kCadDir / "gismo_hammer.iges", hammer).tolerances.empty());
  const Model cube = read_model(kCadDir / "asitus_wavy-cube.stp");
  const Pmi none = read_pmi(kCadDir / "asitus_wavy-cube.stp", cube);
  EXPECT_TRUE(none.tolerances.empty());
  EXPECT_TRUE(none.warnings.empty());
}

}  // namespace
}  // namespace probecomp::cad
