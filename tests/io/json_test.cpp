// Numbers in the JSON files: the digits their quantity carries, null for what JSON cannot hold, and text that a
// parser reads whatever bytes a CAD file's names hold.
#include "probecomp/io/json.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace probecomp::io {
namespace {

TEST(Json, NumbersKeepTheDigitsAsked) {
  EXPECT_EQ(json_number(0.25).dump(), "0.25");
  EXPECT_EQ(json_number(0.1 + 0.2).dump(), "0.3");  // not 0.30000000000000004
  EXPECT_EQ(json_number(1.0 / 3.0, 4).dump(), "0.3333");
  EXPECT_EQ(json_number(123456.789, 4).dump(), "123500.0");
  EXPECT_EQ(json_fixed(0.00123456, 4).dump(), "0.0012");
  EXPECT_EQ(json_fixed(2.0, 3).dump(), "2.0");
  EXPECT_EQ(json_fixed(-0.00001, 4).dump(), "0.0");  // no "-0.0"
  EXPECT_EQ(json_number(-0.0).dump(), "0.0");
  EXPECT_EQ(json_number(1.5e-12).dump(), "1.5e-12");
}

TEST(Json, ValuesThatAreNotFiniteAreNull) {
  EXPECT_TRUE(json_number(std::numeric_limits<double>::quiet_NaN()).is_null());
  EXPECT_TRUE(json_number(-std::numeric_limits<double>::infinity()).is_null());
  EXPECT_TRUE(json_fixed(std::numeric_limits<double>::infinity(), 3).is_null());
}

TEST(Json, TextReadsBackAndToleratesBytesThatAreNotUtf8) {
  const Json j = {{"name", std::string("face \xff\"7\"\n")}, {"x", json_fixed(1.25, 2)}};
  const std::string text = json_text(j);
  EXPECT_EQ(text.back(), '\n');
  const Json back = Json::parse(text);
  EXPECT_EQ(back["name"], "face \xEF\xBF\xBD\"7\"\n");  // U+FFFD for the stray byte
  EXPECT_EQ(back["x"].get<double>(), 1.25);
  EXPECT_EQ(json_text(Json::array({1, 2}), -1), "[1,2]\n");
}

}  // namespace
}  // namespace probecomp::io
