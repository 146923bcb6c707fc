#include "probecomp/io/charts.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "probecomp/io/format.hpp"

namespace probecomp::io {

namespace {

// 10^e, exact for |e| <= 22 (10^22 is the largest power of ten a double holds exactly).
double power_of_ten(int e) {
  if (e < 0) return 1.0 / power_of_ten(-e);
  if (e > 22) return std::pow(10.0, e);
  double p = 1.0;
  for (int k = 0; k < e; ++k) p *= 10.0;
  return p;
}

// k·n·10^e as the double nearest the exact decimal: one rounding (an exact product or quotient of exact integers).
double decimal(double k, int n, int e) { return e >= 0 ? k * n * power_of_ten(e) : k * n / power_of_ten(-e); }

std::string px(double v) { return fmt("%.2f", v); }
std::string number(double v) { return fmt("%.6g", v); }

// Okabe and Ito's colour-blind-safe palette, yellow last (weak on white).
constexpr std::array<const char*, 8> kOkabeIto = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                                   "#E69F00", "#56B4E9", "#000000", "#F0E442"};
// viridis at 0, 0.1, …, 1.
constexpr std::array<std::array<int, 3>, 11> kViridis = {{{0x44, 0x01, 0x54}, {0x48, 0x24, 0x75}, {0x41, 0x44, 0x87},
                                                         {0x35, 0x5F, 0x8D}, {0x2A, 0x78, 0x8E}, {0x21, 0x91, 0x8C},
                                                         {0x22, 0xA8, 0x84}, {0x44, 0xBF, 0x70}, {0x7A, 0xD1, 0x51},
                                                         {0xBD, 0xDF, 0x26}, {0xFD, 0xE7, 0x25}}};

std::size_t code_points(const std::string& s) {
  return static_cast<std::size_t>(
      std::count_if(s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

std::string svg_open(double width, double height) {
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + fmt("%g", width) + "\" height=\"" + fmt("%g", height) +
         "\" viewBox=\"0 0 " + fmt("%g", width) + " " + fmt("%g", height) +
         "\" font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"12\">\n";
}

// The plot area and the axes' ranges; maps values to pixels.
struct Frame {
  double left = 0, top = 0, right = 0, bottom = 0;
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  bool log_y = false;
  [[nodiscard]] double x(double v) const { return left + (v - x0) / (x1 - x0) * (right - left); }
  [[nodiscard]] double y(double v) const {
    if (log_y) return bottom - (std::log10(v) - std::log10(y0)) / (std::log10(y1) - std::log10(y0)) * (bottom - top);
    return bottom - (v - y0) / (y1 - y0) * (bottom - top);
  }
};

Frame frame_for(const ChartOptions& o, const std::vector<Series>& series) {
  Frame f;
  f.left = kChartLeft;
  f.top = kChartTop;
  f.right = o.width - kChartRight - legend_width(series);
  f.bottom = o.height - kChartBottom;
  f.log_y = o.log_y;
  if (f.right - f.left < 40 || f.bottom - f.top < 40) {
    throw std::invalid_argument("chart '" + o.title + "': " + fmt("%g", o.width) + " x " + fmt("%g", o.height) +
                                " leaves no room for the plot beside the legend");
  }
  return f;
}

bool drawable(double x, double y, bool log_y) { return std::isfinite(x) && std::isfinite(y) && (!log_y || y > 0); }

// Y ticks over the finite values (log: the positive ones).
std::vector<double> y_ticks(const std::vector<double>& values, const ChartOptions& o) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double v : values) {
    if (!std::isfinite(v) || (o.log_y && v <= 0)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (o.log_y) return lo <= hi ? log_ticks(lo, hi) : log_ticks(1, 10);
  if (lo > hi) lo = hi = 0;
  if (o.y_includes_zero) {
    lo = std::min(lo, 0.0);
    hi = std::max(hi, 0.0);
  }
  return nice_ticks(lo, hi);
}

// Title, y grid and labels, axis labels and the frame; the x ticks are the caller's.
void draw_axes(std::ostringstream& s, const ChartOptions& o, const Frame& f, const std::vector<double>& yt) {
  s << "<rect width=\"" << fmt("%g", o.width) << "\" height=\"" << fmt("%g", o.height) << "\" fill=\"#ffffff\"/>\n";
  if (!o.title.empty()) {
    s << "<title>" << xml_escape(o.title) << "</title>\n<text x=\"" << px(o.width / 2) << "\" y=\"22\" text-anchor=\"middle\""
      << " font-size=\"14\" font-weight=\"bold\">" << xml_escape(o.title) << "</text>\n";
  }
  const std::vector<std::string> labels = tick_labels(yt, o.log_y);
  for (std::size_t k = 0; k < yt.size(); ++k) {
    const double y = f.y(yt[k]);
    const bool zero = !o.log_y && yt[k] == 0 && k > 0 && k + 1 < yt.size();
    s << "<line x1=\"" << px(f.left) << "\" y1=\"" << px(y) << "\" x2=\"" << px(f.right) << "\" y2=\"" << px(y)
      << "\" stroke=\"" << (zero ? "#888888" : "#e4e4e4") << "\"/>\n"
      << "<text x=\"" << px(f.left - 6) << "\" y=\"" << px(y) << "\" dy=\"0.32em\" text-anchor=\"end\">" << labels[k]
      << "</text>\n";
  }
  s << "<rect x=\"" << px(f.left) << "\" y=\"" << px(f.top) << "\" width=\"" << px(f.right - f.left) << "\" height=\""
    << px(f.bottom - f.top) << "\" fill=\"none\" stroke=\"#333333\"/>\n";
  if (!o.x_label.empty()) {
    s << "<text x=\"" << px((f.left + f.right) / 2) << "\" y=\"" << px(o.height - 12) << "\" text-anchor=\"middle\">"
      << xml_escape(o.x_label) << "</text>\n";
  }
  if (!o.y_label.empty()) {
    const double cy = (f.top + f.bottom) / 2;
    s << "<text x=\"18\" y=\"" << px(cy) << "\" text-anchor=\"middle\" transform=\"rotate(-90 18 " << px(cy) << ")\">"
      << xml_escape(o.y_label) << "</text>\n";
  }
}

void draw_x_tick(std::ostringstream& s, const Frame& f, double x, const std::string& label) {
  s << "<line x1=\"" << px(x) << "\" y1=\"" << px(f.bottom) << "\" x2=\"" << px(x) << "\" y2=\"" << px(f.bottom + 5)
    << "\" stroke=\"#333333\"/>\n<text x=\"" << px(x) << "\" y=\"" << px(f.bottom + 18) << "\" text-anchor=\"middle\">"
    << xml_escape(label) << "</text>\n";
}

bool dashed(const Series& series, const ChartOptions& o, std::size_t k) {
  return series.dashed || (o.palette == Palette::Categorical && k >= kOkabeIto.size());
}

// A legend entry per named series, top to bottom beside the plot: a swatch (a line with its marker, or a square).
void draw_legend(std::ostringstream& s, const std::vector<Series>& series, const ChartOptions& o, const Frame& f,
                 bool bars) {
  if (legend_width(series) == 0) return;
  const double x = f.right + 12;
  for (std::size_t k = 0; k < series.size(); ++k) {
    if (series[k].name.empty()) continue;
    const double y = f.top + 10 + 18 * static_cast<double>(k);
    const std::string colour = series_colour(o.palette, k, series.size());
    if (bars) {
      s << "<rect x=\"" << px(x + 6) << "\" y=\"" << px(y - 6) << "\" width=\"12\" height=\"12\" fill=\"" << colour
        << "\"/>\n";
    } else {
      s << "<line x1=\"" << px(x) << "\" y1=\"" << px(y) << "\" x2=\"" << px(x + 24) << "\" y2=\"" << px(y)
        << "\" stroke=\"" << colour << "\" stroke-width=\"2\"" << (dashed(series[k], o, k) ? " stroke-dasharray=\"6 4\"" : "")
        << "/>\n";
      if (series[k].markers) {
        s << "<circle cx=\"" << px(x + 12) << "\" cy=\"" << px(y) << "\" r=\"3\" fill=\"" << colour << "\"/>\n";
      }
    }
    s << "<text x=\"" << px(x + 30) << "\" y=\"" << px(y) << "\" dy=\"0.32em\">" << xml_escape(series[k].name)
      << "</text>\n";
  }
}

}  // namespace

double legend_width(const std::vector<Series>& series) {
  std::size_t longest = 0;
  bool named = false;
  for (const Series& s : series) {
    if (s.name.empty()) continue;
    named = true;
    longest = std::max(longest, code_points(s.name));
  }
  return named ? 44 + 8 * static_cast<double>(longest) : 0;
}

std::vector<double> nice_ticks(double lo, double hi, int target) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) lo = 0, hi = 1;
  if (lo > hi) std::swap(lo, hi);
  if (lo == hi) {
    const double d = lo == 0 ? 1 : std::abs(lo) / 10;
    lo -= d;
    hi += d;
  }
  const double raw = (hi - lo) / std::max(1, target);
  if (!std::isfinite(raw) || !(raw > 0)) return {lo, hi};  // a range a double cannot step through
  int e = static_cast<int>(std::floor(std::log10(raw)));
  const double normalised = raw / power_of_ten(e);
  constexpr double slack = 1 + 1e-9;  // 0.2 / 0.1 may come out a hair above 2
  int n = normalised <= slack ? 1 : normalised <= 2 * slack ? 2 : normalised <= 5 * slack ? 5 : 10;
  if (n == 10) n = 1, ++e;
  const double step = decimal(1, n, e);
  // A bound within a billionth of a step of a multiple is that multiple (0.6 / 0.2 is 2.9999999999999996).
  const double first = std::floor(lo / step + 1e-9), last = std::ceil(hi / step - 1e-9);
  // Steps too fine for the doubles there (k + 1 == k beyond 2^53): the range as it is.
  if (!(last - first <= 10000) || !(std::abs(first) < 1e15) || !(std::abs(last) < 1e15)) return {lo, hi};
  std::vector<double> ticks;
  for (double k = first; k <= last; ++k) ticks.push_back(decimal(k, n, e) + 0.0);
  return ticks;
}

std::vector<double> log_ticks(double lo, double hi) {
  if (!(lo > 0) || !(hi >= lo) || !std::isfinite(hi)) return {1, 10};
  lo = std::max(lo, 1e-300);  // (their decades stay normal doubles)
  hi = std::clamp(hi, lo, 1e300);
  int a = static_cast<int>(std::floor(std::log10(lo)));
  if (power_of_ten(a + 1) <= lo) ++a;
  if (power_of_ten(a) > lo) --a;
  int b = static_cast<int>(std::ceil(std::log10(hi)));
  if (power_of_ten(b - 1) >= hi) --b;
  if (power_of_ten(b) < hi) ++b;
  if (b == a) ++b;
  // Over more than 8 decades every stride-th, from a multiple of the stride.
  const int stride = (b - a + 7) / 8;
  auto floor_multiple = [stride](int e) { return (e >= 0 ? e / stride : -((-e + stride - 1) / stride)) * stride; };
  a = floor_multiple(a);
  if (floor_multiple(b) != b) b = floor_multiple(b) + stride;
  std::vector<double> ticks;
  for (int k = a; k <= b; k += stride) ticks.push_back(power_of_ten(k));
  return ticks;
}

std::vector<std::string> tick_labels(const std::vector<double>& ticks, bool log) {
  std::vector<std::string> labels;
  int decimals = -1;  // %g
  if (!log && ticks.size() > 1) {
    const double step = std::abs(ticks[1] - ticks[0]);
    const int d = std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)));
    double largest = 0;
    for (double t : ticks) largest = std::max(largest, std::abs(t));
    if (d <= 6 && largest < 1e7) decimals = d;
  }
  for (double t : ticks) {
    labels.push_back(decimals < 0 ? fmt("%g", t) : fmt(("%." + std::to_string(decimals) + "f").c_str(), t));
  }
  return labels;
}

