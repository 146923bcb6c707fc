#include "probecomp/io/dmis.hpp"

#include <gtest/gtest.h>

#include <fstream>

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

TEST(Dmis, ErrorsNameTheFileAndLine) {
  auto message = [](const std::string& name, const std::string& text) {
    try {
      (void)io::read_point_dmis(write(name, text));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
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

}  // namespace
}  // namespace probecomp
