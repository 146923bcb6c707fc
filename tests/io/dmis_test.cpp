#include "probecomp/io/dmis.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "probecomp/io/point_files.hpp"
#include "probecomp/results/files.hpp"
#include "probecomp/results/statistics.hpp"

namespace probecomp {
namespace {

std::filesystem::path write(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("probecomp_dmis_" + name);
  std::ofstream(path) << text;
  return path;
}

TEST(Dmis, ReadsActualPointsWithContinuationsAndComments) {
  const auto path = write("a.dmo",
                          "$$ measured\n"
                          "DMISMN/'x',05.3\n"
                          "F(P1)=FEAT/POINT,CART,0,0,0,0,0,1\n"
                          "FA(P1)=FEAT/POINT,CART,1.5,2.5,3.5,0,0,2\n"
                          "FA(P2) = FEAT/POINT,CART,$\n"
                          "  4,5,$\n"
                          "  6,1,0,0\n"
                          "ENDFIL\n");
  const io::PointTable t = io::read_points(path);
  ASSERT_EQ(t.points.size(), 2u);  // the nominal F(P1) is not a measured point when actuals exist
  EXPECT_EQ(t.points[0], Point3(1.5, 2.5, 3.5));
  EXPECT_EQ(t.points[1], Point3(4, 5, 6));
  ASSERT_TRUE(t.normals.has_value());
  EXPECT_EQ((*t.normals)[0], Vector3(0, 0, 1));  // normalised
  EXPECT_EQ(t.rows[1][0], "P2");
  EXPECT_EQ(t.line[1], 5);
  ASSERT_EQ(t.carried_columns().size(), 1u);
}

TEST(Dmis, FeaturePointsAreReadWhenThereAreNoActuals) {
  const io::PointTable t = io::read_point_dmis(write("b.dmo", "F(A)=FEAT/POINT,CART,1,2,3\nF(B)=FEAT/POINT,CART,4,5,6\n"));
  EXPECT_EQ(t.points.size(), 2u);
  EXPECT_FALSE(t.normals.has_value());
}

// The message read_point_dmis throws for a file of `text`, or "no error".
std::string message(const std::string& name, const std::string& text) {
  try {
    (void)io::read_point_dmis(write(name, text));
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(Dmis, ErrorsNameTheFileAndLine) {
  EXPECT_NE(message("c.dmo", "FA(A)=FEAT/POINT,CART,1,2\n").find("c.dmo:1: point A has 2 numbers"), std::string::npos);
  EXPECT_NE(message("d.dmo", "\nFA(A)=FEAT/POINT,CART,1,x,3\n").find("d.dmo:2:"), std::string::npos);
  EXPECT_NE(message("e.dmo", "FA(A)=FEAT/POINT,CART,1,2,3,0,0,0\n").find("zero"), std::string::npos);
  EXPECT_NE(message("f.dmo", "FA(A)=FEAT/POINT,CART,1,2,3,0,0,1\nFA(B)=FEAT/POINT,CART,1,2,3\n").find("f.dmo:2:"),
            std::string::npos);
  EXPECT_NE(message("g.dmo", "DMISMN/'x',05.3\n").find("no points"), std::string::npos);
  EXPECT_NE(message("h.dmo", "FA(A)=FEAT/POINT,CART,1,2,$\n").find("ends inside"), std::string::npos);
  EXPECT_NE(message("i.dmo", "FA(A)=FEAT/POINT,POL,1,2,3,0,0,1\n").find("polar"), std::string::npos);
}

TEST(Dmis, WrittenPointsReadBack) {
  const std::string text = io::dmis_point("Q7", Point3(1.25, -2, 3e-9), Vector3(0, 0.6, 0.8));
  const io::PointTable t = io::read_point_dmis(write("j.dmo", text));
  ASSERT_EQ(t.points.size(), 1u);
  EXPECT_NEAR((t.points[0] - Point3(1.25, -2, 3e-9)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(((*t.normals)[0] - Vector3(0, 0.6, 0.8)).norm(), 0.0, 1e-12);
  EXPECT_EQ(t.rows[0][0], "Q7");
}

// Issue 20, item 6: DMIS's UNITS statement. 1 inch = 25.4 mm exactly; 25.4 itself is not exact in binary, so
// products are compared to 1e-12 mm.
TEST(Dmis, UnitsStatementsScaleThePointsAfterThem) {
  const io::PointTable t = io::read_point_dmis(write("u1.dmo",
                                                     "UNITS/INCH,ANGDEC\n"
                                                     "FA(A)=FEAT/POINT,CART,1,2,-0.5,0,0,1\n"
                                                     "UNITS/MM,ANGDEC\n"
                                                     "FA(B)=FEAT/POINT,CART,1,2,-0.5,0,0,1\n"
                                                     "units / cm , angdec\n"
                                                     "FA(C)=FEAT/POINT,CART,1,2,-0.5,0,0,1\n"));
  ASSERT_EQ(t.points.size(), 3u);
  EXPECT_EQ(t.unit.name, std::string("inch"));  // the unit at the first point: outputs are written in it
  EXPECT_NEAR((t.points[0] - Point3(25.4, 50.8, -12.7)).norm(), 0.0, 1e-12);
  EXPECT_EQ(t.points[1], Point3(1, 2, -0.5));
  EXPECT_NEAR((t.points[2] - Point3(10, 20, -5)).norm(), 0.0, 1e-12);
  EXPECT_EQ((*t.normals)[0], Vector3(0, 0, 1));  // normals have no unit
}

TEST(Dmis, TheDeclaredUnitReadsAFileWithoutUnitsAndMustAgreeWithOne) {
  const auto plain = write("u2.dmo", "FA(A)=FEAT/POINT,CART,1,0,0\nFA(B)=FEAT/POINT,CART,0,1,0\n");
  const io::PointTable t = io::read_points(plain, io::kInch);
  EXPECT_EQ(t.unit.name, std::string("inch"));
  EXPECT_EQ(t.points[0], Point3(25.4, 0, 0));
  EXPECT_EQ(io::read_points(plain).points[0], Point3(1, 0, 0));  // DMIS's default: mm
  const auto inch = write("u3.dmo", "$$ x\nUNITS/INCH,ANGDEC\nFA(A)=FEAT/POINT,CART,1,0,0\n");
  EXPECT_EQ(io::read_points(inch, io::kInch).points[0], Point3(25.4, 0, 0));
  try {
    (void)io::read_points(inch, io::kMillimetre);
    ADD_FAILURE() << "a UNITS statement against --units was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("u3.dmo:2: the file says its lengths are in inch, not in mm"), std::string::npos)
        << e.what();
  }
  try {
    (void)io::read_points(write("u4.dmo", "UNITS/YARD,ANGDEC\nFA(A)=FEAT/POINT,CART,1,0,0\n"));
    ADD_FAILURE() << "an unknown unit was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("u4.dmo:1: unknown length unit 'YARD'"), std::string::npos) << e.what();
  }
}

TEST(Dmis, PointsWrittenInInchesReadBackInMillimetres) {
  const std::string text = io::dmis_units(io::kInch) + io::dmis_point("P", Point3(25.4, -2.54, 0.127), Vector3(1, 0, 0), io::kInch);
  EXPECT_NE(text.find("UNITS/INCH,ANGDEC\nFA(P)=FEAT/POINT,CART,1.000000000,-0.100000000,0.005000000,"), std::string::npos) << text;
  const io::PointTable t = io::read_point_dmis(write("u5.dmo", text));
  EXPECT_NEAR((t.points[0] - Point3(25.4, -2.54, 0.127)).norm(), 0.0, 1e-12);
}

// Issue 21: tip definitions (SNSDEF) and selections (SNSLCT) give each measured point its tip radius.
TEST(Dmis, SensorsGiveEachPointItsTipRadiusInTheUnitInForce) {
  const io::PointTable t = io::read_point_dmis(write("s1.dmo",
                                                     "UNITS/INCH,ANGDEC\n"
                                                     "FA(P0)=FEAT/POINT,CART,0,0,1,0,0,1\n"
                                                     "S(BIG)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,6,0.04\n"
                                                     "s(Small) = snsdef/probe, fixed, cart, 10, 0, -2, 0, 0, 1, $\n"
                                                     "  0.02\n"
                                                     "S(DISC1)=SNSDEF/PROBE,FIXED,POL,0,0,0,0,1,4.5,0.5,DISC,0.1\n"
                                                     "SNSLCT/S(BIG)\n"
                                                     "FA(P1)=FEAT/POINT,CART,1,2,3,0,0,1\n"
                                                     "SNSLCT/S(SMALL)\n"
                                                     "FA(P2)=FEAT/POINT,CART,4,5,6,0,0,1\n"
                                                     "SA(BIG)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,6,0.0398\n"
                                                     "SNSLCT/SA(BIG)\n"
                                                     "FA(P3)=FEAT/POINT,CART,7,8,9,0,0,1\n"));
  EXPECT_EQ(t.columns, (std::vector<std::string>{"label", "x", "y", "z", "i", "j", "k", "r", "tip"}));
  ASSERT_TRUE(t.radii.has_value());
  ASSERT_EQ(t.radii->size(), 4u);
  EXPECT_TRUE(std::isnan((*t.radii)[0]));  // measured before any selection: the run's default
  EXPECT_EQ((*t.radii)[1], 25.4 * 0.02);   // half the diameter, in inches
  EXPECT_EQ((*t.radii)[2], 25.4 * 0.01);
  EXPECT_EQ((*t.radii)[3], 25.4 * 0.0199);  // the calibrated (actual) sensor, defined later
  EXPECT_EQ(t.rows[0][7], "");
  EXPECT_EQ(t.rows[1][7], "0.02");
  EXPECT_EQ(t.rows[1][8], "BIG");
  EXPECT_EQ(t.rows[2][8], "Small");  // names are matched without case, kept as defined
  EXPECT_EQ(t.sensor_definitions.at("Small"), "snsdef/probe,fixed,cart,10,0,-2,0,0,1,0.02");
  // The label and the tip are carried to outputs; r is the row's radius.
  EXPECT_EQ(t.carried_header({"x"}), ",label,tip");
}

TEST(Dmis, FilesWithoutSelectionsReadAsBefore) {
  const io::PointTable t = io::read_point_dmis(
      write("s2.dmo", "S(BIG)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,6,2\nFA(P1)=FEAT/POINT,CART,1,2,3,0,0,1\n"));
  EXPECT_EQ(t.columns, (std::vector<std::string>{"label", "x", "y", "z", "i", "j", "k"}));
  EXPECT_FALSE(t.radii.has_value());
}

TEST(Dmis, SensorErrorsNameTheFileAndLine) {
  const std::string point = "FA(P1)=FEAT/POINT,CART,1,2,3\n";
  EXPECT_NE(message("e1.dmo", "S(A)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,6,2\nSNSLCT/S(B)\n" + point)
                .find("e1.dmo:2: SNSLCT selects S(B), which no SNSDEF before it defines"),
            std::string::npos);
  EXPECT_NE(message("e2.dmo", "SNSLCT/S(A)\nS(A)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,6,2\n" + point).find("e2.dmo:1: SNSLCT selects S(A)"),
            std::string::npos);
  for (const std::string bad : {"0", "-1", "abc", "nan"}) {
    EXPECT_NE(message("e3.dmo", "$$ x\nS(A)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,6," + bad + "\n" + point)
                  .find("e3.dmo:2: sensor S(A): the ball diameter (the last number) must be a positive number, not '" + bad + "'"),
              std::string::npos)
        << bad;
  }
  EXPECT_NE(message("e4.dmo", "S(A)=SNSDEF/PROBE,INDEX,POL,0,x,0,0,1,6,2\n" + point).find("e4.dmo:1: sensor S(A): 'x' is not a number"),
            std::string::npos);
  // A form probecomp does not read is an error only where it is selected.
  const std::string disc = "S(D)=SNSDEF/PROBE,FIXED,POL,0,0,0,0,1,115,12,DISC,3\n";
  EXPECT_EQ(message("e5.dmo", disc + point), "no error");
  EXPECT_NE(message("e6.dmo", disc + "SNSLCT/S(D)\n" + point)
                .find("e6.dmo:2: SNSLCT selects S(D), whose definition (line 1) probecomp cannot read: its tip is a DISC"),
            std::string::npos);
  EXPECT_NE(message("e7.dmo", "S(V)=SNSDEF/PROBE,FIXED,VEC,0,0,1,100,2\nSNSLCT/S(V)\n" + point).find("e7.dmo:2: SNSLCT selects S(V)"),
            std::string::npos);
}

TEST(Dmis, OutputsDefineEachTipOnceAndSelectItWhenItChanges) {
  io::PointTable t;
  t.columns = {"x", "y", "z"};
  for (int k = 0; k < 4; ++k) {
    t.points.emplace_back(k, 0, 0);
    t.rows.push_back({std::to_string(k), "0", "0"});
    t.line.push_back(k + 2);
  }
  t.radii = std::vector<double>{1, 0.25, 0.25, 1};
  const std::string text = io::points_dmis(t, "in.csv");
  EXPECT_NE(text.find("UNITS/MM,ANGDEC\n$$ S(TIP1): the ball's diameter as measured with; the probe's orientation and length "
                      "are not known here (neutral INDEX,POL,0,0,0,0,1,0)\nS(TIP1)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,0,2\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("SNSLCT/S(TIP1)\nFA(P1)=FEAT/POINT,CART,0,0,0\nSNSLCT/S(TIP2)\nFA(P2)=FEAT/POINT,CART,1,0,0\n"
                      "FA(P3)=FEAT/POINT,CART,2,0,0\nSNSLCT/S(TIP1)\nFA(P4)"),
            std::string::npos)
      << text;
  const io::PointTable back = io::read_point_dmis(write("o1.dmo", text));
  EXPECT_EQ(*back.radii, *t.radii);
  // A tip name met with two radii is two tips; a row without a radius after one with is refused.
  t.columns.push_back("tip");
  io::Fields tagged;
  for (const auto row : t.rows) tagged.push_back({std::string(row[0]), std::string(row[1]), std::string(row[2]), "T"});
  t.rows = tagged;
  EXPECT_NE(io::points_dmis(t, "in.csv").find("S(T_2)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,0,0.5\n"), std::string::npos);
  (*t.radii)[2] = std::nan("");
  EXPECT_THROW((void)io::points_dmis(t, "in.csv"), InputError);
}

TEST(Dmis, CompensatedOutputStatesTheTipsOfAnInputThatGaveThem) {
  const io::PointTable in = io::read_point_dmis(write("c1.dmo",
                                                      "S(A)=SNSDEF/PROBE,INDEX,POL,0,90,0,0,1,150,2\n"
                                                      "SNSLCT/S(A)\nFA(P1)=FEAT/POINT,CART,1,2,3,0,0,1\n"
                                                      "FA(P2)=FEAT/POINT,CART,1,2,4,0,0,1\n"));
  compensation::CompensationResult r;
  for (int k = 0; k < 2; ++k) {
    compensation::CompensatedPoint p;
    p.status = compensation::PointStatus::Ok;
    p.normal = Vector3(0, 0, 1);
    p.radius = 1.0;
    r.points.push_back(p);
  }
  const std::string text = results::compensated_dmis(in, r, "c1.dmo");
  EXPECT_NE(text.find("UNITS/MM,ANGDEC\nS(A)=SNSDEF/PROBE,INDEX,POL,0,90,0,0,1,150,2\nSNSLCT/S(A)\nFA(P1)="), std::string::npos)
      << text;
  EXPECT_EQ(text.find("SNSLCT", text.find("FA(P1)")), std::string::npos) << text;  // selected once
}

}  // namespace
}  // namespace probecomp