std::string series_colour(Palette palette, std::size_t k, std::size_t n) {
  if (palette == Palette::Categorical) return kOkabeIto[k % kOkabeIto.size()];
  // viridis over [0, 0.9] (its yellow end is too light on white).
  const double t = n > 1 ? 0.9 * static_cast<double>(k) / static_cast<double>(n - 1) : 0.0;
  const double at = t * 10;
  const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(at), kViridis.size() - 2);
  const double w = at - static_cast<double>(i);
  std::string colour = "#";
  for (int c = 0; c < 3; ++c) {
    const double v = (1 - w) * kViridis[i][c] + w * kViridis[i + 1][c];
    const int byte = std::clamp(static_cast<int>(std::lround(v)), 0, 255);
    const char* hex = "0123456789ABCDEF";
    colour += hex[byte / 16];
    colour += hex[byte % 16];
  }
  return colour;
}

std::string xml_escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string line_chart_svg(const std::vector<Series>& series, const ChartOptions& o) {
  Frame f = frame_for(o, series);
  std::vector<double> xs, ys;
  for (const Series& s : series) {
    if (s.x.size() != s.y.size()) {
      throw std::invalid_argument("chart '" + o.title + "': series '" + s.name + "' has " + std::to_string(s.x.size()) +
                                  " x and " + std::to_string(s.y.size()) + " y values");
    }
    for (std::size_t k = 0; k < s.x.size(); ++k) {
      if (!drawable(s.x[k], s.y[k], o.log_y)) continue;
      xs.push_back(s.x[k]);
      ys.push_back(s.y[k]);
    }
  }
  std::vector<double> xt = o.x_ticks;
  if (xt.size() < 2 || !(xt.front() < xt.back())) {
    const auto [lo, hi] = std::minmax_element(xs.begin(), xs.end());
    xt = xs.empty() ? nice_ticks(0, 1) : nice_ticks(*lo, *hi);
  }
  const std::vector<double> yt = y_ticks(ys, o);
  f.x0 = xt.front();
  f.x1 = xt.back();
  f.y0 = yt.front();
  f.y1 = yt.back();

  std::ostringstream s;
  s << svg_open(o.width, o.height);
  draw_axes(s, o, f, yt);
  const std::vector<std::string> xl = tick_labels(xt, false);
  for (std::size_t k = 0; k < xt.size(); ++k) draw_x_tick(s, f, f.x(xt[k]), xl[k]);

  for (std::size_t k = 0; k < series.size(); ++k) {
    const Series& line = series[k];
    const std::string colour = series_colour(o.palette, k, series.size());
    s << "<g>\n";
    // One polyline per run of drawable points; a lone point without markers gets a dot of its own.
    std::vector<std::size_t> run;
    auto flush = [&] {
      if (run.size() >= 2) {
        s << "<polyline fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"1.5\" stroke-linejoin=\"round\""
          << (dashed(line, o, k) ? " stroke-dasharray=\"6 4\"" : "") << " points=\"";
        for (std::size_t i = 0; i < run.size(); ++i) {
          s << (i ? " " : "") << px(f.x(line.x[run[i]])) << ',' << px(f.y(line.y[run[i]]));
        }
        s << "\"/>\n";
      } else if (run.size() == 1 && !line.markers) {
        s << "<circle cx=\"" << px(f.x(line.x[run[0]])) << "\" cy=\"" << px(f.y(line.y[run[0]])) << "\" r=\"1.5\" fill=\""
          << colour << "\"/>\n";
      }
      run.clear();
    };
    for (std::size_t i = 0; i < line.x.size(); ++i) {
      if (drawable(line.x[i], line.y[i], o.log_y)) {
        run.push_back(i);
      } else {
        flush();
      }
    }
    flush();
    if (line.markers) {
      for (std::size_t i = 0; i < line.x.size(); ++i) {
        if (!drawable(line.x[i], line.y[i], o.log_y)) continue;
        s << "<circle cx=\"" << px(f.x(line.x[i])) << "\" cy=\"" << px(f.y(line.y[i])) << "\" r=\"3\" fill=\"" << colour
          << "\"><title>" << xml_escape(line.name) << ": " << xml_escape(o.x_label.empty() ? "x" : o.x_label) << " = "
          << number(line.x[i]) << ", " << xml_escape(o.y_label.empty() ? "y" : o.y_label) << " = " << number(line.y[i])
          << "</title></circle>\n";
      }
    }
    s << "</g>\n";
  }
  draw_legend(s, series, o, f, false);
  s << "</svg>\n";
  return s.str();
}

