#pragma once
// Charts for the studies' figures as self-contained SVG text: line charts and grouped bar charts with "nice" ticks, a
// legend and hover titles; no script and no external reference (the files open offline), text escaped, numbers via fmt.

#include <cstddef>
#include <string>
#include <vector>

namespace probecomp::io {

// One line of a line chart (x and y of equal length) or, for grouped_bar_chart_svg, one bar per category (y; x unused).
// A point whose x or y is NaN (or, on a log axis, y <= 0) is skipped and breaks the line.
struct Series {
  std::string name{};
  std::vector<double> x{}, y{};
  bool markers = true;  // a circle with a hover <title> ("name: x = …, y = …") at every point
  bool dashed = false;
};

enum class Palette {
  Categorical,  // Okabe–Ito's colour-blind-safe colours, in order, repeated dashed after the 8th
  Sequential    // viridis from dark to light (not its yellow end): for series ordered by a parameter
};

struct ChartOptions {
  std::string title{}, x_label{}, y_label{};
  double width = 640, height = 400;  // of the whole chart, legend included
  bool log_y = false;                // decades 10^k; values <= 0 are not drawn
  bool y_includes_zero = true;       // a linear y axis always spans 0
  std::vector<double> x_ticks{};     // a line chart's x ticks as given (their first and last are the x range)
  Palette palette = Palette::Categorical;
};

// The layout, in pixels from the top left corner (for tests and captions):
//   plot area x from kChartLeft to width − kChartRight − legend width, y from kChartTop to height − kChartBottom;
//   legend width = 0 without named series, else 44 + 8 × the longest name's length in characters (UTF-8 code points).
// A value v maps linearly from the first..last tick onto the plot area (upwards for y); on a log axis log10(v) does.
inline constexpr double kChartLeft = 72, kChartRight = 16, kChartTop = 40, kChartBottom = 52;
[[nodiscard]] double legend_width(const std::vector<Series>& series);

// Ticks at multiples of the step 1, 2 or 5 × 10^k that gives about `target` intervals over [lo, hi], from the
// largest multiple <= lo to the smallest >= hi, each the double nearest to the exact decimal (0.6, not
// 0.6000000000000001). lo == hi is widened to lo ± 1 (lo ± |lo|/10 when lo != 0); non-finite bounds give 0..1; a
// range too wide or too fine for doubles to step through gives {lo, hi}.
[[nodiscard]] std::vector<double> nice_ticks(double lo, double hi, int target = 5);
// Decades 10^a … 10^b with 10^a <= lo and 10^b >= hi (at least two; over more than 8 decades every k-th, the
// smallest k that leaves at most 8 intervals, a and b multiples of k), within 1e-300 … 1e300; requires 0 < lo <= hi,
// else 1, 10.
[[nodiscard]] std::vector<double> log_ticks(double lo, double hi);
// Tick labels with as many decimals as the step needs ("0.2", "10", "1e-05" on a log axis).
[[nodiscard]] std::vector<std::string> tick_labels(const std::vector<double>& ticks, bool log);

// The colour of series k of n as "#rrggbb" (Categorical: the 8 colours repeat; line charts draw the repeats dashed).
[[nodiscard]] std::string series_colour(Palette palette, std::size_t k, std::size_t n);

// &, <, >, " and ' as entities: for SVG and HTML text and attribute values.
[[nodiscard]] std::string xml_escape(const std::string& text);

[[nodiscard]] std::string line_chart_svg(const std::vector<Series>& series, const ChartOptions& options);
// One group of bars per category, one bar per series in each group (series[s].y[c]; NaN: no bar). options.x_ticks
// is unused; the y axis is linear from 0 or, with log_y, decades.
[[nodiscard]] std::string grouped_bar_chart_svg(const std::vector<std::string>& categories,
                                                const std::vector<Series>& series, const ChartOptions& options);
// Charts made by the two functions above in one SVG, left to right (each keeps its own size); `title` is the
// outer SVG's <title>. Throws std::invalid_argument on text that is not such a chart.
[[nodiscard]] std::string side_by_side_svg(const std::vector<std::string>& charts, const std::string& title);

// Counts of the values in the bins [start + k·width, start + (k+1)·width), k < bins; finite values outside them are
// counted in `outside`, NaNs nowhere. Throws std::invalid_argument unless width > 0.
struct Histogram {
  double start = 0, width = 1;
  std::vector<int> counts{};
  int outside = 0;
  [[nodiscard]] double centre(std::size_t k) const { return start + (static_cast<double>(k) + 0.5) * width; }
};
[[nodiscard]] Histogram histogram(const std::vector<double>& values, double start, double width, std::size_t bins);

}  // namespace probecomp::io
