// The --json statistics: values that are not finite (a face whose points have no finite uncertainty, a registration
// that failed numerically) must not make the file unreadable, as printf's "nan" and "inf" would.

#include "probecomp/results/files.hpp"
#include "probecomp/results/statistics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <limits>
#include <string>

#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/io/format.hpp"

namespace probecomp::results {

using io::json_number;
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

TEST(StatisticsJson, FiniteValuesAreWrittenAsBefore) {
  EXPECT_EQ(json_number("%.9g", 0.25), "0.25");
  EXPECT_EQ(json_number("%.4f", -0.0), "0.0000");
  EXPECT_EQ(json_number("%.9g", std::numeric_limits<double>::quiet_NaN()), "null");
  EXPECT_EQ(json_number("%.9g", -std::numeric_limits<double>::infinity()), "null");
}

}  // namespace
}  // namespace probecomp::results