std::string grouped_bar_chart_svg(const std::vector<std::string>& categories, const std::vector<Series>& series,
                                  const ChartOptions& o) {
  Frame f = frame_for(o, series);
  std::vector<double> values;
  for (const Series& s : series) {
    if (s.y.size() != categories.size()) {
      throw std::invalid_argument("chart '" + o.title + "': series '" + s.name + "' has " + std::to_string(s.y.size()) +
                                  " values for " + std::to_string(categories.size()) + " categories");
    }
    values.insert(values.end(), s.y.begin(), s.y.end());
  }
  ChartOptions yo = o;
  yo.y_includes_zero = true;  // bars stand on 0
  const std::vector<double> yt = y_ticks(values, yo);
  f.y0 = yt.front();
  f.y1 = yt.back();

  std::ostringstream s;
  s << svg_open(o.width, o.height);
  draw_axes(s, o, f, yt);
  const double group = (f.right - f.left) / static_cast<double>(std::max<std::size_t>(1, categories.size()));
  const double bar = 0.8 * group / static_cast<double>(std::max<std::size_t>(1, series.size()));
  for (std::size_t c = 0; c < categories.size(); ++c) {
    draw_x_tick(s, f, f.left + (static_cast<double>(c) + 0.5) * group, categories[c]);
  }
  const double base = o.log_y ? f.bottom : f.y(0);
  for (std::size_t k = 0; k < series.size(); ++k) {
    const std::string colour = series_colour(o.palette, k, series.size());
    s << "<g fill=\"" << colour << "\">\n";
    for (std::size_t c = 0; c < categories.size(); ++c) {
      const double v = series[k].y[c];
      if (!drawable(0, v, o.log_y)) continue;
      const double top = f.y(v);
      const double x = f.left + static_cast<double>(c) * group + 0.1 * group + static_cast<double>(k) * bar;
      s << "<rect x=\"" << px(x) << "\" y=\"" << px(std::min(top, base)) << "\" width=\"" << px(bar) << "\" height=\""
        << px(std::abs(base - top)) << "\"><title>" << xml_escape(series[k].name) << ", " << xml_escape(categories[c])
        << ": " << number(v) << "</title></rect>\n";
    }
    s << "</g>\n";
  }
  draw_legend(s, series, o, f, true);
  s << "</svg>\n";
  return s.str();
}

