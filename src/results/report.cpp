#include "probecomp/results/report.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "probecomp/io/charts.hpp"  // xml_escape
#include "probecomp/io/format.hpp"
#include "probecomp/io/json.hpp"
#include "probecomp/version.hpp"
#include "report_view.hpp"  // generated from src/results/report_view.js

namespace probecomp::results {

using io::fmt;
using io::Json;
using io::json_fixed;
using io::json_text;
using io::xml_escape;

namespace {

using compensation::CompensatedPoint;
using compensation::PointStatus;

std::string mm4(double v) { return fmt("%.4f", v); }
std::string mm6(double v) { return fmt("%.6f", v); }

// A histogram as inline SVG. `values` and `band` (shaded, the bars with a value outside it in red) in the unit
// named by `unit`.
std::string histogram_svg(const std::vector<double>& values, const std::optional<std::pair<double, double>>& band,
                          const std::string& unit, const std::string& label) {
  constexpr int kBins = 40;
  constexpr double kWidth = 640, kHeight = 240, kLeft = 50, kBottom = 34, kTop = 10, kRight = 16;
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kWidth << "\" height=\"" << kHeight
    << "\" role=\"img\" aria-label=\"" << xml_escape(label) << "\">\n";
  if (values.empty()) {
    s << "<text x=\"10\" y=\"20\">no trusted points</text></svg>\n";
    return s.str();
  }
  double lo = *std::min_element(values.begin(), values.end()), hi = *std::max_element(values.begin(), values.end());
  if (band) {
    lo = std::min(lo, band->first);
    hi = std::max(hi, band->second);
  }
  if (!(hi > lo)) {
    lo -= 0.5;
    hi += 0.5;
  }
  const double width = (hi - lo) / kBins;
  std::vector<int> count(kBins, 0), outside(kBins, 0);
  for (double x : values) {
    const auto b = static_cast<std::size_t>(std::clamp(static_cast<int>((x - lo) / width), 0, kBins - 1));
    ++count[b];
    if (band && (x < band->first || x > band->second)) ++outside[b];
  }
  const int most = *std::max_element(count.begin(), count.end());
  const double plot_w = kWidth - kLeft - kRight, plot_h = kHeight - kTop - kBottom;
  auto x_of = [&](double v) { return kLeft + plot_w * (v - lo) / (hi - lo); };
  if (band) {
    s << "<rect x=\"" << fmt("%.1f", x_of(band->first)) << "\" y=\"" << kTop << "\" width=\""
      << fmt("%.1f", x_of(band->second) - x_of(band->first)) << "\" height=\"" << plot_h
      << "\" fill=\"#e3f2e3\"><title>tolerance band " << fmt("%.2f", band->first) << " to " << fmt("%.2f", band->second)
      << " " << unit << "</title></rect>\n";
  }
  for (std::size_t b = 0; b < count.size(); ++b) {
    if (count[b] == 0) continue;
    const double h = std::max(plot_h * count[b] / most, 1.0);
    s << "<rect x=\"" << fmt("%.1f", kLeft + plot_w * double(b) / kBins) << "\" y=\"" << fmt("%.1f", kTop + plot_h - h)
      << "\" width=\"" << fmt("%.1f", plot_w / kBins - 1) << "\" height=\"" << fmt("%.1f", h) << "\" fill=\""
      << (outside[b] > 0 ? "#c62828" : "#1f6fb2") << "\"><title>" << fmt("%.2f", lo + double(b) * width) << " to "
      << fmt("%.2f", lo + double(b + 1) * width) << " " << unit << ": " << count[b] << " points</title></rect>\n";
  }
  s << "<line x1=\"" << kLeft << "\" y1=\"" << kTop + plot_h << "\" x2=\"" << kWidth - kRight << "\" y2=\""
    << kTop + plot_h << "\" stroke=\"#333\"/>\n";
  for (int t = 0; t <= 4; ++t) {
    const double v = lo + (hi - lo) * t / 4;
    s << "<text x=\"" << fmt("%.1f", x_of(v)) << "\" y=\"" << kHeight - 18 << "\" font-size=\"11\" "
      << "text-anchor=\"" << (t == 0 ? "start" : t == 4 ? "end" : "middle") << "\">" << fmt("%.2f", v) << "</text>\n";
  }
  s << "<text x=\"" << kLeft + plot_w / 2 << "\" y=\"" << kHeight - 3 << "\" font-size=\"11\" text-anchor=\"middle\">"
    << xml_escape(label) << " (" << unit << ")</text>\n<text x=\"4\" y=\"" << kTop + 10 << "\" font-size=\"11\">" << most
    << "</text>\n</svg>\n";
  return s.str();
}

bool finite(const Point3& p) { return p.allFinite(); }

// The 3-D view's data, as JSON read by report_view.js: coordinates (mm, relative to `origin`, to 1 µm), deviation
// and u (µm, null where not computed), status (index into kPointStatuses), input row, the colour bar's range, the
// labelled points and the nominal outlines.
std::string view_json(const compensation::CompensationResult& r, const ReportContext& c, std::string& caption) {
  const std::vector<CompensatedPoint>& pts = r.points;
  const std::size_t n = pts.size();
  std::vector<std::size_t> drawable;
  for (std::size_t k = 0; k < n; ++k) {
    if (finite(pts[k].contact)) drawable.push_back(k);
  }
  // The points labelled: the trusted ones of largest |deviation| (the earlier row first among equals), each at least
  // a fifteenth of the points' extent from those labelled before it, so that one dent does not take every label.
  std::vector<std::size_t> ok;
  BoundingBox extent;
  for (std::size_t k : drawable) {
    extent.extend(pts[k].contact);
    if (pts[k].status == PointStatus::Ok && std::isfinite(pts[k].deviation)) ok.push_back(k);
  }
  std::sort(ok.begin(), ok.end(), [&](std::size_t a, std::size_t b) {
    const double da = std::abs(pts[a].deviation), db = std::abs(pts[b].deviation);
    return da != db ? da > db : a < b;
  });
  const double apart = drawable.empty() ? 0.0 : (extent.max - extent.min).norm() / 15.0;
  std::vector<std::size_t> worst;
  for (std::size_t k : ok) {
    if (worst.size() >= static_cast<std::size_t>(std::max(c.labelled_worst, 0))) break;
    const bool far = std::all_of(worst.begin(), worst.end(),
                                 [&](std::size_t w) { return (pts[w].contact - pts[k].contact).norm() >= apart; });
    if (far) worst.push_back(k);
  }
  // The colour bar: the tolerance band, else ±(99th percentile of the trusted |deviation|) so that one stray point
  // does not wash the map out; beyond it the map's darkest ends.
  std::pair<double, double> range{-1.0, 1.0};
  if (c.tolerance) {
    range = {1000.0 * c.tolerance->lower, 1000.0 * c.tolerance->upper};
    caption = "Colour bar: the tolerance band";
  } else {
    std::vector<double> a;
    for (std::size_t k : ok) a.push_back(1000.0 * std::abs(pts[k].deviation));
    double q = 1.0;
    if (!a.empty()) {
      const auto at = static_cast<std::size_t>(std::floor(0.99 * double(a.size() - 1)));
      std::nth_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(at), a.end());
      q = std::max(a[at], 0.1);
    }
    range = {-q, q};
    caption = "Colour bar: &plusmn;" + fmt("%.2f", q) + " &micro;m, 99 % of the trusted points' |deviation|";
  }
  // Every k-th drawable row, and the labelled ones.
  const std::size_t cap = std::max<std::size_t>(c.max_view_points, 1);
  const std::size_t stride = (drawable.size() + cap - 1) / cap;
  std::vector<std::size_t> shown;
  for (std::size_t i = 0; i < drawable.size(); ++i) {
    const std::size_t k = drawable[i];
    if (stride <= 1 || i % stride == 0 || std::find(worst.begin(), worst.end(), k) != worst.end()) shown.push_back(k);
  }
  if (shown.size() < drawable.size()) {
    caption += "; every " + std::to_string(stride) + "th of " + std::to_string(drawable.size()) + " points drawn (" +
               std::to_string(shown.size()) + "), the tables use them all";
  }
  Point3 origin = Point3::Zero();
  for (std::size_t k : shown) origin += pts[k].contact;
  if (!shown.empty()) origin /= static_cast<double>(shown.size());

