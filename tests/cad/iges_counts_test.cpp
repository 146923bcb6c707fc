// The IGES count check (cad/iges_counts.hpp) on small hand-made files, and on every IGES file we have. Each case
// states what OpenCASCADE 7.6's reader would have allocated: the check must see the counts as that reader does.

#include "probecomp/cad/iges_counts.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace probecomp::cad {
namespace {

struct EntityText {
  int type;          // in the directory entry: the type OpenCASCADE reads the entity as
  std::string text;  // the parameter data, starting with the type as the P section repeats it
  int form = 0;
};

std::string record(std::string data, std::size_t width, char section, int seq) {
  data.resize(width, ' ');
  const std::string s = std::to_string(seq);
  return data + section + std::string(7 - s.size(), ' ') + s + "\n";
}

std::string field(long long v) {
  const std::string s = std::to_string(v);
  return std::string(8 - s.size(), ' ') + s;
}

// A whole IGES file (S, G, D, P and T sections): `global` as the G section's text; entity k gets directory lines
// 2k + 1 and 2k + 2, and its parameter text split into lines of 64 columns pointing back to them.
std::string iges(const std::string& global, const std::vector<EntityText>& entities) {
  std::string s = record("", 72, 'S', 1), g, d, p;
  int gs = 0, ds = 0, ps = 0;
  for (std::size_t i = 0; i < global.size(); i += 72) g += record(global.substr(i, 72), 72, 'G', ++gs);
  for (const EntityText& e : entities) {
    const int de = ds + 1;
    const int first = ps + 1;
    for (std::size_t i = 0; i < e.text.size(); i += 64) {
      std::string line = e.text.substr(i, 64);
      line.resize(64, ' ');
      const std::string pointer = std::to_string(de);
      p += record(line + " " + std::string(7 - pointer.size(), ' ') + pointer, 72, 'P', ++ps);
    }
    d += record(field(e.type) + field(first) + field(0) + field(1) + field(0) + field(0) + field(0) + field(0) +
                    "00000000",
                72, 'D', ++ds);
    d += record(field(e.type) + field(0) + field(0) + field(ps - first + 1) + field(e.form) + std::string(32, ' '), 72,
                'D', ++ds);
  }
  std::string t;
  for (const auto& [letter, count] : {std::pair{'S', 1}, {'G', gs}, {'D', ds}, {'P', ps}}) {
    t += letter;
    t += field(count).substr(1);
  }
  return s + g + d + p + record(t, 72, 'T', 1);
}

std::optional<std::string> check(const std::string& text) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                     ("probecomp_iges_counts_" + std::to_string(::getpid()) + ".igs");
  {
    std::ofstream out(path, std::ios::binary);
    out << text;
  }
  std::optional<std::string> r = iges_count_beyond_data(path);
  std::filesystem::remove(path);
  return r;
}

const std::string kGlobal = "1H,,1H;,4HTEST;";

// A B-spline curve, K = 1, M = 1: 4 knots, 2 weights, 2 poles, the range and the plane's normal (23 parameters).
const std::string kCurveTail = ",1,0,0,1,0,0.,0.,1.,1.,1.,1.,0.,0.,0.,1.,0.,0.,0.,1.,0.,0.,1.;";
// A bilinear B-spline surface, K1 = K2 = M1 = M2 = 1: 4 + 4 knots, 4 weights, 4 poles, the range (37 parameters).
const std::string kSurfaceTail = ",0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,0.,0.,0.,1.,0.,0.,0.,1.,0.,1.,1.,0.,0.,1.,0.,1.;";

TEST(IgesCounts, CountsTheParameterDataHoldsPass) {
  EXPECT_FALSE(check(iges(kGlobal, {{126, "126,1" + kCurveTail}})));
  EXPECT_FALSE(check(iges(kGlobal, {{128, "128,1,1,1,1" + kSurfaceTail}})));
}

