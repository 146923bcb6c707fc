// io/charts: ticks, the axis mapping (marker and bar positions computed by hand from the documented layout), NaN
// breaking a line, escaping, and nothing outside the SVG referenced.

#include "probecomp/io/charts.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace probecomp::io {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}

// Nothing the SVG would fetch: no links, no script, no CSS import or url(), no address but the SVG namespace.
void expect_self_contained(const std::string& svg) {
  EXPECT_EQ(count(svg, "href"), 0u);
  EXPECT_EQ(count(svg, "src="), 0u);
  EXPECT_EQ(count(svg, "url("), 0u);
  EXPECT_EQ(count(svg, "@import"), 0u);
  EXPECT_EQ(count(svg, "<script"), 0u);
  EXPECT_EQ(count(svg, "http"), count(svg, "http://www.w3.org/2000/svg"));
  EXPECT_EQ(count(svg, "<svg"), 1u);
  EXPECT_EQ(svg.rfind("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"", 0), 0u);
}

TEST(Charts, NiceTicksAreOneTwoOrFiveTimesAPowerOfTen) {
  EXPECT_EQ(nice_ticks(0, 1), (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1}));
  EXPECT_EQ(nice_ticks(0, 37), (std::vector<double>{0, 10, 20, 30, 40}));
  EXPECT_EQ(nice_ticks(0, 40), (std::vector<double>{0, 10, 20, 30, 40}));
  EXPECT_EQ(nice_ticks(-0.013, 0.027), (std::vector<double>{-0.02, -0.01, 0, 0.01, 0.02, 0.03}));
  EXPECT_EQ(nice_ticks(0.6, 1.4), (std::vector<double>{0.6, 0.8, 1, 1.2, 1.4}));  // bounds on multiples stay ends
  EXPECT_EQ(nice_ticks(0, 180), (std::vector<double>{0, 50, 100, 150, 200}));
  EXPECT_EQ(nice_ticks(5, 5), (std::vector<double>{4.4, 4.6, 4.8, 5, 5.2, 5.4, 5.6}));  // widened to 4.5..5.5
  EXPECT_EQ(nice_ticks(0, 0), (std::vector<double>{-1, -0.5, 0, 0.5, 1}));
  EXPECT_EQ(nice_ticks(kNaN, 3), (std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1}));
  EXPECT_EQ(nice_ticks(37, 0), (std::vector<double>{0, 10, 20, 30, 40}));
  // Ranges a double cannot step through come back as they are rather than looping.
  EXPECT_EQ(nice_ticks(-1e308, 1e308), (std::vector<double>{-1e308, 1e308}));
  EXPECT_EQ(nice_ticks(1e300, std::nextafter(1e300, 2e300), 3).size(), 2u);
}

TEST(Charts, LogTicksAreDecadesCoveringTheRange) {
  EXPECT_EQ(log_ticks(0.003, 0.2), (std::vector<double>{0.001, 0.01, 0.1, 1}));
  EXPECT_EQ(log_ticks(0.001, 1000), (std::vector<double>{0.001, 0.01, 0.1, 1, 10, 100, 1000}));
  EXPECT_EQ(log_ticks(1, 1), (std::vector<double>{1, 10}));
  EXPECT_EQ(log_ticks(0, 5), (std::vector<double>{1, 10}));
  EXPECT_EQ(log_ticks(2e-7, 3e-7), (std::vector<double>{1e-7, 1e-6}));
  EXPECT_EQ(log_ticks(1e-8, 1), (std::vector<double>{1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1}));  // 8 decades
  EXPECT_EQ(log_ticks(1e-9, 1), (std::vector<double>{1e-10, 1e-8, 1e-6, 1e-4, 1e-2, 1}));              // 9: every 2nd
  EXPECT_EQ(log_ticks(8e-16, 0.178), (std::vector<double>{1e-16, 1e-14, 1e-12, 1e-10, 1e-8, 1e-6, 1e-4, 1e-2, 1}));
  EXPECT_DOUBLE_EQ(log_ticks(1e-320, 1e-310).front(), 1e-300);  // no decade below the normal doubles
  EXPECT_EQ(log_ticks(3, 2e20), (std::vector<double>{1, 1e3, 1e6, 1e9, 1e12, 1e15, 1e18, 1e21}));      // 21: every 3rd
}

TEST(Charts, TickLabelsHaveTheDecimalsTheStepNeeds) {
  EXPECT_EQ(tick_labels(nice_ticks(0, 1), false), (std::vector<std::string>{"0.0", "0.2", "0.4", "0.6", "0.8", "1.0"}));
  EXPECT_EQ(tick_labels(nice_ticks(0, 37), false), (std::vector<std::string>{"0", "10", "20", "30", "40"}));
  EXPECT_EQ(tick_labels(nice_ticks(-0.013, 0.027), false),
            (std::vector<std::string>{"-0.02", "-0.01", "0.00", "0.01", "0.02", "0.03"}));
  EXPECT_EQ(tick_labels(log_ticks(0.003, 20), true), (std::vector<std::string>{"0.001", "0.01", "0.1", "1", "10", "100"}));
}