std::string side_by_side_svg(const std::vector<std::string>& charts, const std::string& title) {
  static const std::string open = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"";
  double width = 0, height = 0;
  std::ostringstream body;
  for (const std::string& chart : charts) {
    const std::size_t end_of_open = chart.find('>');
    const std::size_t close = chart.rfind("</svg>");
    if (chart.compare(0, open.size(), open) != 0 || end_of_open == std::string::npos || close == std::string::npos ||
        close < end_of_open) {
      throw std::invalid_argument("side_by_side_svg: not a chart of line_chart_svg or grouped_bar_chart_svg");
    }
    const char* p = chart.c_str() + open.size();
    char* after = nullptr;
    const double w = std::strtod(p, &after);
    static const std::string height_attribute = "\" height=\"";
    if (after == p || chart.compare(static_cast<std::size_t>(after - chart.c_str()), height_attribute.size(),
                                    height_attribute) != 0) {
      throw std::invalid_argument("side_by_side_svg: a chart without its width and height");
    }
    const double h = std::strtod(after + height_attribute.size(), nullptr);
    body << "<g transform=\"translate(" << fmt("%g", width) << " 0)\">"
         << chart.substr(end_of_open + 1, close - end_of_open - 1) << "</g>\n";
    width += w;
    height = std::max(height, h);
  }
  return svg_open(width, height) + (title.empty() ? "" : "<title>" + xml_escape(title) + "</title>\n") + body.str() +
         "</svg>\n";
}

Histogram histogram(const std::vector<double>& values, double start, double width, std::size_t bins) {
  if (!(width > 0) || !std::isfinite(width)) throw std::invalid_argument("histogram: the bin width must be positive");
  Histogram h{.start = start, .width = width, .counts = std::vector<int>(bins, 0), .outside = 0};
  for (double v : values) {
    if (std::isnan(v)) continue;
    const double k = std::floor((v - start) / width);
    if (k >= 0 && k < static_cast<double>(bins)) {
      ++h.counts[static_cast<std::size_t>(k)];
    } else {
      ++h.outside;
    }
  }
  return h;
}

}  // namespace probecomp::io
