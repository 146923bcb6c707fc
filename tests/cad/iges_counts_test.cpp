// The IGES count check (cad/iges_counts.hpp) on small hand-made parameter sections, and on every IGES file we have.

#include "probecomp/cad/iges_counts.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace probecomp::cad {
namespace {

// An IGES file's G and P sections (S, D and T do not matter to the check): `global` as the G section's text, each
// entity's parameter text split into lines of 64 columns with its directory line in columns 66–72.
std::string iges(const std::string& global, const std::vector<std::pair<int, std::string>>& entities) {
  auto record = [](const std::string& data, char section, int seq, int de = -1) {
    std::string line = data;
    line.resize(64, ' ');
    line += ' ';
    std::string pointer = de < 0 ? "" : std::to_string(de);
    line += std::string(7 - pointer.size(), ' ') + pointer;
    line += section;
    const std::string s = std::to_string(seq);
    return line + std::string(7 - s.size(), ' ') + s + "\n";
  };
  std::string out = record("", 'S', 1);
  for (std::size_t i = 0, seq = 1; i < global.size(); i += 72, ++seq) {
    std::string line = global.substr(i, 72);
    line.resize(72, ' ');
    out += line + "G" + std::string(7 - std::to_string(seq).size(), ' ') + std::to_string(seq) + "\n";
  }
  int seq = 1;
  for (const auto& [de, text] : entities) {
    for (std::size_t i = 0; i < text.size(); i += 64) out += record(text.substr(i, 64), 'P', seq++, de);
  }
  return out;
}

std::optional<std::string> check(const std::string& text) {
  std::istringstream in(text);
  return iges_count_beyond_data(in);
}

const std::string kGlobal = "1H,,1H;,4HTEST;";

TEST(IgesCounts, CountsTheParameterDataHoldsPass) {
  // A B-spline curve, K = 1, M = 1: 4 knots, 2 weights, 2 poles, the range and the plane's normal.
  EXPECT_FALSE(check(iges(kGlobal, {{1, "126,1,1,0,0,1,0,0.,0.,1.,1.,1.,1.,0.,0.,0.,1.,0.,0.,0.,1.,0.,0.,1.;"}})));
  // A bilinear B-spline surface (K1 = K2 = 1, M1 = M2 = 1): 4 + 4 knots, 4 weights, 4 poles, the range.
  EXPECT_FALSE(check(iges(kGlobal, {{3, "128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,0.,0.,0.,1.,0.,0.,"
                                          "0.,1.,0.,1.,1.,0.,0.,1.,0.,1.;"}})));
}

TEST(IgesCounts, ACountBeyondTheDataIsNamedWithItsEntityAndDirectoryLine) {
  // The same curve declaring K = 5000: 5 003 knots in 23 parameters.
  const std::optional<std::string> r =
      check(iges(kGlobal, {{1, "124,1.,0.,0.,0.,0.,1.,0.,0.,0.,0.,1.,0.;"},
                           {3, "126,5000,1,0,0,1,0,0.,0.,1.,1.,1.,1.,0.,0.,0.,1.,0.,0.,0.,1.,0.,0.,1.;"}}));
  ASSERT_TRUE(r);
  EXPECT_EQ(*r, "IGES entity 126 (directory line 3) declares 5003 knots but its parameter data hold 23 values");
  // A surface whose poles alone would be 10⁸: what made OpenCASCADE take gigabytes (tests/data/fuzz/README.md).
  const std::optional<std::string> s = check(iges(kGlobal, {{7, "128,9999,9999,1,1,0,0,1,0,0,0.,0.,1.,1.;"}}));
  ASSERT_TRUE(s);
  EXPECT_NE(s->find("entity 128 (directory line 7) declares 100000000 poles"), std::string::npos) << *s;
  // Copious data, composite curve, parametric spline curve and surface.
  EXPECT_TRUE(check(iges(kGlobal, {{1, "106,1,400,0.,0.,0.;"}})));
  EXPECT_TRUE(check(iges(kGlobal, {{1, "102,4,5,7;"}})));
  EXPECT_TRUE(check(iges(kGlobal, {{1, "112,3,2,3,50,0.,1.;"}})));
  EXPECT_TRUE(check(iges(kGlobal, {{1, "114,3,1,40,40,0.,1.;"}})));
  EXPECT_TRUE(check(iges(kGlobal, {{1, "406,4,1.,2.;"}})));
  // A negative count is OpenCASCADE's to refuse (its arrays check their bounds): not ours.
  EXPECT_FALSE(check(iges(kGlobal, {{1, "126,-5,1,0,0,1,0,0.,1.;"}})));
}

TEST(IgesCounts, StringsAndTheFilesOwnDelimitersAreRespected) {
  // A Hollerith string holding commas and semicolons is one parameter, across a line break too.
  const std::string name(70, ',');
  EXPECT_FALSE(check(iges(kGlobal, {{1, "406,2,70H" + name + ",1;"}})));
  // The curve with K = 5000 again, written with '/' and '#' as its delimiters (declared in the G section).
  const std::optional<std::string> r = check(
      iges("1H/,1H#,4HTEST#", {{1, "126/5000/1/0/0/1/0/0./0./1./1./1./1./0./0./0./1./0./0./0./1./0./0./1.#"}}));
  ASSERT_TRUE(r);
  EXPECT_NE(r->find("declares 5003 knots"), std::string::npos) << *r;
  // Defaulted delimiters (the G section starts with its own delimiter).
  EXPECT_TRUE(check(iges(",,4HTEST;", {{1, "126,5000,1,0,0,1,0,0.;"}})));
}

TEST(IgesCounts, ParameterLinesWithoutADirectoryPointerAreReadAsOneEntity) {
  // Was a read of an entity not yet made (UndefinedBehaviorSanitizer, fuzz_cad_iges): the first parameter line's
  // pointer columns blank.
  std::string text = iges(kGlobal, {{1, "126,5000,1,0,0,1,0,0.;"}});
  const std::size_t p = text.find("126,");
  text.replace(p + 65, 7, "       ");
  EXPECT_TRUE(check(text));
}

TEST(IgesCounts, EveryIgesFileWeHavePasses) {
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(PROBECOMP_TEST_CAD_DIR)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".igs" && ext != ".iges") continue;
    std::ifstream in(entry.path(), std::ios::binary);
    const std::optional<std::string> r = iges_count_beyond_data(in);
    EXPECT_FALSE(r) << entry.path() << ": " << r.value_or("");
    ++files;
  }
  EXPECT_EQ(files, 4);  // the IGES specification's two samples, the hammer and the impeller
}

}  // namespace
}  // namespace probecomp::cad