  // Flat x, y, z triples, as report_view.js reads them.
  const auto coord = [&](Json& to, const Point3& q) {
    for (int a = 0; a < 3; ++a) to.push_back(json_fixed(q[a] - origin[a], 3));
  };
  const auto micro = [](double v) { return json_fixed(1000.0 * v, 2); };
  Json p = Json::array(), row = Json::array(), s = Json::array(), d = Json::array(), u = Json::array();
  double u_max = 0.0;
  for (std::size_t k : shown) {
    coord(p, pts[k].contact);
    row.push_back(k + 1);
    s.push_back(static_cast<int>(pts[k].status));
    d.push_back(micro(pts[k].computed() ? pts[k].deviation : std::numeric_limits<double>::quiet_NaN()));
    u.push_back(micro(pts[k].uncertainty));
    if (std::isfinite(pts[k].uncertainty)) u_max = std::max(u_max, 1000.0 * pts[k].uncertainty);
  }
  Json statuses = Json::array(), status_counts = Json::array();
  for (const PointStatus st : compensation::kPointStatuses) {
    statuses.push_back(compensation::to_string(st));
    status_counts.push_back(r.count(st));
  }
  Json labelled = Json::array();
  for (std::size_t k : worst) labelled.push_back(std::lower_bound(shown.begin(), shown.end(), k) - shown.begin());
  Json lines = Json::array();
  for (const cad::Polyline& l : c.nominal) {
    Json line = Json::array();
    for (const Point3& q : l) coord(line, q);
    lines.push_back(line);
  }
  // Each evaluated characteristic's drawn points: their place in the view's arrays, deviation in its frame and U (µm),
  // and its zone's limits (µm), for colouring by a chosen characteristic.
  Json characteristics = Json::array();
  if (c.inspection != nullptr) {
    for (const inspection::CharacteristicResult& ch : c.inspection->characteristics) {
      if (ch.decision == inspection::Decision::NotEvaluated) continue;
      Json at = Json::array(), dev = Json::array(), U = Json::array();
      for (const inspection::JudgedPoint& j : ch.judged) {
        const auto it = std::lower_bound(shown.begin(), shown.end(), j.row);
        if (it == shown.end() || *it != j.row) continue;
        at.push_back(it - shown.begin());
        dev.push_back(micro(j.deviation));
        U.push_back(micro(j.U));
      }
      characteristics.push_back({{"name", ch.spec.name},
                                 {"zone", {micro(ch.outside - ch.spec.tolerance), micro(ch.outside)}},
                                 {"k", at},
                                 {"d", dev},
                                 {"U", U}});
    }
  }
  const Json view = {{"total", n},
                     {"origin", {json_fixed(origin.x(), 9), json_fixed(origin.y(), 9), json_fixed(origin.z(), 9)}},
                     {"p", p},
                     {"row", row},
                     {"s", s},
                     {"d", d},
                     {"u", u},
                     {"u_max", json_fixed(u_max > 0.0 ? u_max : 1.0, 2)},
                     {"dev_range", {json_fixed(range.first, 2), json_fixed(range.second, 2)}},
                     {"statuses", statuses},
                     {"status_counts", status_counts},
                     {"worst", labelled},
                     {"lines", lines},
                     {"characteristics", characteristics}};
  // Inside <script>, "</script>" or "<!--" in a name (a characteristic's, from the specification or the CAD file)
  // would end or upset the element: every '<' as its JSON escape, which only strings hold.
  const std::string text = json_text(view, -1);
  std::string safe;
  safe.reserve(text.size());
  for (const char ch : text) {
    if (ch == '<') {
      safe += "\\u003c";
    } else {
      safe += ch;
    }
  }
  return safe;
}

// The view's "characteristic" colouring and its choice among the evaluated ones (in their order); nothing without any.
std::string characteristic_choice(const inspection::Inspection* in) {
  if (in == nullptr) return {};
  std::string options;
  int index = 0;
  for (const inspection::CharacteristicResult& ch : in->characteristics) {
    if (ch.decision == inspection::Decision::NotEvaluated) continue;
    options += "<option value=\"" + std::to_string(index++) + "\">" + xml_escape(ch.spec.name) + "</option>";
  }
  if (options.empty()) return {};
  return " <label><input type=\"radio\" name=\"colour\" value=\"characteristic\"> deviation in the frame and zone "
         "of</label> <select id=\"view-characteristic\">" + options + "</select>";
}

std::string joined(const std::vector<int>& v) {
  std::string out;
  for (int x : v) out += (out.empty() ? "" : ", ") + std::to_string(x);
  return out;
}

// The drawing's characteristics and the datums their frames fitted (DESIGN.md section 7): the tables of --json's
// "characteristics" and "datums".
void characteristics_section(std::ostream& h, const inspection::Inspection& in) {
  h << "<h2>Characteristics</h2>\n<p class=\"note\">Each judged on the trusted points of its faces in its datum "
       "reference frame (the motions its datums leave free best-fitted to its own points); the decision per ISO "
       "14253-1 with U = 2u, u including the datums' share."
    << (in.alignment.empty() ? std::string() : " The deviations of this report are in datum frame " + xml_escape(in.alignment) + ".")
    << "</p>\n<table id=\"characteristics\"><tr><th class=\"l\">name</th><th class=\"l\">type</th><th>faces</th>"
       "<th>datums</th><th>tolerance (mm)</th><th>outside (mm)</th><th>points</th><th>min (mm)</th><th>max (mm)</th>"
       "<th>value (mm)</th><th>U (mm)</th><th class=\"l\">decision</th></tr>\n";
  for (const inspection::CharacteristicResult& c : in.characteristics) {
    std::string frame;
    for (const std::string& d : c.spec.datums) frame += (frame.empty() ? "" : "|") + d;
    const bool evaluated = c.decision != inspection::Decision::NotEvaluated;
    const char* mark = c.decision == inspection::Decision::DoesNotConform ? " class=\"l fail\""
                       : c.decision == inspection::Decision::Conforms     ? " class=\"l\""
                                                                          : " class=\"l warn\"";
    h << "<tr><td class=\"l\">" << xml_escape(c.spec.name) << "</td><td class=\"l\">" << xml_escape(c.spec.type)
      << "</td><td>" << joined(c.spec.faces) << "</td><td>" << xml_escape(frame) << "</td><td>" << mm4(c.spec.tolerance)
      << "</td><td>" << mm4(c.outside) << "</td><td>" << c.points << "</td>";
    if (evaluated) {
      h << "<td>" << mm4(c.min) << "</td><td>" << mm4(c.max) << "</td><td>" << mm4(c.value) << "</td><td>" << mm4(c.u)
        << "</td>";
    } else {
      h << "<td></td><td></td><td></td><td></td>";
    }
    h << "<td" << mark << ">" << inspection::to_string(c.decision)
      << (c.reason.empty() ? std::string() : ": " + xml_escape(c.reason)) << "</td></tr>\n";
  }
  h << "</table>\n";
  if (in.datums.empty()) return;
  h << "<table id=\"datums\"><caption>Datums as their frames fitted them</caption><tr><th class=\"l\">datum</th>"
       "<th>frame</th><th class=\"l\">fit</th><th>faces</th><th>points</th><th>motions fixed</th><th>RMS (mm)</th>"
       "<th>size change (mm)</th></tr>\n";
  for (const inspection::FrameDatum& f : in.datums) {
    const inspection::DatumResult& d = f.datum;
    h << "<tr><td class=\"l\">" << xml_escape(d.name) << "</td><td>" << xml_escape(f.frame) << "</td><td class=\"l\">"
      << inspection::to_string(d.fit) << "</td><td>" << joined(d.faces) << "</td><td>" << d.points << "</td><td>"
      << d.fixes << "</td><td>" << mm6(d.rms) << "</td><td>" << (d.size_change ? mm6(*d.size_change) : std::string())
      << "</td></tr>\n";
  }
  h << "</table>\n";
}

}  // namespace