TEST(Charts, MarkersLandWhereTheAxisMappingPutsThem) {
  // Legend: one name of 1 character → 44 + 8 = 52 px. Plot area: x 72 … 640 − 16 − 52 = 572, y 40 … 400 − 52 = 348.
  // Axes: x ticks 0 … 10 (step 2), y ticks 0 … 1 (step 0.2).
  const std::string svg = line_chart_svg({{.name = "s", .x = {0, 5, 10}, .y = {0, 0.5, 1}}},
                                         {.title = "t", .x_label = "x", .y_label = "y"});
  EXPECT_DOUBLE_EQ(legend_width({{.name = "s"}}), 52);
  EXPECT_NE(svg.find("<circle cx=\"72.00\" cy=\"348.00\" r=\"3\""), std::string::npos) << svg;
  EXPECT_NE(svg.find("<circle cx=\"322.00\" cy=\"194.00\" r=\"3\""), std::string::npos) << svg;  // 72 + 500/2, 348 − 308/2
  EXPECT_NE(svg.find("<circle cx=\"572.00\" cy=\"40.00\" r=\"3\""), std::string::npos) << svg;
  EXPECT_NE(svg.find("points=\"72.00,348.00 322.00,194.00 572.00,40.00\""), std::string::npos) << svg;
  EXPECT_NE(svg.find("<title>s: x = 5, y = 0.5</title>"), std::string::npos) << svg;  // hover text
  EXPECT_NE(svg.find(">0.6</text>"), std::string::npos);                                // y tick label
  EXPECT_NE(svg.find(">10</text>"), std::string::npos);                                 // x tick label
  EXPECT_NE(svg.find("width=\"640\" height=\"400\""), std::string::npos);
  expect_self_contained(svg);

  // Given x ticks are the x range: x = 5 on 0 … 20 is a quarter of the way.
  const std::string given = line_chart_svg({{.name = "s", .x = {5}, .y = {0.5}}}, {.x_ticks = {0, 10, 20}});
  EXPECT_NE(given.find("<circle cx=\"197.00\""), std::string::npos) << given;  // 72 + 500/4
}

TEST(Charts, NaNBreaksTheLine) {
  const std::vector<Series> series = {{.name = "gap", .x = {0, 1, 2, 3, 4}, .y = {0, 1, kNaN, 3, 4}},
                                      {.name = "bad x", .x = {0, kNaN, 2}, .y = {1, 1, 1}, .markers = false}};
  const std::string svg = line_chart_svg(series, {});
  EXPECT_EQ(count(svg, "<polyline"), 2u);  // "gap": 0-1 and 3-4; "bad x": two lone points, dots
  EXPECT_EQ(count(svg, "<title>gap: "), 4u);
  EXPECT_EQ(count(svg, "<title>bad x: "), 0u);
  EXPECT_EQ(count(svg, "r=\"1.5\""), 2u);
  EXPECT_EQ(count(svg, "nan"), 0u);
  EXPECT_EQ(count(svg, "inf"), 0u);

  // On a log axis a value <= 0 is not drawn either.
  const std::string log = line_chart_svg({{.name = "l", .x = {0, 1, 2, 3}, .y = {1, 10, 0, 100}}}, {.log_y = true});
  EXPECT_EQ(count(log, "<polyline"), 1u);
  EXPECT_EQ(count(log, "<title>l: "), 3u);
  EXPECT_NE(log.find(">100</text>"), std::string::npos);
}

TEST(Charts, PalettesAndDashes) {
  EXPECT_EQ(series_colour(Palette::Categorical, 0, 3), "#0072B2");
  EXPECT_EQ(series_colour(Palette::Categorical, 9, 10), "#D55E00");
  EXPECT_EQ(series_colour(Palette::Sequential, 0, 10), "#440154");
  EXPECT_EQ(series_colour(Palette::Sequential, 9, 10), "#BDDF26");  // viridis at 0.9
  EXPECT_EQ(series_colour(Palette::Sequential, 1, 10), "#482475");
  std::vector<Series> nine;
  for (int k = 0; k < 9; ++k) nine.push_back({.name = std::string(1, static_cast<char>('a' + k)), .x = {0, 1}, .y = {0, 1.0 * k}});
  const std::string svg = line_chart_svg(nine, {.width = 800});
  EXPECT_EQ(count(svg, "stroke-dasharray"), 2u);  // the 9th series and its legend swatch
  nine.front().dashed = true;
  EXPECT_EQ(count(line_chart_svg(nine, {.width = 800}), "stroke-dasharray"), 4u);
}