TEST(IgesCounts, ACountBeyondTheDataIsNamedWithItsEntityAndDirectoryLine) {
  // The curve declaring K = 5000: OpenCASCADE makes 5 001 poles for its 23 parameters.
  const std::optional<std::string> r = check(iges(kGlobal, {{124, "124,1.,0.,0.,0.,0.,1.,0.,0.,0.,0.,1.,0.;"},
                                                            {126, "126,5000" + kCurveTail}}));
  ASSERT_TRUE(r);
  EXPECT_EQ(*r, "IGES entity 126 (directory line 3) declares 5001 poles but its parameter data hold 23 values");
  // A surface whose poles alone would be 10⁸: what made OpenCASCADE take gigabytes (tests/data/fuzz/README.md).
  const std::optional<std::string> s = check(iges(kGlobal, {{124, "124,1.,0.,0.,0.,0.,1.,0.,0.,0.,0.,1.,0.;"},
                                                            {124, "124,1.,0.,0.,0.,0.,1.,0.,0.,0.,0.,1.,0.;"},
                                                            {124, "124,1.,0.,0.,0.,0.,1.,0.,0.,0.,0.,1.,0.;"},
                                                            {128, "128,9999,9999,1,1" + kSurfaceTail}}));
  ASSERT_TRUE(s);
  EXPECT_EQ(*s, "IGES entity 128 (directory line 7) declares 100000000 poles but its parameter data hold 37 values");
}

TEST(IgesCounts, TheTypeIsTheDirectoryEntrysAsOpenCascadeReadsIt) {
  // The parameter data say 126 but the directory entry says 128: OpenCASCADE reads a surface, 5001 × 2 poles.
  const std::optional<std::string> r = check(iges(kGlobal, {{128, "126,5000,1,1,1" + kSurfaceTail}}));
  ASSERT_TRUE(r);
  EXPECT_NE(r->find("IGES entity 128 (directory line 1) declares 10002 poles"), std::string::npos) << *r;
  // The other way round: a curve's count read as a surface's is not refused for a surface's rule it does not break.
  EXPECT_FALSE(check(iges(kGlobal, {{126, "128,1" + kCurveTail}})));
}

TEST(IgesCounts, ThePolesAreRefusedWhateverTheDegreesSay) {
  // OpenCASCADE sizes the poles by K (K1, K2) as soon as they read as integers, whatever follows: a degree that is
  // not an integer (or a Hollerith string) does not stop it.
  EXPECT_TRUE(check(iges(kGlobal, {{126, "126,5000,1.5,0,0,1,0,0.;"}})));
  EXPECT_TRUE(check(iges(kGlobal, {{126, "126,5000,2Hab,0,0,1,0,0.;"}})));
  EXPECT_TRUE(check(iges(kGlobal, {{128, "128,9999,9999,x,1" + kSurfaceTail}})));
}

TEST(IgesCounts, IntegersAreReadAsOpenCascadeReadsThem) {
  // A leading '+' is an integer to its lexer.
  EXPECT_TRUE(check(iges(kGlobal, {{126, "126,+5000" + kCurveTail}})));
  // An empty parameter reads as 0: one row of 100 000 poles.
  const std::optional<std::string> r = check(iges(kGlobal, {{128, "128,,99999,1,1" + kSurfaceTail}}));
  ASSERT_TRUE(r);
  EXPECT_NE(r->find("declares 100000 poles"), std::string::npos) << *r;
  // Negative extents multiply to a size all the same: (−2) × 100 000.
  EXPECT_TRUE(check(iges(kGlobal, {{128, "128,-3,99999,1,1" + kSurfaceTail}})));
  // A real is not an integer to ReadInteger: no array is made from it.
  EXPECT_FALSE(check(iges(kGlobal, {{126, "126,5000.0" + kCurveTail}})));
  // A negative K makes no poles in OpenCASCADE's curve reader (it reports the count): left to it.
  EXPECT_FALSE(check(iges(kGlobal, {{126, "126,-5000" + kCurveTail}})));
}

// An entity whose parameter data are `head` followed by `filler` parameters "0".
EntityText padded(int type, const std::string& head, int filler) {
  std::string text = std::to_string(type) + "," + head;
  for (int i = 0; i < filler; ++i) text += ",0";
  return {type, text + ";"};
}

