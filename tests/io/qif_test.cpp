// QIF 3.0 point files (issue 21): the real sample against numbers typed from it, exact round trips through QIF,
// the compensated document's layout, and the errors that name the file, the line and the set.
// (Every document written is validated against the QIF 3.0 schemas by tests/cli/qif.sh, with xmllint.)

#include "probecomp/io/qif.hpp"

#include <gtest/gtest.h>
#include <pugixml.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>

#include "probecomp/error.hpp"
#include "probecomp/io/dmis.hpp"
#include "probecomp/io/text.hpp"
#include "probecomp/results/files.hpp"

namespace probecomp::io {
namespace {

namespace fs = std::filesystem;

const fs::path kSample = fs::path(PROBECOMP_TEST_CAD_DIR) / "qif_QIF_PTS_SAMPLE.QIF";

fs::path write(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / ("probecomp_qif_" + name);
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// The sample with one line replaced (1-based), written to a file of its own.
fs::path sample_with(int line, const std::string& from, const std::string& to, const std::string& name) {
  std::ifstream in(kSample, std::ios::binary);
  std::string text, l;
  for (int n = 1; std::getline(in, l); ++n) {
    if (n == line) {
      const auto at = l.find(from);
      EXPECT_NE(at, std::string::npos) << "line " << line << " has no '" << from << "'";
      if (at != std::string::npos) l.replace(at, from.size(), to);
    }
    text += l + '\n';
  }
  return write(name, text);
}

// Every value of two tables equal (==): points, normals, radii (NaN in the same places), the numbers of the named
// `numbers` columns as written (i, j, k before normalising, say) and the text of the `columns`.
void expect_same_values(const PointTable& a, const PointTable& b, const std::vector<std::string>& columns,
                        const std::vector<std::string>& numbers = {}) {
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_TRUE(a.unit == b.unit);
  ASSERT_EQ(a.normals.has_value(), b.normals.has_value());
  ASSERT_EQ(a.radii.has_value(), b.radii.has_value());
  for (std::size_t k = 0; k < a.points.size(); ++k) {
    EXPECT_EQ(a.points[k], b.points[k]) << "row " << k;
    if (a.normals) {
      EXPECT_EQ((*a.normals)[k], (*b.normals)[k]) << "row " << k;
    }
    if (a.radii) {
      const double ra = (*a.radii)[k], rb = (*b.radii)[k];
      EXPECT_TRUE(ra == rb || (std::isnan(ra) && std::isnan(rb))) << "row " << k << ": " << ra << " vs " << rb;
    }
    for (const std::string& c : numbers) {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      const double va = row_value(a, column_index(a, c), k, nan), vb = row_value(b, column_index(b, c), k, nan);
      EXPECT_TRUE(va == vb || (std::isnan(va) && std::isnan(vb))) << c << ", row " << k << ": " << va << " vs " << vb;
    }
    for (const std::string& c : columns) {
      const int ca = column_index(a, c), cb = column_index(b, c);
      ASSERT_GE(ca, 0) << c;
      ASSERT_GE(cb, 0) << c;
      EXPECT_EQ(a.rows[k][static_cast<std::size_t>(ca)], b.rows[k][static_cast<std::size_t>(cb)]) << c << ", row " << k;
    }
  }
}

TEST(Qif, TheRealSampleReadsExactly) {
  const PointTable t = read_point_qif(kSample);
  ASSERT_EQ(t.points.size(), 691u);
  EXPECT_EQ(t.columns, (std::vector<std::string>{"x", "y", "z", "r", "set"}));
  EXPECT_TRUE(t.unit == kMillimetre);
  EXPECT_FALSE(t.normals.has_value());
  ASSERT_TRUE(t.radii.has_value());
  for (std::size_t k = 0; k < t.points.size(); ++k) {
    ASSERT_EQ((*t.radii)[k], 2.49978271104) << k;
    ASSERT_EQ(t.rows[k][3], "2.49978271104") << k;
  }
  // The sets' ids and counts, in document order.
  std::vector<std::pair<std::string, int>> sets;
  for (const auto& row : t.rows) {
    if (sets.empty() || sets.back().first != row[4]) sets.emplace_back(row[4], 0);
    ++sets.back().second;
  }
  EXPECT_EQ(sets, (std::vector<std::pair<std::string, int>>{{"29", 219}, {"262", 219}, {"510", 219}, {"797", 18},
                                                             {"12", 8}, {"256", 2}, {"757", 1}, {"767", 1},
                                                             {"777", 1}, {"787", 1}, {"829", 1}, {"834", 1}}));
  // First and last points of several sets, as typed from the file.
  EXPECT_EQ(t.points[0], Point3(3.54516458565, 0.0037440421, -1.82916012241));
  EXPECT_EQ(t.points[218], Point3(3.54406294492, -0.07350448483, -1.8194095497));
  EXPECT_EQ(t.points[219], Point3(-29.65156295289, -4.35146716339, -1.30554312075));
  EXPECT_EQ(t.points[437], Point3(-29.65385677214, -4.42320260897, -1.32261141214));
  EXPECT_EQ(t.points[438], Point3(-29.6082220648, 43.05470395336, -1.65356383054));
  EXPECT_EQ(t.points[656], Point3(-29.61199184928, 43.00912325637, -1.67876406339));
  EXPECT_EQ(t.points[657], Point3(-10.68167127504, 10.64337662543, -4.49374276264));
  EXPECT_EQ(t.points[674], Point3(-25.54677278185, 8.64276466747, -2.48298055198));
  EXPECT_EQ(t.points[675], Point3(-43.73170020597, 49.51823501394, 2.50038872433));
  EXPECT_EQ(t.points[682], Point3(15.30780835101, 12.62061692428, 2.50055258359));
  EXPECT_EQ(t.points[683], Point3(22.953045849941, -7.907186804579, -3.061917904289));
  EXPECT_EQ(t.points[684], Point3(22.953045849941, 38.70507400996, -4.026441689361));
  EXPECT_EQ(t.points[690], Point3(-8.780180022677, 67.820797479257, -3.009861578624));
  EXPECT_EQ(t.rows[690][0], "-8.780180022677");  // the number as the file writes it
  EXPECT_EQ(t.line[0], 1113);                    // the line of its set's Points
  EXPECT_EQ(t.line[690], 1179);
}

TEST(Qif, TheSampleAsCsvHoldsEveryRowExactly) {
  const PointTable t = read_point_qif(kSample);
  const fs::path csv = write("sample.csv", points_csv(t));
  const PointTable back = read_point_csv(csv);
  EXPECT_EQ(back.columns, (std::vector<std::string>{"x", "y", "z", "r", "set"}));
  expect_same_values(t, back, {"set"});
}

TEST(Qif, CsvThroughQifAndBackIsExact) {
  const fs::path csv = write("rt.csv",
                             "x,y,z,i,j,k,r,id,note\n"
                             "0.1,-123.456789012345678,1e-7,0,0,2,0.5,7,\"a, b\"\n"
                             "3.14159265358979,2.718281828459045,-0,0.6,0.8,0,,8,\n"
                             "1e300,-1e-300,12345678901234567890,1,1,1,1.25,9,\"say \"\"hi\"\"\"\n");
  const PointTable a = read_point_csv(csv);
  const fs::path qif = write("rt.qif", points_qif(a));
  const PointTable b = read_point_qif(qif);
  expect_same_values(a, b, {"id", "note"}, {"x", "y", "z", "i", "j", "k", "r"});
  // And on to CSV: the same file but for the set column QIF adds.
  const PointTable c = read_point_csv(write("rt2.csv", points_csv(b)));
  expect_same_values(a, c, {"id", "note"}, {"x", "y", "z", "i", "j", "k", "r"});
  EXPECT_EQ(c.columns, (std::vector<std::string>{"x", "y", "z", "i", "j", "k", "r", "set", "id", "note"}));
}

TEST(Qif, InchesStayInchesThroughQif) {
  const fs::path csv = write("inch.csv", "x,y,z,r\n1,-0.1,0.005,0.0393700787401575\n2.5,3,4,0.02\n");
  const PointTable a = read_point_csv(csv, kInch);
  const std::string doc = points_qif(a);
  EXPECT_NE(doc.find("<UnitName>inch</UnitName>"), std::string::npos);
  EXPECT_NE(doc.find("<Factor>0.0254</Factor>"), std::string::npos);
  const PointTable b = read_point_qif(write("inch.qif", doc));
  EXPECT_TRUE(b.unit == kInch);
  expect_same_values(a, b, {"x", "y", "z", "r"}, {"x", "y", "z", "r"});  // the file's text, here the shortest
  const std::string text = points_csv(b);
  EXPECT_TRUE(text.starts_with("# lengths in inch\nx,y,z,r,set\n1,-0.1,0.005,0.0393700787401575,1\n")) << text;
  // The CSV says its unit: read back without --units, in inches; --units mm against it is an error naming the line.
  const fs::path back = write("inch2.csv", text);
  expect_same_values(a, read_point_csv(back), {"x", "y", "z", "r"});
  EXPECT_NE(error_of([&] { (void)read_point_csv(back, kMillimetre); })
                .find("inch2.csv:1: the file says its lengths are in inch, not in mm"),
            std::string::npos);
  EXPECT_NE(error_of([&] { (void)read_point_qif(write("inch.qif", doc), kMillimetre); })
                .find("the file says its lengths are in inch, not in mm"),
            std::string::npos);
}

TEST(Qif, DmisWithTwoTipsThroughQifAndBackIsExact) {
  const fs::path dmo = write("tips.dmo",
                             "UNITS/MM,ANGDEC\n"
                             "S(BIG)=SNSDEF/PROBE,INDEX,POL,0,90,0,0,1,150,2\n"
                             "S(SMALL)=SNSDEF/PROBE,INDEX,POL,90,0,0,0,1,120,0.7\n"
                             "SNSLCT/S(BIG)\n"
                             "FA(A1)=FEAT/POINT,CART,10.125,-3.3,0.1,0,0,1\n"
                             "FA(A2)=FEAT/POINT,CART,11.5,-3.3,0.2,0,0,1\n"
                             "SNSLCT/S(SMALL)\n"
                             "FA(B1)=FEAT/POINT,CART,1e-3,2.000000000001,3,0.6,0,0.8\n"
                             "SNSLCT/S(BIG)\n"
                             "FA(A3)=FEAT/POINT,CART,7,8,9,1,0,0\n");
  const PointTable a = read_point_dmis(dmo);
  const PointTable b = read_point_qif(write("tips.qif", points_qif(a)));
  expect_same_values(a, b, {"label", "tip"}, {"x", "y", "z", "i", "j", "k", "r"});
  const std::string text = points_dmis(b, "tips.qif");
  const PointTable c = read_point_dmis(write("tips2.dmo", text));
  expect_same_values(a, c, {"label", "tip"}, {"x", "y", "z", "i", "j", "k", "r"});
  // Through QIF the probes' orientations are lost: each tip is defined anew with its diameter, and said so.
  EXPECT_NE(text.find("S(BIG)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,0,2\n"), std::string::npos) << text;
  EXPECT_NE(text.find("S(SMALL)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,0,0.7\n"), std::string::npos) << text;
  EXPECT_NE(text.find("$$ S(BIG): the ball's diameter as measured with"), std::string::npos) << text;
  // Straight from DMIS to DMIS they are kept as written.
  const std::string direct = points_dmis(a, "tips.dmo");
  EXPECT_NE(direct.find("S(BIG)=SNSDEF/PROBE,INDEX,POL,0,90,0,0,1,150,2\nS(SMALL)=SNSDEF/PROBE,INDEX,POL,90,0,0,0,1,120,0.7\n"
                        "SNSLCT/S(BIG)\nFA(A1)"),
            std::string::npos)
      << direct;
}

TEST(Qif, SetValuesThatAreNotIdsAreKeptAsAColumn) {
  const PointTable a = read_point_csv(write("sets.csv", "x,y,z,set\n1,2,3,A\n4,5,6,A\n7,8,9,B\n1,1,1,A\n"));
  const std::string doc = points_qif(a);
  EXPECT_NE(doc.find("MeasuredPointSets n=\"3\""), std::string::npos) << doc;  // three runs
  const PointTable b = read_point_qif(write("sets.qif", doc));
  expect_same_values(a, b, {"set"});
  // Ids that are ids are kept as ids.
  const PointTable c = read_point_csv(write("ids.csv", "x,y,z,set\n1,2,3,40\n4,5,6,40\n7,8,9,12\n"));
  const std::string ids = points_qif(c);
  EXPECT_NE(ids.find("<MeasuredPointSet count=\"2\" id=\"40\">"), std::string::npos) << ids;
  EXPECT_NE(ids.find("<MeasuredPointSet count=\"1\" id=\"12\">"), std::string::npos) << ids;
  EXPECT_EQ(ids.find("probecomp:column:set"), std::string::npos);
}

// A QIF document around one MeasuredPointSet's inside, for the reader's checks.
std::string one_set(const std::string& inside, const std::string& count = "2", const std::string& units = "") {
  return "<?xml version=\"1.0\"?>\n<QIFDocument xmlns=\"http://qifstandards.org/xsd/qif3\" idMax=\"9\" versionQIF=\"3.0.0\">\n" +
         units + "<Results><MeasurementResultsSet n=\"1\"><MeasurementResults id=\"1\">\n<MeasuredPointSets n=\"1\">\n"
         "<MeasuredPointSet count=\"" + count + "\" id=\"5\">\n" + inside +
         "</MeasuredPointSet></MeasuredPointSets>\n</MeasurementResults></MeasurementResultsSet></Results></QIFDocument>\n";
}

TEST(Qif, UnitsByNameOrFactorAndPerPointRadiiAndNormals) {
  const std::string inch = "<FileUnits><PrimaryUnits><LinearUnit><UnitName>in</UnitName></LinearUnit></PrimaryUnits></FileUnits>\n";
  const PointTable t = read_point_qif(write("u1.qif", one_set("<Points>1 2 3 +4 5E0 -6</Points>\n<Normals>0 0 2 0 1 0</Normals>\n"
                                                               "<Compensations>false 0</Compensations>\n"
                                                               "<ProbeRadii>0.02 NaN</ProbeRadii>\n",
                                                               "2", inch)));
  EXPECT_TRUE(t.unit == kInch);
  EXPECT_EQ(t.columns, (std::vector<std::string>{"x", "y", "z", "i", "j", "k", "r", "set"}));
  EXPECT_EQ(t.points[1], Point3(4 * 25.4, 5 * 25.4, -6 * 25.4));
  EXPECT_EQ(t.rows[1][0], "4");  // '+4' is an xs:double; the row keeps a number every reader takes
  EXPECT_EQ((*t.normals)[0], Vector3(0, 0, 1));
  EXPECT_EQ((*t.radii)[0], 0.02 * 25.4);
  EXPECT_TRUE(std::isnan((*t.radii)[1]));  // NaN: the run's default radius
  EXPECT_EQ(t.rows[1][6], "");
  const std::string by_factor =
      "<FileUnits><PrimaryUnits><LinearUnit><UnitName>pouce</UnitName><UnitConversion><Factor>0.025400</Factor>"
      "</UnitConversion></LinearUnit></PrimaryUnits></FileUnits>\n";
  EXPECT_TRUE(read_point_qif(write("u2.qif", one_set("<Points>1 2 3</Points><Compensated>false</Compensated>", "1",
                                                     by_factor)))
                  .unit == kInch);
  const std::string unknown = "<FileUnits><PrimaryUnits><LinearUnit><UnitName>furlong</UnitName></LinearUnit></PrimaryUnits></FileUnits>\n";
  EXPECT_NE(error_of([&] {
              (void)read_point_qif(write("u3.qif", one_set("<Points>1 2 3</Points><Compensated>false</Compensated>", "1", unknown)));
            }).find("u3.qif:3: LinearUnit 'furlong' is not a length unit probecomp reads"),
            std::string::npos);
}

TEST(Qif, ErrorsNameTheFileTheLineAndTheSet) {
  const auto error = [](const fs::path& p) { return error_of([&] { (void)read_point_qif(p); }); };
  EXPECT_NE(error(sample_with(1111, "count=\"219\"", "count=\"220\"", "count.qif"))
                .find("count.qif:1113: MeasuredPointSet id=29: count is 220 but Points holds 219 points"),
            std::string::npos);
  EXPECT_NE(error(sample_with(1114, "false", "true", "compensated.qif"))
                .find("compensated.qif:1114: MeasuredPointSet id=29: the points are compensated already"),
            std::string::npos);
  EXPECT_NE(error(sample_with(1119, "-29.65156295289", "-29.65x", "token.qif"))
                .find("token.qif:1119: MeasuredPointSet id=262: Points: '-29.65x' (number 1) is not a number"),
            std::string::npos);
  EXPECT_NE(error(sample_with(1115, "2.49978271104", "0", "radius.qif"))
                .find("radius.qif:1115: MeasuredPointSet id=29: a tip radius must be positive, not 0"),
            std::string::npos);
  EXPECT_NE(error(write("binary.qif", one_set("<BinaryPoints count=\"6\" sizeElement=\"8\">AAAA</BinaryPoints>\n"
                                              "<Compensated>false</Compensated>\n")))
                .find("binary.qif:6: MeasuredPointSet id=5: binary lists (BinaryPoints) are not read"),
            std::string::npos);
  EXPECT_NE(error(write("notxml.qif", "x,y,z\n1,2,3\n")).find("notxml.qif:2: not XML"), std::string::npos);
  EXPECT_NE(error(write("unclosed.qif", "<QIFDocument>\n<Results>\n</QIFDocument>\n")).find("unclosed.qif:3: not XML"),
            std::string::npos);
  EXPECT_NE(error(write("other.qif", "<?xml version=\"1.0\"?>\n<html/>\n")).find("other.qif:2: not a QIF document"),
            std::string::npos);
  EXPECT_NE(error(write("none.qif", "<QIFDocument/>")).find("none.qif: no MeasuredPointSet"), std::string::npos);
  EXPECT_NE(error(write("nopoints.qif", one_set("<Compensated>false</Compensated>\n"))).find("nopoints.qif:5: MeasuredPointSet id=5: no Points"),
            std::string::npos);
  EXPECT_NE(error(write("flags.qif", one_set("<Points>1 2 3 4 5 6</Points>\n<Compensations>false true</Compensations>\n")))
                .find("flags.qif:7: MeasuredPointSet id=5: point 2 is compensated already"),
            std::string::npos);
  EXPECT_NE(error(write("zero.qif", one_set("<Points>1 2 3 4 5 6</Points>\n<Normals>0 0 1 0 0 0</Normals>\n"
                                            "<Compensated>false</Compensated>\n")))
                .find("zero.qif:7: MeasuredPointSet id=5: the normal of point 2 is zero"),
            std::string::npos);
  EXPECT_NE(error(write("radii.qif", one_set("<Points>1 2 3 4 5 6</Points>\n<Compensated>false</Compensated>\n"
                                             "<ProbeRadii>1</ProbeRadii>\n")))
                .find("radii.qif:8: MeasuredPointSet id=5: count is 2 but ProbeRadii holds 1 number"),
            std::string::npos);
  EXPECT_NE(error(write("inf.qif", one_set("<Points>1 2 INF 4 5 6</Points>\n<Compensated>false</Compensated>\n")))
                .find("inf.qif:6: MeasuredPointSet id=5: Points: number 3 ('INF') is not finite"),
            std::string::npos);
}

// A result of three points, the second not computed, for the compensated document.
compensation::CompensationResult three_points() {
  compensation::CompensationResult r;
  r.method = compensation::Method::Cad;
  for (int k = 0; k < 3; ++k) {
    compensation::CompensatedPoint p;
    p.status = k == 1 ? compensation::PointStatus::NotOnModel : compensation::PointStatus::Ok;
    p.contact = Point3(k, 0.5, -0.25);
    p.normal = Vector3(0, 0, 1);
    p.deviation = 0.125;
    p.uncertainty = 0.0625;
    p.face = k == 1 ? -1 : 3;
    p.radius = k == 2 ? 0.25 : 0.5;
    r.points.push_back(p);
  }
  return r;
}

TEST(Qif, CompensatedDocumentHoldsEverySetPointAndStatus) {
  const PointTable input = read_point_csv(write("in.csv", "x,y,z,i,j,k,set,id\n0,0,1,0,0,1,7,a\n9,9,9,0,0,1,7,b\n2,0,1,0,0,1,8,c\n"));
  const std::string doc = results::compensated_qif(input, three_points(), "in.csv");
  pugi::xml_document x;
  ASSERT_TRUE(x.load_string(doc.c_str()));
  const pugi::xml_node sets = x.child("QIFDocument").child("Results").child("MeasurementResultsSet")
                                  .child("MeasurementResults").child("MeasuredPointSets");
  EXPECT_EQ(std::string(sets.attribute("n").value()), "2");
  const pugi::xml_node first = sets.first_child(), second = first.next_sibling();
  EXPECT_EQ(std::string(first.attribute("id").value()), "7");
  EXPECT_EQ(std::string(first.attribute("count").value()), "2");
  EXPECT_EQ(std::string(first.child("Points").text().get()), "0 0.5 -0.25 9 9 9");  // the raw centre kept
  EXPECT_EQ(std::string(first.child("Normals").text().get()), "0 0 1 NaN NaN NaN");
  EXPECT_EQ(std::string(first.child("Compensations").text().get()), "true false");
  EXPECT_EQ(std::string(first.child("ProbeRadius").text().get()), "0.5");
  EXPECT_EQ(std::string(first.child("Deviations").text().get()), "0.125 NaN");
  const pugi::xml_node attributes = first.child("Attributes");
  EXPECT_EQ(std::string(attributes.find_child_by_attribute("name", "probecomp:status").attribute("value").value()),
            "ok not-on-model");
  EXPECT_EQ(std::string(attributes.find_child_by_attribute("name", "probecomp:u").attribute("value").value()), "0.0625 NaN");
  EXPECT_EQ(std::string(attributes.find_child_by_attribute("name", "probecomp:face").attribute("value").value()), "3 -1");
  EXPECT_EQ(std::string(attributes.find_child_by_attribute("name", "probecomp:column:id").attribute("value").value()), "a,b");
  EXPECT_EQ(std::string(second.attribute("id").value()), "8");
  EXPECT_EQ(std::string(second.child("Compensated").text().get()), "true");
  EXPECT_EQ(std::string(second.child("ProbeRadius").text().get()), "0.25");
  EXPECT_TRUE(doc.find("probecomp:source\" value=\"in.csv\"") != std::string::npos);
  // The same input gives the same document, byte for byte (its QPId too).
  EXPECT_EQ(doc, results::compensated_qif(input, three_points(), "in.csv"));
  // A compensated document is not read as probe centres.
  EXPECT_NE(error_of([&] { (void)read_point_qif(write("out.qif", doc)); }).find("point 1 is compensated already"),
            std::string::npos);
}

// Every kind of document probecomp writes validates against the QIF 3.0 schemas (xmllint, from libxml2-utils: a
// machine without it fails here rather than skip the check): raw points of every source, with per-point radii,
// NaN radii, inches and carried columns, and a compensated one with points not computed (Compensations, NaN).
TEST(Qif, EveryDocumentWrittenValidatesAgainstTheQif3Schemas) {
  ASSERT_EQ(std::system("xmllint --version >/dev/null 2>&1"), 0) << "xmllint is missing (Debian libxml2-utils)";
  const PointTable csv = read_point_csv(write("v.csv",
                                              "x,y,z,i,j,k,r,set,note\n1,2,3,0,0,1,0.5,4,\"<&>\"\n4,5,6,0,1,0,,4,x\n"
                                              "7,8,9,1,0,0,1,A,\"a, b\"\n"));
  const PointTable inch = read_point_csv(write("v_inch.csv", "x,y,z\n1,2,3\n"), kInch);
  const PointTable dmis = read_point_dmis(write("v.dmo", "S(A)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,6,2\nSNSLCT/S(A)\n"
                                                         "FA(P1)=FEAT/POINT,CART,1,2,3\nFA(P2)=FEAT/POINT,CART,1e-9,2,3\n"));
  const PointTable three = read_point_csv(write("v3.csv", "x,y,z,i,j,k,set,id\n0,0,1,0,0,1,7,a\n9,9,9,0,0,1,7,b\n2,0,1,0,0,1,8,c\n"));
  const std::vector<std::pair<std::string, std::string>> documents{
      {"v_sample.qif", points_qif(read_point_qif(kSample))}, {"v_csv.qif", points_qif(csv)},
      {"v_inch.qif", points_qif(inch)},                      {"v_dmis.qif", points_qif(dmis)},
      {"v_compensated.qif", results::compensated_qif(three, three_points(), "v3.csv")}};
  for (const auto& [name, text] : documents) {
    const fs::path p = write(name, text);
    const fs::path log = write(name + ".log", "");
    const std::string command = "xmllint --nonet --noout --schema '" + std::string(PROBECOMP_TEST_QIF_XSD) + "' '" +
                                p.string() + "' >'" + log.string() + "' 2>&1";
    EXPECT_EQ(std::system(command.c_str()), 0) << name << " does not validate: see " << log << "\n" << text.substr(0, 2000);
  }
}

}  // namespace
}  // namespace probecomp::io