std::vector<cad::Polyline> registered_outline(const cad::Model& model, const geometry::RigidTransform& cad_to_machine,
                                              std::size_t max_points) {
  auto outline = [&](int isolines) {
    std::vector<cad::Polyline> lines;
    for (const cad::Face& f : model.faces) {
      for (cad::Polyline& l : cad::face_outline(f, {.isolines = isolines})) lines.push_back(std::move(l));
    }
    return lines;
  };
  auto points = [](const std::vector<cad::Polyline>& lines) {
    std::size_t total = 0;
    for (const cad::Polyline& l : lines) total += l.size();
    return total;
  };
  std::vector<cad::Polyline> lines = outline(cad::OutlineOptions{}.isolines);
  if (points(lines) > max_points) lines = outline(0);
  // Still too many (a model of thousands of faces): every k-th point of each line, its ends kept, k the smallest
  // that keeps to the budget (every line keeps its two ends whatever k).
  auto thinned_size = [&](std::size_t k) {
    std::size_t total = 0;
    for (const cad::Polyline& l : lines) total += l.size() < 2 ? l.size() : (l.size() - 2) / k + 2;
    return total;
  };
  std::size_t stride = 1;
  while (thinned_size(stride) > max_points && thinned_size(stride + 1) < thinned_size(stride)) ++stride;
  if (stride > 1) {
    for (cad::Polyline& l : lines) {
      cad::Polyline thin;
      for (std::size_t i = 0; i < l.size(); ++i) {
        if (i % stride == 0 || i + 1 == l.size()) thin.push_back(l[i]);
      }
      l = std::move(thin);
    }
  }
  for (cad::Polyline& l : lines) {
    for (Point3& p : l) p = cad_to_machine * p;
  }
  return lines;
}