TEST(IgesCounts, TheOtherEntitiesWhoseReadersSizeArraysByACount) {
  // Within the data: pass. Beyond: refused, naming the count.
  EXPECT_FALSE(check(iges(kGlobal, {padded(106, "1,10", 30)})));
  const std::optional<std::string> copious = check(iges(kGlobal, {padded(106, "1,100000", 30)}));
  ASSERT_TRUE(copious);
  EXPECT_NE(copious->find("IGES entity 106 (directory line 1) declares 100000 points but its parameter data hold 32 "
                          "values"),
            std::string::npos)
      << *copious;
  // A loop (IGESSolid_ToolLoop) with one edge whose K (the edge's fifth parameter) counts 100 000 curves.
  EXPECT_FALSE(check(iges(kGlobal, {padded(508, "1,0,1,1,1,2,0,1", 3)})));
  const std::optional<std::string> loop = check(iges(kGlobal, {padded(508, "1,0,1,1,1,100000,0,1", 3)}));
  ASSERT_TRUE(loop);
  EXPECT_NE(loop->find("declares 100000 curves"), std::string::npos) << *loop;
  // A parametric spline surface of 100 × 100 patches, each count within its 120 parameters but not their product.
  EXPECT_FALSE(check(iges(kGlobal, {padded(114, "3,1,10,10", 116)})));
  const std::optional<std::string> spline = check(iges(kGlobal, {padded(114, "3,1,100,100", 116)}));
  ASSERT_TRUE(spline);
  EXPECT_NE(spline->find("declares 10000 patches"), std::string::npos) << *spline;
  // A general symbol: its leader count NL comes after its NG geometry pointers (here 2), so the 99999s at the third
  // and fourth parameters are pointers, not counts.
  EXPECT_FALSE(check(iges(kGlobal, {padded(228, "1,2,99999,99999,3", 4)})));
  const std::optional<std::string> symbol = check(iges(kGlobal, {padded(228, "1,2,3,5,99999", 4)}));
  ASSERT_TRUE(symbol);
  EXPECT_NE(symbol->find("declares 99999 leaders"), std::string::npos) << *symbol;
  // Forms: an associativity of form 3 (views visible) counts views at its first parameter; no other form is read so.
  EntityText views = padded(402, "99999", 4);
  EXPECT_FALSE(check(iges(kGlobal, {views})));
  views.form = 3;
  const std::optional<std::string> visible = check(iges(kGlobal, {views}));
  ASSERT_TRUE(visible);
  EXPECT_NE(visible->find("IGES entity 402 (directory line 1) declares 99999 views"), std::string::npos) << *visible;
}

TEST(IgesCounts, StringsAndTheFilesOwnDelimitersAreRespected) {
  // A Hollerith string holding commas and semicolons is one parameter, across a line break too.
  const std::string name(70, ',');
  EXPECT_FALSE(check(iges(kGlobal, {{406, "406,2,70H" + name + ",1;"}})));
  // The curve with K = 5000 again, written with '/' and '#' as its delimiters (declared in the G section).
  std::string slashes = "126/5000" + kCurveTail;
  for (char& c : slashes) c = c == ',' ? '/' : c == ';' ? '#' : c;
  const std::optional<std::string> r = check(iges("1H/,1H#,4HTEST#", {{126, slashes}}));
  ASSERT_TRUE(r);
  EXPECT_NE(r->find("declares 5001 poles"), std::string::npos) << *r;
  // Defaulted delimiters (the G section starts with its own delimiter).
  EXPECT_TRUE(check(iges(",,4HTEST;", {{126, "126,5000,1,0,0,1,0,0.;"}})));
}

TEST(IgesCounts, AFileItsLexerCannotReadIsLeftToOpenCascade) {
  EXPECT_FALSE(check("not an IGES file\n"));
  EXPECT_FALSE(iges_count_beyond_data("/nonexistent/file.igs"));
}

TEST(IgesCounts, EveryIgesFileWeHavePasses) {
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(PROBECOMP_TEST_CAD_DIR)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".igs" && ext != ".iges") continue;
    const std::optional<std::string> r = iges_count_beyond_data(entry.path());
    EXPECT_FALSE(r) << entry.path() << ": " << r.value_or("");
    ++files;
  }
  EXPECT_EQ(files, 4);  // the IGES specification's two samples, the hammer and the impeller
}

}  // namespace
}  // namespace probecomp::cad