TEST(Charts, TextIsEscaped) {
  EXPECT_EQ(xml_escape("a<b & \"c\" > 'd'"), "a&lt;b &amp; &quot;c&quot; &gt; &#39;d&#39;");
  const std::string svg = line_chart_svg({{.name = "<script>x</script>", .x = {1, 2}, .y = {1, 2}}},
                                         {.title = "R & r <\"mm\">", .x_label = "θ (°)", .y_label = "a<b"});
  EXPECT_EQ(count(svg, "<script"), 0u);
  EXPECT_NE(svg.find("&lt;script&gt;x&lt;/script&gt;"), std::string::npos);
  EXPECT_NE(svg.find("<title>R &amp; r &lt;&quot;mm&quot;&gt;</title>"), std::string::npos);
  EXPECT_NE(svg.find("θ (°)"), std::string::npos);
  EXPECT_EQ(count(svg, "a<b"), 0u);
  // Legend width counts characters, not bytes: "θ" is 2 bytes, one character.
  EXPECT_DOUBLE_EQ(legend_width({{.name = "θθ"}}), 44 + 16);
  expect_self_contained(svg);
}

TEST(Charts, BarsStandOnZeroAtTheMappedHeight) {
  // Legend 52 px (names of 1 character): plot x 72 … 572, y 40 … 348; y ticks 0 … 3; groups 250 px wide, bars
  // 0.8 · 250 / 2 = 100 px, starting 0.1 of a group in.
  const std::string svg = grouped_bar_chart_svg({"rx", "tx"}, {{.name = "a", .y = {1, 2}}, {.name = "b", .y = {3, kNaN}}},
                                                {.title = "bars"});
  EXPECT_NE(svg.find("<rect x=\"97.00\" y=\"245.33\" width=\"100.00\" height=\"102.67\"><title>a, rx: 1</title>"),
            std::string::npos)
      << svg;
  EXPECT_NE(svg.find("<rect x=\"197.00\" y=\"40.00\" width=\"100.00\" height=\"308.00\"><title>b, rx: 3</title>"),
            std::string::npos)
      << svg;
  EXPECT_EQ(count(svg, "<title>b, tx"), 0u);  // NaN: no bar
  EXPECT_NE(svg.find(">rx</text>"), std::string::npos);
  expect_self_contained(svg);

  // Log scale: decades 0.001 … 1; 0.01 is a third of the way up; 0 is not drawn.
  const std::string log =
      grouped_bar_chart_svg({"c"}, {{.name = "a", .y = {0.01}}, {.name = "b", .y = {0.5}}, {.name = "y", .y = {0.002}},
                                    {.name = "z", .y = {0}}},
                            {.log_y = true});
  EXPECT_NE(log.find("y=\"245.33\""), std::string::npos) << log;  // 348 − 308/3
  EXPECT_EQ(count(log, "<title>z, c"), 0u);
  EXPECT_THROW((void)grouped_bar_chart_svg({"a", "b"}, {{.name = "s", .y = {1}}}, {}), std::invalid_argument);
}

TEST(Charts, SideBySideIsOneSvg) {
  const std::string left = line_chart_svg({{.name = "a", .x = {0, 1}, .y = {0, 1}}}, {.title = "L", .width = 300, .height = 200});
  const std::string right = grouped_bar_chart_svg({"c"}, {{.name = "b", .y = {1}}}, {.title = "R", .width = 320, .height = 240});
  const std::string both = side_by_side_svg({left, right}, "both & more");
  EXPECT_EQ(both.rfind("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"620\" height=\"240\"", 0), 0u) << both;
  EXPECT_NE(both.find("<title>both &amp; more</title>"), std::string::npos);
  EXPECT_NE(both.find("<g transform=\"translate(300 0)\">"), std::string::npos);
  EXPECT_NE(both.find("<title>L</title>"), std::string::npos);
  EXPECT_EQ(count(both, "</svg>"), 1u);
  expect_self_contained(both);
  EXPECT_THROW((void)side_by_side_svg({"<svg>"}, ""), std::invalid_argument);
}

TEST(Charts, MismatchedSeriesAndCrampedChartsAreRefused) {
  EXPECT_THROW((void)line_chart_svg({{.name = "s", .x = {1, 2}, .y = {1}}}, {}), std::invalid_argument);
  EXPECT_THROW((void)line_chart_svg({{.name = std::string(80, 'n'), .x = {1}, .y = {1}}}, {.width = 400}),
               std::invalid_argument);
}

TEST(Charts, HistogramCountsPerBin) {
  const Histogram h = histogram({0.05, 0.15, 0.15, 0.95, -0.1, kNaN, 1.0}, 0, 0.1, 10);
  EXPECT_EQ(h.counts, (std::vector<int>{1, 2, 0, 0, 0, 0, 0, 0, 0, 1}));
  EXPECT_EQ(h.outside, 2);  // -0.1 and 1.0
  EXPECT_DOUBLE_EQ(h.centre(1), 0.15);
  EXPECT_THROW((void)histogram({1}, 0, 0, 1), std::invalid_argument);
}

}  // namespace
}  // namespace probecomp::io
