// read_transform (--initial-transform) against matrices written by hand, and every malformed file refused with
// its line.

#include "probecomp/io/transform_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "probecomp/error.hpp"

namespace probecomp::io {
namespace {

std::filesystem::path write_transform_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("probecomp_transform_" + name);
  std::ofstream(path) << text;
  return path;
}

std::string message(const std::string& name, const std::string& text) {
  try {
    (void)read_transform(write_transform_file(name, text));
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ReadTransform, FourRowsOfFourWithCommentsCommasAndTabs) {
  // 90° about z, then (1, -2.5, 3).
  const geometry::RigidTransform T =
      read_transform(write_transform_file("a.txt", "# CAD -> machine\n\n0 -1 0 1\n1,0,0,-2.5\n0\t0\t1\t+3\n0 0 0 1\n"));
  EXPECT_NEAR((T * Point3(1, 0, 0) - Point3(1, -1.5, 3)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((T * Point3(0, 1, 0) - Point3(0, -2.5, 3)).norm(), 0.0, 1e-15);
}

TEST(ReadTransform, RoundingInTheFileIsTakenToTheNearestRotation) {
  // cos and sin of 30° to 7 digits: off orthonormal by about 1e-7, within the tolerance; the result is exact.
  const geometry::RigidTransform T =
      read_transform(write_transform_file("b.txt", "0.8660254 -0.5 0 0\n0.5 0.8660254 0 0\n0 0 1 0\n0 0 0 1\n"));
  EXPECT_NEAR((T.linear().transpose() * T.linear() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-14);
  EXPECT_NEAR(std::atan2(T.linear()(1, 0), T.linear()(0, 0)) * 180.0 / M_PI, 30.0, 1e-5);
}

TEST(ReadTransform, MalformedFilesNameTheLineAndCause) {
  EXPECT_NE(message("c.txt", "1 0 0 0\n0 1 0\n0 0 1 0\n0 0 0 1\n").find("c.txt:2: row 2 has 3 numbers"), std::string::npos);
  EXPECT_NE(message("d.txt", "1 0 0 0\n0 1 x 0\n").find("d.txt:2: 'x' is not a finite number"), std::string::npos);
  EXPECT_NE(message("e.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n").find("e.txt: 3 rows"), std::string::npos);
  EXPECT_NE(message("f.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n0 0 0 1\n").find("f.txt:5: more than four rows"),
            std::string::npos);
  EXPECT_NE(message("g.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n").find("g.txt:4: the last row must be 0 0 0 1"),
            std::string::npos);
  EXPECT_NE(message("h.txt", "2 0 0 0\n0 2 0 0\n0 0 2 0\n0 0 0 1\n").find("not orthonormal"), std::string::npos);
  EXPECT_NE(message("i.txt", "-1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n").find("it mirrors"), std::string::npos);
  EXPECT_NE(message("j.txt", "1 0 0 nan\n0 1 0 0\n0 0 1 0\n0 0 0 1\n").find("'nan' is not a finite number"), std::string::npos);
  EXPECT_NE(message("k.txt", "").find("0 rows"), std::string::npos);
  try {
    (void)read_transform("/nonexistent/T.txt");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/T.txt: cannot be opened"), std::string::npos);
  }
}

}  // namespace
}  // namespace probecomp::io