std::string html_report(const compensation::CompensationResult& r, const ReportContext& c) {
  const DeviationSummaries dev = summarise_deviations(r, c.tolerance);
  std::vector<double> trusted_um;
  for (const CompensatedPoint& p : r.points) {
    if (p.status == PointStatus::Ok) trusted_um.push_back(1000.0 * p.deviation);
  }
  const RunInputs& in = c.inputs;
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>probecomp report: "
    << xml_escape(in.points) << "</title>\n<style>"
       "body{font-family:sans-serif;margin:1.5em;color:#222;max-width:1400px}"
       "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #bbb;padding:2px 8px;text-align:right}"
       "th{background:#eee}td.l,th.l{text-align:left}.fail{color:#c62828;font-weight:bold}.warn{color:#8a5a00}"
       "#view{border:1px solid #ccc;cursor:grab;display:block;touch-action:none}#view-box{width:100%}.note{color:#555;font-size:90%}"
       "</style></head><body>\n";
  h << "<h1>probecomp: " << compensation::to_string(r.method) << " compensation</h1>\n";
  // The inputs.
  h << "<table id=\"inputs\"><tr><th class=\"l\">CAD</th><td class=\"l\">" << xml_escape(in.cad)
    << "</td></tr><tr><th class=\"l\">points</th><td class=\"l\">" << xml_escape(in.points) << " (" << r.points.size()
    << " rows, lengths in " << in.points_unit.name << ")</td></tr><tr><th class=\"l\">tip radii (mm)</th><td class=\"l\">";
  for (std::size_t k = 0; k < in.tip_radii.size(); ++k) h << (k ? ", " : "") << fmt("%.9g", in.tip_radii[k]);
  h << "</td></tr><tr><th class=\"l\">tolerance (mm)</th><td class=\"l\">"
    << (c.tolerance ? mm4(c.tolerance->lower) + " to " + mm4(c.tolerance->upper) : std::string("none"))
    << "</td></tr><tr><th class=\"l\">probecomp</th><td class=\"l\">" << xml_escape(version()) << "</td></tr></table>\n";
  // Counts by status.
  h << "<h2>Points by status</h2>\n<table id=\"counts\"><tr>";
  for (PointStatus s : compensation::kPointStatuses) h << "<th>" << compensation::to_string(s) << "</th>";
  h << "<th>total</th></tr><tr>";
  for (PointStatus s : compensation::kPointStatuses) h << "<td>" << r.count(s) << "</td>";
  h << "<td>" << r.statistics.total << "</td></tr></table>\n";
  if (c.inspection != nullptr && !c.inspection->characteristics.empty()) characteristics_section(h, *c.inspection);
  // The 3-D view.
  std::string caption;
  const std::string view = view_json(r, c, caption);
  const bool any_u = std::any_of(r.points.begin(), r.points.end(), [](const CompensatedPoint& p) {
    return std::isfinite(p.uncertainty);
  });
  h << "<h2>Deviation map</h2>\n<p class=\"note\">Deviation of each compensated point from the registered nominal "
       "(+ outside the material), the nominal faces faint; the "
    << "largest |deviation| of the trusted points labelled, at up to " << c.labelled_worst
    << " places apart. " << caption
    << ". Drag to turn, shift-drag to move, wheel to zoom, double-click to reset.</p>\n"
       "<p>Colour by <label><input type=\"radio\" name=\"colour\" value=\"deviation\" checked> deviation</label> "
       "<label><input type=\"radio\" name=\"colour\" value=\"status\"> status</label> "
       "<label><input type=\"radio\" name=\"colour\" value=\"u\""
    << (any_u ? "" : " disabled") << "> uncertainty u</label>"
    << characteristic_choice(c.inspection) << "</p>\n"
    << "<div id=\"view-box\"><canvas id=\"view\" width=\"1000\" height=\"600\"></canvas></div>\n"
       "<p id=\"view-info\" class=\"note\">&nbsp;</p>\n"
       "<script type=\"application/json\" id=\"view-data\">"
    << view << "</script>\n";
  // Deviations.
  h << "<h2>Deviation of the trusted (ok) points from the registered nominal</h2>\n<table id=\"deviation\"><tr>"
       "<th>points</th><th>mean (mm)</th><th>std (mm)</th><th>min (mm)</th><th>max (mm)</th>"
    << (c.tolerance ? "<th>out of tolerance</th>" : "") << "</tr><tr><td>" << dev.all.points << "</td><td>"
    << mm6(dev.all.mean) << "</td><td>" << mm6(dev.all.std) << "</td><td>" << mm6(dev.all.min) << "</td><td>"
    << mm6(dev.all.max) << "</td>";
  if (c.tolerance) {
    h << "<td" << (dev.all.out_of_tolerance > 0 ? " class=\"fail\"" : "") << ">" << dev.all.out_of_tolerance << "</td>";
  }
  h << "</tr></table>\n<figure id=\"histogram\">"
    << histogram_svg(trusted_um,
                     c.tolerance ? std::optional(std::pair{1000.0 * c.tolerance->lower, 1000.0 * c.tolerance->upper})
                                 : std::nullopt,
                     "&#181;m", "deviation")
    << "</figure>\n";
  // The paper's point: how far the CAD-based contact point is from the conventional one.
  if (c.conventional && c.conventional->size() == r.points.size()) {
    std::vector<double> diff;
    for (std::size_t k = 0; k < r.points.size(); ++k) {
      const CompensatedPoint& p = r.points[k];
      const Point3& q = (*c.conventional)[k];
      if (p.status == PointStatus::Ok && finite(q) && p.normal.allFinite()) {
        diff.push_back(1000.0 * (p.contact - q).dot(p.normal));
      }
    }
    h << "<h2>CAD-based minus conventional compensation</h2>\n<p class=\"note\">For each trusted point: its "
         "contact point minus the conventional one (the centre moved by the tip radius against the programmed "
         "approach normal), along the normal used. This is the error the conventional method makes where the "
         "part's actual normal differs from the programmed one.</p>\n<figure id=\"difference\">"
      << histogram_svg(diff, std::nullopt, "&#181;m", "CAD-based minus conventional") << "</figure>\n";
    const DeviationSummary d = summarise(diff, std::nullopt);
    h << "<table id=\"difference-summary\"><tr><th>points</th><th>mean (&micro;m)</th><th>std (&micro;m)</th>"
         "<th>largest |difference| (&micro;m)</th></tr><tr><td>"
      << d.points << "</td><td>" << fmt("%.2f", d.mean) << "</td><td>" << fmt("%.2f", d.std) << "</td><td>"
      << fmt("%.2f", std::max(std::abs(d.min), std::abs(d.max))) << "</td></tr></table>\n";
  }
  // Faces.
  h << "<h2>Faces</h2>\n<table id=\"faces\"><tr><th>face</th><th>points</th><th>ok</th><th>mean (mm)</th>"
       "<th>std (mm)</th><th>min (mm)</th><th>max (mm)</th>"
    << (c.tolerance ? "<th>out of tolerance</th>" : "") << "<th>mean u (&micro;m)</th><th class=\"l\">fit</th></tr>\n";
  for (std::size_t f = 0; f < r.faces.size(); ++f) {
    const compensation::FaceReport& x = r.faces[f];
    const DeviationSummary& d = dev.faces[f];
    h << "<tr><td>" << x.face << "</td><td>" << x.points << "</td><td>" << d.points << "</td><td>" << mm6(d.mean)
      << "</td><td>" << mm6(d.std) << "</td><td>" << mm6(d.min) << "</td><td>" << mm6(d.max) << "</td>";
    if (c.tolerance) h << "<td" << (d.out_of_tolerance > 0 ? " class=\"fail\"" : "") << ">" << d.out_of_tolerance << "</td>";
    h << "<td>" << fmt("%.2f", 1000.0 * x.mean_uncertainty) << "</td><td class=\"l\">"
      << (x.fitted ? "fitted: " : x.fitted_as ? "" : "not fitted: ") << xml_escape(x.stop_reason) << "</td></tr>\n";
  }
  h << "</table>\n";
  // Registration.
  const registration::RegistrationResult& g = r.registration;
  h << "<h2>Registration</h2>\n<p id=\"registration\">" << registration::to_string(g.status) << ": "
    << xml_escape(g.stop_reason) << "; RMS " << mm6(g.rms) << " mm, robust scale " << mm6(g.scale) << " mm, "
    << g.inliers << " inliers, " << g.starts << " start(s)</p>\n<table id=\"transform\"><caption>CAD to machine"
    << "</caption>";
  const Eigen::Matrix4d M = g.transform.matrix();
  for (int a = 0; a < 4; ++a) {
    h << "<tr>";
    for (int b = 0; b < 4; ++b) h << "<td>" << fmt("%.9f", M(a, b)) << "</td>";
    h << "</tr>";
  }
  h << "</table>\n";
  if (!g.constraints.free.empty()) {
    h << "<p class=\"warn\" id=\"free-motions\">Motions the points do not fix, held at the start:</p><ul>";
    for (const registration::FreeMotion& m : g.constraints.free) {
      const bool turn = m.kind == registration::FreeMotion::Kind::Rotation;
      h << "<li>" << (turn ? "rotation about (" : "translation along (") << fmt("%.6f", m.direction.x()) << ", "
        << fmt("%.6f", m.direction.y()) << ", " << fmt("%.6f", m.direction.z()) << ")";
      if (turn) {
        h << " through (" << fmt("%.3f", m.through.x()) << ", " << fmt("%.3f", m.through.y()) << ", "
          << fmt("%.3f", m.through.z()) << ") mm";
      }
      h << "</li>";
    }
    h << "</ul>\n";
  }
  if (!r.warnings.empty()) {
    h << "<h2>Warnings</h2>\n<ul id=\"warnings\">";
    for (const std::string& w : r.warnings) h << "<li class=\"warn\">" << xml_escape(w) << "</li>";
    h << "</ul>\n";
  }
  const compensation::Timings& t = r.seconds;
  h << "<h2>Timings (s)</h2>\n<table id=\"timings\"><tr><th>read</th><th>prepare</th><th>register</th><th>fit</th>"
       "<th>compensate</th><th>write</th><th>total</th></tr><tr><td>"
    << fmt("%.3f", c.timings.read) << "</td><td>" << fmt("%.3f", t.prepare) << "</td><td>" << fmt("%.3f", t.registration)
    << "</td><td>" << fmt("%.3f", t.fitting) << "</td><td>" << fmt("%.3f", t.compensation) << "</td><td>"
    << fmt("%.3f", c.timings.write) << "</td><td>" << fmt("%.3f", c.timings.total) << "</td></tr></table>\n<script>" << detail::kReportViewJs
    << "</script>\n</body></html>\n";
  return h.str();
}

}  // namespace probecomp::results
