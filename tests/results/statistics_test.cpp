// The --json statistics: values that are not finite (a face whose points have no finite uncertainty, a registration
// that failed numerically) must not make the file unreadable, as printf's "nan" and "inf" would.

#include "probecomp/results/files.hpp"
#include "probecomp/results/statistics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <limits>
#include <string>
#include <vector>

#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/io/json.hpp"

namespace probecomp::results {

namespace {

TEST(StatisticsJson, ValuesThatAreNotFiniteAreWrittenNull) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  constexpr double inf = std::numeric_limits<double>::infinity();
  compensation::CompensationResult r;
  r.registration.rms = inf;
  r.registration.scale = nan;
  compensation::FaceReport face;
  face.face = 0;
  face.points = 3;
  face.fitted = true;
  face.mean_uncertainty = nan;
  face.rms = -inf;
  r.faces.push_back(face);
  r.statistics.deviation_mean = nan;
  const std::string json = statistics_json(r, {.cad = "part.stp", .points = "points.csv", .probe_radius = nan}, {});
  std::string lower = json;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  EXPECT_EQ(lower.find("nan"), std::string::npos) << json;
  EXPECT_EQ(lower.find("inf"), std::string::npos) << json;
  EXPECT_NE(json.find("\"mean_u\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"rms\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"probe_radius\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"rms_residual\": null"), std::string::npos) << json;
}

// The file reads back with a JSON parser (Python's json module reads it too: tests/python, the report's checker),
// its keys in the documented order, its figures to the digits they carry.
TEST(StatisticsJson, ReadsBackWithTheDocumentedKeysAndFigures) {
  compensation::CompensationResult r;
  r.registration.rms = 0.00123456789012;
  compensation::FaceReport face;
  face.face = 4;
  face.points = 2;
  r.faces.push_back(face);
  r.warnings = {"a \"quoted\" warning\nover two lines"};
  r.seconds.fitting = 1.23456;
  const std::string text =
      statistics_json(r, {.cad = "dir/part \"A\".stp", .points = "p.csv", .probe_radius = 1.0, .tip_radii = {1.0, 0.5}},
                      {.read = 0.5}, Tolerance{-0.05, 0.05});
  const io::Json j = io::Json::parse(text);
  std::vector<std::string> keys;
  for (const auto& [key, value] : j.items()) keys.push_back(key);
  EXPECT_EQ(keys, (std::vector<std::string>{"method", "units", "inputs", "transform", "registration", "faces", "counts",
                                            "deviation", "warnings", "timings"}));
  EXPECT_EQ(j["inputs"]["cad"], "dir/part \"A\".stp");
  EXPECT_EQ(j["inputs"]["tip_radii"], io::Json::array({1.0, 0.5}));
  EXPECT_EQ(j["registration"]["rms"].get<double>(), 0.00123456789);  // 9 significant digits
  EXPECT_EQ(j["transform"][0][0].get<double>(), 1.0);
  EXPECT_EQ(j["faces"][0]["face"], 4);
  EXPECT_EQ(j["deviation"]["tolerance"], io::Json::array({-0.05, 0.05}));
  EXPECT_EQ(j["warnings"][0], "a \"quoted\" warning\nover two lines");
  EXPECT_EQ(j["timings"]["fit"].get<double>(), 1.2346);  // seconds to 0.1 ms
  EXPECT_EQ(j["timings"]["read"].get<double>(), 0.5);
  EXPECT_EQ(text.back(), '\n');
}

}  // namespace
}  // namespace probecomp::results
