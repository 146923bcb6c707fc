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

}  // namespace
}  // namespace probecomp
