// The NIST AP242 test parts' semantic PMI: tolerance counts by type and magnitudes as the files state them (the
// prototypes' figures, as OpenCASCADE's XDE reads them, and NIST's drawings: FTC-06's flatness 0.254 mm on single
// planes, its perpendicularities 0.3048 mm to A), the toleranced faces tied to the model's, and CTC-02's magnitudes,
// which OpenCASCADE 7.6 does not read, named instead of given as 0.

#include "probecomp/cad/pmi.hpp"

#include <gtest/gtest.h>

#include <map>

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
TEST(Pmi, MagnitudesOpenCascadeDoesNotReadAreNamedNotZero) {
  const Model model = read_model(kCadDir / "nist_ctc_02_asme1_ap242-e2.stp");
  const Pmi pmi = read_pmi(kCadDir / "nist_ctc_02_asme1_ap242-e2.stp", model);
  ASSERT_EQ(pmi.tolerances.size(), 22u);
  EXPECT_EQ(by_type(pmi)[ToleranceType::ProfileOfSurface], 13);
  for (const GeometricTolerance& t : pmi.tolerances) EXPECT_FALSE(t.value.has_value());
  ASSERT_EQ(pmi.warnings.size(), 22u);
  EXPECT_NE(pmi.warnings[0].find("magnitude was not read"), std::string::npos) << pmi.warnings[0];
  // Datum targets (A1, A2, A3) give their datum once, in the frame's order.
  for (const GeometricTolerance& t : pmi.tolerances) {
    for (std::size_t i = 0; i < t.datums.size(); ++i) {
      for (std::size_t j = i + 1; j < t.datums.size(); ++j) EXPECT_NE(t.datums[i], t.datums[j]);
    }
  }
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
