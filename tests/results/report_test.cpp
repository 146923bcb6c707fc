// The report's figures against closed forms: the tolerance band's parsing, the deviation summaries per face and
// overall (mean, population std, min, max, out of tolerance) on deviations chosen by hand, and the 3-D view's
// decimation (every k-th row, the worst always); the nominal outline moved by the registration. Rendering in a browser
// is tests/cli/report.sh's.

#include "probecomp/results/report.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace probecomp::results {
namespace {

using compensation::CompensatedPoint;
using compensation::CompensationResult;
using compensation::PointStatus;

CompensatedPoint point(int face, double deviation, PointStatus status = PointStatus::Ok) {
  CompensatedPoint p;
  p.status = status;
  p.face = face;
  p.deviation = deviation;
  p.contact = Point3(deviation, face, 0.0);
  p.normal = Vector3::UnitZ();
  p.uncertainty = 0.001;
  return p;
}

TEST(Tolerance, ParsesABandAndRefusesWhatIsNotOne) {
  const Tolerance t = parse_tolerance("-0.05,0.05");
  EXPECT_EQ(t.lower, -0.05);
  EXPECT_EQ(t.upper, 0.05);
  EXPECT_TRUE(t.passes(0.05));
  EXPECT_TRUE(t.passes(-0.05));
  EXPECT_FALSE(t.passes(0.0500001));
  const Tolerance spaced = parse_tolerance(" 0 , 0.2 ");
  EXPECT_EQ(spaced.lower, 0.0);
  EXPECT_EQ(spaced.upper, 0.2);
  for (const char* bad : {"", "0.05", "0.05,-0.05", "0.01,0.01", "a,b", ",0.1", "0.1,", "nan,1", "0,inf", "1,2,3"}) {
    EXPECT_THROW((void)parse_tolerance(bad), std::invalid_argument) << bad;
  }
}

TEST(DeviationSummaries, PerFaceAndOverallAreTheClosedFormsOfTheTrustedPoints) {
  CompensationResult r;
  r.faces.resize(3);
  r.faces[0].face = 7;
  r.faces[1].face = 2;
  r.faces[2].face = 9;  // no trusted point
  // Face 7: 0.01, 0.03, -0.02 (ok), plus an outlier at 5 that must not count. Face 2: 0.1 and -0.1. Face 9: an edge.
  r.points = {point(7, 0.01), point(7, 0.03), point(2, 0.1), point(7, -0.02), point(7, 5.0, PointStatus::Outlier),
              point(2, -0.1), point(9, 0.5, PointStatus::Edge)};
  const DeviationSummaries s = summarise_deviations(r, Tolerance{-0.025, 0.025});
  ASSERT_EQ(s.faces.size(), 3u);
  const DeviationSummary& f7 = s.faces[0];
  EXPECT_EQ(f7.points, 3);
  EXPECT_NEAR(f7.mean, 0.02 / 3, 1e-15);
  const double m = 0.02 / 3;
  EXPECT_NEAR(f7.std, std::sqrt(((0.01 - m) * (0.01 - m) + (0.03 - m) * (0.03 - m) + (-0.02 - m) * (-0.02 - m)) / 3), 1e-15);
  EXPECT_EQ(f7.min, -0.02);
  EXPECT_EQ(f7.max, 0.03);
  EXPECT_EQ(f7.out_of_tolerance, 1);  // 0.03
  const DeviationSummary& f2 = s.faces[1];
  EXPECT_EQ(f2.points, 2);
  EXPECT_NEAR(f2.mean, 0.0, 1e-15);
  EXPECT_NEAR(f2.std, 0.1, 1e-15);
  EXPECT_EQ(f2.out_of_tolerance, 2);
  EXPECT_EQ(s.faces[2].points, 0);
  EXPECT_EQ(s.faces[2].out_of_tolerance, 0);
  EXPECT_EQ(s.all.points, 5);
  EXPECT_NEAR(s.all.mean, 0.02 / 5, 1e-15);
  EXPECT_EQ(s.all.min, -0.1);
  EXPECT_EQ(s.all.max, 0.1);
  EXPECT_EQ(s.all.out_of_tolerance, 3);
  EXPECT_EQ(summarise_deviations(r, std::nullopt).all.out_of_tolerance, 0);
}

// The view's arrays from the report's embedded JSON.
std::vector<long> view_array(const std::string& html, const std::string& name) {
  const std::string key = "\"" + name + "\":[";
  const std::size_t from = html.find(key);
  EXPECT_NE(from, std::string::npos) << name;
  if (from == std::string::npos) return {};
  const std::size_t begin = from + key.size(), end = html.find(']', begin);
  std::vector<long> out;
  for (std::size_t at = begin; at < end;) {
    const std::size_t comma = std::min(html.find(',', at), end);
    out.push_back(std::stol(html.substr(at, comma - at)));
    at = comma + 1;
  }
  return out;
}

TEST(HtmlReport, TheViewDrawsEveryKthRowAndAlwaysTheWorst) {
  CompensationResult r;
  r.faces.resize(1);
  for (int k = 0; k < 1000; ++k) r.points.push_back(point(0, 0.001 * std::sin(k)));
  r.points[333].deviation = -0.5;  // the worst, not on the stride of 10
  r.points[777].deviation = 0.4;   // the second
  r.statistics.total = 1000;
  r.statistics.counts[0] = 1000;
  ReportContext c;
  c.max_view_points = 100;
  c.labelled_worst = 2;
  const std::string html = html_report(r, c);
  const std::vector<long> rows = view_array(html, "row");
  ASSERT_EQ(rows.size(), 102u);  // rows 1, 11, 21, ... and the two worst
  for (std::size_t i = 1; i < rows.size(); ++i) EXPECT_LT(rows[i - 1], rows[i]);
  const std::vector<long> worst = view_array(html, "worst");
  ASSERT_EQ(worst.size(), 2u);
  EXPECT_EQ(rows[static_cast<std::size_t>(worst[0])], 334);  // 1-based input rows
  EXPECT_EQ(rows[static_cast<std::size_t>(worst[1])], 778);
  EXPECT_NE(html.find("every 10th of 1000 points drawn (102)"), std::string::npos);

  c.max_view_points = 5000;
  EXPECT_EQ(view_array(html_report(r, c), "row").size(), 1000u);
}

TEST(HtmlReport, AHundredThousandPointsStayUnderEightMegabytes) {
  CompensationResult r;
  r.faces.resize(1);
  for (int k = 0; k < 100000; ++k) {
    CompensatedPoint p = point(0, 0.0123456 * std::sin(0.37 * k));
    p.contact = Point3(-123.456789 + 0.01 * k, 456.789012 - 0.003 * k, -78.901234 + 0.002 * k);
    r.points.push_back(p);
  }
  r.statistics.total = 100000;
  r.statistics.counts[0] = 100000;
  const std::string html = html_report(r, ReportContext{});
  EXPECT_LE(html.size(), 8'000'000u);
  EXPECT_EQ(view_array(html, "row").size(), 100000u);  // under the view's limit: every point drawn
}

TEST(HtmlReport, NamesAreEscaped) {
  CompensationResult r;
  ReportContext c;
  c.inputs.points = "a<b>&\"c\".csv";
  const std::string html = html_report(r, c);
  EXPECT_EQ(html.find("a<b>"), std::string::npos);
  EXPECT_NE(html.find("a&lt;b&gt;&amp;&quot;c&quot;.csv"), std::string::npos);
}

TEST(HtmlReport, CharacteristicsAndDatumsHaveTheirTablesWithTheDecisions) {
  CompensationResult r;
  inspection::Inspection judged;
  inspection::CharacteristicResult p1;
  p1.spec = {.name = "P<1>", .faces = {3, 4}, .tolerance = 0.5, .outside = {}, .datums = {"A", "B"}};
  p1.outside = 0.25;
  p1.points = 40;
  p1.min = -0.1234;
  p1.max = 0.3456;
  p1.value = 0.6912;
  p1.u = 0.004;
  p1.decision = inspection::Decision::DoesNotConform;
  inspection::CharacteristicResult p2;
  p2.spec = {.name = "F", .faces = {7}, .tolerance = 0.05, .outside = {}, .datums = {}};
  p2.reason = "3 trusted points on its faces (7 needed for the motions its datums leave free)";
  judged.characteristics = {p1, p2};
  inspection::DatumResult a{.name = "A", .faces = {1}, .fit = inspection::DatumFit::Tangent, .points = 12, .fixes = 3,
                            .rms = 0.002, .size_change = {}};
  judged.datums = {{"A|B", a}};
  judged.alignment = "A|B";
  ReportContext c;
  c.inspection = &judged;
  const std::string html = html_report(r, c);
  EXPECT_NE(html.find("<td class=\"l\">P&lt;1&gt;</td><td class=\"l\">surface-profile</td><td>3, 4</td><td>A|B</td>"
                      "<td>0.5000</td><td>0.2500</td><td>40</td><td>-0.1234</td><td>0.3456</td><td>0.6912</td>"
                      "<td>0.0040</td><td class=\"l fail\">does-not-conform</td>"),
            std::string::npos);
  EXPECT_NE(html.find("<td class=\"l warn\">not-evaluated: 3 trusted points on its faces"), std::string::npos);
  EXPECT_NE(html.find("<td class=\"l\">A</td><td>A|B</td><td class=\"l\">tangent</td><td>1</td><td>12</td><td>3</td>"),
            std::string::npos);
  EXPECT_NE(html.find("in datum frame A|B."), std::string::npos);
  // The view colours by the evaluated one (its zone in µm), chosen by name; a '<' in the view's JSON is escaped, so
  // that no name can end its <script>.
  EXPECT_NE(html.find("<select id=\"view-characteristic\"><option value=\"0\">P&lt;1&gt;</option></select>"),
            std::string::npos);
  EXPECT_NE(html.find("\"characteristics\":[{\"name\":\"P\\u003c1>\",\"zone\":[-250.0,250.0],\"k\":[],\"d\":[],\"U\":[]}]"),
            std::string::npos);
  EXPECT_EQ(html.find("\"name\":\"F\""), std::string::npos);
  // Without characteristics, no such section.
  EXPECT_EQ(html_report(r, ReportContext{}).find("id=\"characteristics\""), std::string::npos);
}

TEST(RegisteredOutline, IsTheModelsOutlineMovedByTheRegistrationWithinItsBudget) {
  const cad::Model model = cad::Model::load(std::filesystem::path(PROBECOMP_TEST_CAD_DIR) / "asitus_repatch-hpdc.stp");
  geometry::RigidTransform T = geometry::RigidTransform::Identity();
  T.rotate(Eigen::AngleAxisd(0.3, Vector3(1, 2, 3).normalized()));
  T.pretranslate(Vector3(10, -20, 5));
  const std::vector<cad::Polyline> at_cad = registered_outline(model, geometry::RigidTransform::Identity(), 5000);
  const std::vector<cad::Polyline> moved = registered_outline(model, T, 5000);
  ASSERT_EQ(at_cad.size(), moved.size());
  std::size_t total = 0;
  for (std::size_t l = 0; l < moved.size(); ++l) {
    ASSERT_EQ(at_cad[l].size(), moved[l].size());
    total += moved[l].size();
    for (std::size_t i = 0; i < moved[l].size(); ++i) EXPECT_LT((T * at_cad[l][i] - moved[l][i]).norm(), 1e-9);
  }
  // Thinned to every k-th point, each line's ends kept: within the budget.
  EXPECT_LE(total, 5000u);
  EXPECT_GT(total, 4000u);
}

}  // namespace
}  // namespace probecomp::results
