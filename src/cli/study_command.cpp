// probecomp study NAME: the paper's studies (DESIGN.md §3), each printing a table beside the paper's figures and
// writing DIR/NAME.csv (the series), DIR/NAME.json (the summary), its figures as SVG (DIR/NAME*.svg) and
// DIR/NAME.section.html (heading, what the paper's figure or table shows, the figures inlined, ours beside the
// paper's numbers), then DIR/index.html: one self-contained page of the sections of every study run into DIR.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "cli/study_output.hpp"
#include "probecomp/geometry/stopwatch.hpp"
#include "probecomp/io/charts.hpp"
#include "probecomp/io/format.hpp"
#include "probecomp/io/json.hpp"
#include "probecomp/io/output_files.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/studies/analytic_cylinder.hpp"
#include "probecomp/studies/cylinder_study.hpp"
#include "probecomp/studies/freeform_study.hpp"
#include "probecomp/studies/registration_study.hpp"

namespace probecomp::cli {

const std::vector<std::string> kStudyNames = {"analytic-cylinder", "approach-angle", "registration",
                                              "cylinder-misalignment", "cylinder-deformation", "freeform"};

namespace {

using namespace study;

registration::RegistrationOptions registration_options(const std::string& metric, const std::string& loss) {
  registration::RegistrationOptions o;
  o.metric = metric == "point-to-point" ? registration::Metric::PointToPoint : registration::Metric::PointToPlane;
  o.robust.loss = loss == "none"      ? registration::RobustLoss::None
                  : loss == "huber"   ? registration::RobustLoss::Huber
                  : loss == "trimmed" ? registration::RobustLoss::Trimmed
                                      : registration::RobustLoss::Cauchy;
  return o;
}

io::Json json_pose_error(const studies::PoseError& e) {
  io::Json out = io::Json::object();
  for (std::size_t c = 0; c < 6; ++c) out[studies::kPoseComponents[c]] = io::json_number(e[c], 7);
  return out;
}

io::Json json_statistics(const studies::ErrorStatistics& s) {
  return {{"std", json_pose_error(s.std)}, {"mean", json_pose_error(s.mean)}, {"ci95", json_pose_error(s.ci95)}};
}

int run_study_registration(const StudyArgs& a) {
  studies::RegistrationStudyOptions options = a.registration;
  options.registration = registration_options(a.metric, a.loss);
  options.seed = a.seed;
  if (a.noise.size() > 1) throw std::invalid_argument("study registration: one --noise level, not a list");
  if (!a.noise.empty()) options.noise = a.noise.front();
  const std::string& output_dir = a.output_dir;
  const geometry::Stopwatch clock;
  const studies::RegistrationStudyResult r = studies::run_registration_study(options);
  const double seconds = clock.seconds();
  const studies::PaperTable1 paper = studies::paper_table1();

  std::ostringstream t;
  t << "Registration accuracy (paper §5.1, Table 1): cube corner of three 20 mm squares, " << r.points
    << " points offset " << options.probe_radius << " mm along the normal, noise sigma " << options.noise << " mm,\n"
    << options.trials << " random misalignments (+-" << options.max_translation << " mm, +-" << options.max_rotation
    << " deg per axis); " << registration::to_string(options.registration.metric) << " ICP, "
    << registration::to_string(options.registration.robust.loss) << " weights. Converged: proposed "
    << r.proposed.converged << "/" << options.trials << ", conventional " << r.conventional.converged << "/"
    << options.trials << ".\n"
    << "Error = estimated minus true pose; rotations in degrees, translations in mm.\n\n";
  char line[256];
  std::snprintf(line, sizeof line, "%-24s %12s %12s %12s %12s %12s %12s\n", "", "rx (deg)", "ry (deg)", "rz (deg)",
                "tx (mm)", "ty (mm)", "tz (mm)");
  t << line;
  auto row = [&](const char* label, const studies::PoseError& e, bool ours) {
    std::snprintf(line, sizeof line, "%-24s", label);
    t << line;
    for (double v : e) {
      std::snprintf(line, sizeof line, ours ? " %12.3e" : " %12.4f", v + 0.0);
      t << line;
    }
    t << "\n";
  };
  const std::pair<const char*, studies::PoseError studies::ErrorStatistics::*> blocks[] = {
      {"Standard deviation of the registration error", &studies::ErrorStatistics::std},
      {"Mean registration error", &studies::ErrorStatistics::mean},
      {"95 % confidence half-width of the mean (t.s/sqrt(n); the paper's row is about 0.62 x its std)",
       &studies::ErrorStatistics::ci95}};
  for (const auto& [title, member] : blocks) {
    t << title << "\n";
    row("  proposed (probecomp)", r.proposed.stats.*member, true);
    row("  proposed (paper)", paper.proposed.*member, false);
    row("  conventional (probecomp)", r.conventional.stats.*member, true);
    row("  conventional (paper)", paper.conventional.*member, false);
  }
  t << "\n" << fmt("%.2f", seconds) << " s\n";
  std::cout << t.str();

  {
    const io::Json j = {
        {"study", "registration"},
        {"units", {{"rotation", "deg"}, {"translation", "mm"}}},
        {"trials", options.trials},
        {"points", r.points},
        {"noise_mm", figure(options.noise)},
        {"probe_radius_mm", figure(options.probe_radius)},
        {"metric", registration::to_string(options.registration.metric)},
        {"loss", registration::to_string(options.registration.robust.loss)},
        {"proposed", json_statistics(r.proposed.stats)},
        {"conventional", json_statistics(r.conventional.stats)},
        {"converged_trials", {{"proposed", r.proposed.converged}, {"conventional", r.conventional.converged}}},
        {"paper", {{"proposed", json_statistics(paper.proposed)}, {"conventional", json_statistics(paper.conventional)}}}};
    std::ostringstream c;
    c << "trial,route,rx_deg,ry_deg,rz_deg,tx_mm,ty_mm,tz_mm\n";
    for (const auto& [name, route] : {std::pair{"proposed", &r.proposed}, std::pair{"conventional", &r.conventional}}) {
      for (std::size_t k = 0; k < route->errors.size(); ++k) {
        c << k + 1 << ',' << name;
        for (double v : route->errors[k]) c << ',' << fmt("%.6e", v);
        c << '\n';
      }
    }
    // Table 1's standard deviations, ours as the JSON writes them; the chart on log axes (ours and the paper's differ
    // by orders of magnitude), rotations and translations apart.
    const std::vector<std::pair<std::string, const studies::PoseError*>> routes = {
        {"proposed, ours", &r.proposed.stats.std}, {"proposed, paper", &paper.proposed.std},
        {"conventional, ours", &r.conventional.stats.std}, {"conventional, paper", &paper.conventional.std}};
    std::vector<std::string> panels;
    for (const auto& [first, unit_label] : {std::pair{std::size_t{0}, "deg"}, std::pair{std::size_t{3}, "mm"}}) {
      std::vector<std::string> categories;
      std::vector<io::Series> bars;
      for (std::size_t c = first; c < first + 3; ++c) categories.push_back(studies::kPoseComponents[c]);
      for (const auto& [label, e] : routes) {
        bars.push_back({.name = label, .y = {(*e)[first], (*e)[first + 1], (*e)[first + 2]}});
      }
      panels.push_back(io::grouped_bar_chart_svg(
          categories, bars,
          {.title = first == 0 ? "Rotations: std of the error" : "Translations: std of the error",
           .x_label = "component",
           .y_label = std::string("std (") + unit_label + ", log scale)",
           .width = 560,
           .height = 380,
           .log_y = true}));
    }
    const std::string svg = io::side_by_side_svg(panels, "Table 1: standard deviation of the registration error");
    std::vector<TableRow> rows;
    for (std::size_t k = 0; k < routes.size(); ++k) {
      TableRow row{.cells = {routes[k].first}, .paper = k % 2 == 1};
      for (double v : *routes[k].second) row.cells.push_back(row.paper ? paper_number(v) : fmt("%.6e", v));
      rows.push_back(row);
    }
    const std::string section = html_section(
        "registration", "Registration accuracy (§5.1, Table 1)",
        "The paper's Table 1 gives the standard deviation of the registration error over " + std::to_string(options.trials) +
            " random misalignments (up to &#177;" + fmt("%g", options.max_translation) + " mm and &#177;" +
            fmt("%g", options.max_rotation) +
            "&#176; per axis) of a cube corner of three 20 mm squares measured at " + std::to_string(r.points) +
            " points with a " + fmt("%g", options.probe_radius) +
            " mm tip: the proposed route (raw centres registered to the radius-offset model) against the conventional "
            "one (compensated with the unperturbed normals, then registered to the nominal). Ours: noise &#963; = " +
            fmt("%g", options.noise) + " mm, " + io::xml_escape(registration::to_string(options.registration.metric)) +
            " ICP; converged " + std::to_string(r.proposed.converged) + " and " +
            std::to_string(r.conventional.converged) + " of " + std::to_string(options.trials) + ".",
        {svg},
        html_table({"std of the error", "rx (deg)", "ry (deg)", "rz (deg)", "tx (mm)", "ty (mm)", "tz (mm)"}, rows));
    write_study_files(output_dir, "registration",
                      {.csv = c.str(), .json = io::json_text(j), .figures = {{"registration.svg", svg}}, .section = section});
  }
  return 0;
}


int run_study_analytic_cylinder(const StudyArgs& a) {
  const geometry::Stopwatch t0;
  // Fig. 3: R = 10, r = 1, dy = 2 (the paper's CMM experiment); Fig. 5: the largest error against dy for
  // r/R = 0.05 … 0.5 at R = 10; and the paper's worked example R = 10, r = 3, dy = 1.62 ("about 0.03 mm").
  const studies::CircleCase fig3{.R = 10.0, .r = 1.0, .dy = 2.0};
  const studies::CircleCase example{.R = 10.0, .r = 3.0, .dy = 1.62};
  std::vector<double> ratios, dys;
  for (int k = 1; k <= 10; ++k) ratios.push_back(0.05 * k);
  for (int k = 0; k <= 20; ++k) dys.push_back(0.1 * k);
  const std::vector<studies::Fig5Point> fig5 = studies::fig5_series(10.0, ratios, dys);
  const studies::MaxError fig3_max = studies::max_conventional_error(fig3);
  const studies::MaxError example_max = studies::max_conventional_error(example);

  std::ostringstream csv;
  csv << "series,R_mm,r_mm,dy_mm,theta_deg,error_mm\n";
  auto row = [&](const char* series, const studies::CircleCase& c, double theta, double error) {
    csv << series << ',' << fmt("%g", c.R) << ',' << fmt("%g", c.r) << ',' << fmt("%g", c.dy) << ','
        << fmt("%.9f", theta) << ',' << fmt("%.12f", error) << '\n';
  };
  std::ostringstream t;
  t << "Conventional compensation on a misaligned circle, solved exactly (paper §2.1, equations (1)-(4)).\n"
    << "Nominal circle radius R about the origin, actual one displaced dy along y; the probe comes in along the\n"
    << "nominal normal at angle theta; error = signed distance of c - r*(cos theta, sin theta) from the actual circle.\n\n"
    << "Fig. 3: error against approach angle, R = 10, r = 1, dy = 2 mm\n   theta (deg)   error (mm)\n";
  io::Series fig3_line{.name = "conventional", .markers = false};
  for (int k = 0; k <= 360; ++k) {
    const double theta = 0.5 * k;
    const double e = studies::conventional_touch(fig3, theta).error;
    row("fig3", fig3, theta, e);
    fig3_line.x.push_back(theta);
    fig3_line.y.push_back(e);
    if (k % 30 == 0) t << fmt("%13.1f", theta) << fmt("%13.6f", e) << "\n";
  }
  t << "   largest: " << fmt("%.6f", fig3_max.error) << " mm at theta = " << fmt("%.3f", fig3_max.theta_deg) << " deg\n\n"
    << "Fig. 5: largest error over theta in [0, 180] deg (mm), R = 10 mm\n    r/R";
  for (double d : dys) {
    if (std::lround(d * 10) % 4 == 0) t << fmt("%10.1f", d);
  }
  t << "   <- dy (mm)\n";
  std::vector<io::Series> fig5_lines;
  for (double ratio : ratios) {
    t << fmt("%7.2f", ratio);
    fig5_lines.push_back({.name = "r/R = " + fmt("%.2f", ratio)});
    for (const studies::Fig5Point& p : fig5) {
      if (p.r_over_R != ratio) continue;
      row("fig5", {.R = 10.0, .r = ratio * 10.0, .dy = p.dy}, p.max.theta_deg, p.max.error);
      fig5_lines.back().x.push_back(p.dy);
      fig5_lines.back().y.push_back(p.max.error);
      // Rounding leaves about 1e-15 mm where the exact error is 0 (dy = 0): shown as 0.
      if (std::lround(p.dy * 10) % 4 == 0) t << fmt("%10.5f", std::abs(p.max.error) < 1e-12 ? 0.0 : p.max.error);
    }
    t << "\n";
  }
  row("example", example, example_max.theta_deg, example_max.error);
  t << "\nThe paper's example, R = 10, r = 3 (r/R = 0.3), dy = 1.62 mm: largest error " << fmt("%.6f", example_max.error)
    << " mm at theta = " << fmt("%.3f", example_max.theta_deg) << " deg (the paper reads about 0.03 mm off Fig. 5).\n"
    << fmt("%.2f", t0.seconds()) << " s\n";
  std::cout << t.str();

  const io::Json j = {{"study", "analytic-cylinder"},
                      {"units", "mm"},
                      {"max_error_mm", length(example_max.error)},
                      {"theta_deg", io::json_fixed(example_max.theta_deg, 6)},
                      {"R_mm", 10},
                      {"r_mm", 3},
                      {"dy_mm", 1.62},
                      {"paper_reads_mm", 0.03},
                      {"fig3",
                       {{"R_mm", 10},
                        {"r_mm", 1},
                        {"dy_mm", 2},
                        {"max_error_mm", length(fig3_max.error)},
                        {"theta_deg", io::json_fixed(fig3_max.theta_deg, 6)}}}};

  const std::string fig3_svg = io::line_chart_svg(
      {fig3_line, {.name = "largest", .x = {fig3_max.theta_deg}, .y = {fig3_max.error}}},
      {.title = "Fig. 3: error against approach angle (R = 10, r = 1, dy = 2 mm)",
       .x_label = "approach angle θ (deg)",
       .y_label = "error (mm)",
       .width = 760,
       .height = 400,
       .x_ticks = {0, 30, 60, 90, 120, 150, 180}});
  const std::string fig5_svg = io::line_chart_svg(
      fig5_lines, {.title = "Fig. 5: largest error against misalignment (R = 10 mm)",
                   .x_label = "misalignment dy (mm)",
                   .y_label = "largest error over θ (mm)",
                   .width = 760,
                   .height = 460,
                   .palette = io::Palette::Sequential});
  const std::string section = html_section(
      "analytic-cylinder", "Conventional compensation on a misaligned circle (§2.1, Figs 3 and 5)",
      "The paper's Fig. 3 shows the error of conventional compensation against the probe's approach angle &#952; on a "
      "circle of radius R = 10 mm misaligned by dy = 2 mm, probed with an r = 1 mm tip; its Fig. 5 the largest error "
      "over &#952; against dy for r/R from 0.05 to 0.5. Both solved here in closed form (equations (1)&#8211;(4)).",
      {fig3_svg, fig5_svg},
      html_table({"case", "largest error (mm)", "at θ (deg)", "paper"},
                 {{.cells = {"Fig. 3: R = 10, r = 1, dy = 2 mm", fmt("%.9f", fig3_max.error),
                             fmt("%.6f", fig3_max.theta_deg), "(Fig. 3 is a curve)"}},
                  {.cells = {"the paper's example: R = 10, r = 3, dy = 1.62 mm", fmt("%.9f", example_max.error),
                             fmt("%.6f", example_max.theta_deg), "about 0.03 (read off Fig. 5)"}}}));
  write_study_files(a.output_dir, "analytic-cylinder",
                    {.csv = csv.str(),
                     .json = io::json_text(j),
                     .figures = {{"analytic-cylinder-fig3.svg", fig3_svg}, {"analytic-cylinder-fig5.svg", fig5_svg}},
                     .section = section});
  return 0;
}

int run_study_cylinder(const StudyArgs& a, bool deformation) {
  const geometry::Stopwatch t0;
  studies::CylinderStudyOptions o;
  o.seed = a.seed;
  const studies::CylinderStudyResult r =
      deformation ? studies::run_cylinder_deformation_study(o) : studies::run_cylinder_misalignment_study(o);
  const std::string name = deformation ? "cylinder-deformation" : "cylinder-misalignment";

  std::ostringstream t;
  t << (deformation ? "Cylinder with a local sinusoidal deformation (paper §7.2, Fig. 9)"
                    : "Cylinder misaligned by 2 mm along z (paper §7.1, Fig. 8)")
    << ": radius " << o.part.radius << " mm, a " << o.part.arc_end - o.part.arc_start << " deg arc, "
    << o.part.length << " mm long; " << o.grid << " x " << o.grid << " points, probe radius " << o.probe_radius
    << " mm.\n";
  if (deformation) {
    t << "Deformation: a crest of the given peak at the arc's middle, sinusoid of wavelength " << o.wavelength
      << " mm along the axis under a Gaussian window of " << o.window << " mm.\n";
  }
  t << "Compensation error = signed distance of each compensated point from the actual surface, in um.\n\n";
  char line[256];
  std::snprintf(line, sizeof line, "%s %9s | %12s %12s | %12s %12s | %s\n", deformation ? "peak (mm)" : "         ",
                "sigma(um)", "conv. mean", "conv. std", "CAD mean", "CAD std", "CAD untrusted");
  t << line;
  std::ostringstream csv;
  csv << "peak_mm,misalignment_mm,sigma_mm,method,points,mean_mm,std_mm,min_mm,max_mm,untrusted\n";
  io::Json rows = io::Json::array();
  for (std::size_t k = 0; k < r.rows.size(); ++k) {
    const studies::CylinderStudyRow& w = r.rows[k];
    std::snprintf(line, sizeof line, "%9.1f %9.0f | %12.3f %12.3f | %12.3f %12.3f | %d of %d\n", w.peak, 1000 * w.sigma,
                  1000 * w.conventional.mean, 1000 * w.conventional.std, 1000 * w.cad.mean + 0.0, 1000 * w.cad.std,
                  w.cad_untrusted, w.points);
    t << (deformation ? std::string(line) : std::string("         ") + (line + 9));
    for (const auto& [method, s, untrusted] :
         {std::tuple{"conventional", &w.conventional, w.points - w.conventional.points}, std::tuple{"cad", &w.cad, w.cad_untrusted}}) {
      csv << fmt("%g", w.peak) << ',' << fmt("%g", w.misalignment) << ',' << fmt("%g", w.sigma) << ',' << method << ','
          << s->points << ',' << fmt("%.9f", s->mean) << ',' << fmt("%.9f", s->std) << ',' << fmt("%.9f", s->min) << ','
          << fmt("%.9f", s->max) << ',' << untrusted << '\n';
    }
    rows.push_back({{"peak_mm", figure(w.peak)},
                    {"misalignment_mm", figure(w.misalignment)},
                    {"sigma_mm", figure(w.sigma)},
                    {"conventional", json_summary(w.conventional)},
                    {"cad", json_summary(w.cad)},
                    {"cad_untrusted", w.cad_untrusted}});
  }
  const bool better = r.cad_better_everywhere(), smooths = r.cad_smooths_noise();
  t << "\nCAD-based |mean| and std below the conventional's in every row: " << (better ? "yes" : "NO") << "\n"
    << "CAD-based std below sigma wherever sigma >= 10 um: " << (smooths ? "yes" : "NO") << "\n"
    << fmt("%.2f", t0.seconds()) << " s\n";
  std::cout << t.str();
  const io::Json j = {{"study", name},
                      {"units", "mm"},
                      {"cylinder_radius_mm", figure(o.part.radius)},
                      {"arc_deg", figure(o.part.arc_end - o.part.arc_start)},
                      {"length_mm", figure(o.part.length)},
                      {"probe_radius_mm", figure(o.probe_radius)},
                      {"grid", {o.grid, o.grid}},
                      {"cad_better_everywhere", better},
                      {"cad_std_below_sigma_from_10um", smooths},
                      {"rows", rows}};

  // Fig. 8 / 9: mean and std against σ, in µm as printed; one line per method (and peak), conventional dashed.
  std::vector<io::Series> mean_lines, std_lines;
  std::vector<TableRow> table;
  for (const bool cad : {true, false}) {
    for (const studies::CylinderStudyRow& w : r.rows) {
      const std::string label =
          std::string(cad ? "CAD-based" : "conventional") + (deformation ? ", " + fmt("%.1f", w.peak) + " mm" : "");
      if (mean_lines.empty() || mean_lines.back().name != label) {
        mean_lines.push_back({.name = label, .dashed = !cad});
        std_lines.push_back({.name = label, .dashed = !cad});
      }
      const studies::ErrorSummary& e = cad ? w.cad : w.conventional;
      mean_lines.back().x.push_back(1000 * w.sigma);
      mean_lines.back().y.push_back(1000 * e.mean);
      std_lines.back().x.push_back(1000 * w.sigma);
      std_lines.back().y.push_back(1000 * e.std);
    }
  }
  for (const studies::CylinderStudyRow& w : r.rows) {
    TableRow row;
    if (deformation) row.cells.push_back(fmt("%.1f", w.peak));
    row.cells.push_back(fmt("%.0f", 1000 * w.sigma));
    for (const double v : {w.conventional.mean, w.conventional.std, w.cad.mean, w.cad.std}) {
      row.cells.push_back(fmt("%.3f", 1000 * v));
    }
    row.cells.push_back(std::to_string(w.cad_untrusted) + " of " + std::to_string(w.points));
    table.push_back(row);
  }
  std::vector<std::string> header = {"σ (µm)", "conventional mean (µm)", "conventional std (µm)", "CAD-based mean (µm)",
                                     "CAD-based std (µm)", "CAD-based untrusted"};
  if (deformation) header.insert(header.begin(), "peak (mm)");
  const std::string figure = deformation ? "Fig. 9" : "Fig. 8";
  const io::ChartOptions chart{.x_label = "noise σ (µm)", .width = 560, .height = 400};
  io::ChartOptions mean_chart = chart, std_chart = chart;
  mean_chart.title = figure + ": mean of the error";
  mean_chart.y_label = "mean error (µm)";
  std_chart.title = figure + ": std of the error";
  std_chart.y_label = "std of the error (µm)";
  const std::string svg = io::side_by_side_svg(
      {io::line_chart_svg(mean_lines, mean_chart), io::line_chart_svg(std_lines, std_chart)},
      figure + ": compensation error against noise");
  const std::string section = html_section(
      name,
      deformation ? "Cylinder with a local deformation (§7.2, Fig. 9)" : "Misaligned cylinder (§7.1, Fig. 8)",
      "The paper's " + figure +
          " plots the mean and the standard deviation of the compensation error (signed distance of each compensated "
          "point from the actual surface) of the conventional and the CAD-based method against the noise &#963; "
          "(0&#8211;40 &#181;m) on part of a cylinder, r = 1 mm, " +
          (deformation ? std::string("with a local sinusoidal deformation of peak 0.5, 1.0 and 1.5 mm")
                       : std::string("misaligned by 2 mm")) +
          ". Ours: radius " + fmt("%g", o.part.radius) + " mm, " + std::to_string(o.grid) + " &#215; " +
          std::to_string(o.grid) + " points. CAD-based |mean| and std below the conventional's in every row: " +
          (better ? "yes" : "NO") + "; CAD-based std below &#963; wherever &#963; &#8805; 10 &#181;m: " +
          (smooths ? "yes" : "NO") + ".",
      {svg}, html_table(header, table));
  write_study_files(a.output_dir, name,
                    {.csv = csv.str(), .json = io::json_text(j), .figures = {{name + ".svg", svg}}, .section = section});
  return 0;
}

// The free-form case at each noise level: one row per level (both methods' errors, the CAD method's flagged rows,
// its u and u's coverage of the true errors), freeform-noise.csv and freeform-noise.json.
int run_study_freeform_noise(const StudyArgs& a) {
  const geometry::Stopwatch t0;
  std::ostringstream t, csv;
  io::Json rows = io::Json::array();
  t << "The paper's free-form case (§7.3) at " << a.noise.size() << " noise levels, seed " << a.seed
    << ": 7200 grid points, probe radius 1 mm.\n"
    << "Errors: signed distance of each compensated point from the actual surface, um, over the rows each method\n"
    << "trusts (flagged: the CAD-based rows not ok). Coverage: share of the CAD-based ok rows whose true error is\n"
    << "within +-2u.\n\n";
  char line[256];
  std::snprintf(line, sizeof line, "%9s | %9s %9s | %9s %9s %9s %7s | %7s %9s %12s\n", "sigma(um)", "conv.std", "conv.max",
                "CAD std", "CAD mean", "CAD max", "flagged", "mean u", "coverage", "worst region");
  t << line;
  csv << "sigma_mm,conventional_std_mm,conventional_max_mm,cad_std_mm,cad_mean_mm,cad_max_mm,cad_flagged,mean_u_mm,"
         "coverage_2u,worst_region_coverage_2u\n";
  std::vector<io::Series> lines = {{.name = "conventional std"}, {.name = "CAD-based std"}, {.name = "CAD-based mean u"}};
  std::vector<TableRow> table;
  for (std::size_t i = 0; i < a.noise.size(); ++i) {
    studies::FreeformStudyOptions o;
    o.seed = a.seed;
    o.noise_sigma = a.noise[i];
    const studies::FreeformStudyResult r = studies::run_freeform_study(o);
    const studies::ErrorSummary& c = r.conventional_summary;
    const studies::ErrorSummary& d = r.cad_summary;
    std::snprintf(line, sizeof line, "%9.2f | %9.3f %9.3f | %9.3f %9.3f %9.3f %7d | %7.3f %8.1f%% %11.1f%%\n",
                  1000 * a.noise[i], 1000 * c.std, 1000 * c.max_abs(), 1000 * d.std, 1000 * d.mean + 0.0,
                  1000 * d.max_abs(), r.flagged, 1000 * r.mean_uncertainty, 100 * r.coverage_2u,
                  100 * r.worst_region_coverage_2u);
    t << line;
    for (auto& series : lines) series.x.push_back(1000 * a.noise[i]);
    lines[0].y.push_back(1000 * c.std);
    lines[1].y.push_back(1000 * d.std);
    lines[2].y.push_back(1000 * r.mean_uncertainty);
    table.push_back({.cells = {fmt("%.2f", 1000 * a.noise[i]), fmt("%.3f", 1000 * c.std), fmt("%.3f", 1000 * c.max_abs()),
                               fmt("%.3f", 1000 * d.std), fmt("%.3f", 1000 * d.mean), fmt("%.3f", 1000 * d.max_abs()),
                               std::to_string(r.flagged), fmt("%.3f", 1000 * r.mean_uncertainty),
                               fmt("%.1f", 100 * r.coverage_2u) + " %", fmt("%.1f", 100 * r.worst_region_coverage_2u) + " %"}});
    csv << fmt("%g", a.noise[i]) << ',' << fmt("%.9f", c.std) << ',' << fmt("%.9f", c.max_abs()) << ','
        << fmt("%.9f", d.std) << ',' << fmt("%.9f", d.mean) << ',' << fmt("%.9f", d.max_abs()) << ',' << r.flagged << ','
        << fmt("%.9f", r.mean_uncertainty) << ',' << fmt("%.4f", r.coverage_2u) << ','
        << fmt("%.4f", r.worst_region_coverage_2u) << '\n';
    rows.push_back({{"sigma_mm", figure(a.noise[i])},
                    {"conventional", json_summary(c)},
                    {"cad", json_summary(d)},
                    {"cad_flagged", r.flagged},
                    {"mean_u_mm", length(r.mean_uncertainty)},
                    {"coverage_2u", share(r.coverage_2u)},
                    {"worst_region_coverage_2u", share(r.worst_region_coverage_2u)}});
  }
  t << fmt("%.2f", t0.seconds()) << " s\n";
  std::cout << t.str();
  const io::Json j = {{"study", "freeform-noise"}, {"units", "mm"}, {"points", 7200}, {"seed", a.seed}, {"rows", rows}};
  const std::string svg = io::line_chart_svg(lines, {.title = "Free-form case: error against noise",
                                                     .x_label = "noise σ (µm)",
                                                     .y_label = "µm (log scale)",
                                                     .width = 760,
                                                     .height = 400,
                                                     .log_y = true});
  const std::string section = html_section(
      "freeform-noise", "The free-form case at several noise levels (§7.3)",
      "The paper's Table 2 is the free-form case at one noise level (&#963; = 4.5 &#181;m). Here the same case at " +
          std::to_string(a.noise.size()) +
          " levels (seed " + std::to_string(a.seed) +
          "): the standard deviation of both methods' errors and the CAD-based method's mean uncertainty u (k = 1), "
          "with the share of its trusted points whose true error is within &#177;2u.",
      {svg},
      html_table({"σ (µm)", "conventional std (µm)", "conventional max |error| (µm)", "CAD-based std (µm)",
                  "CAD-based mean (µm)", "CAD-based max |error| (µm)", "CAD-based flagged", "mean u (µm)",
                  "within ±2u", "worst of 4 × 4 regions"},
                 table));
  write_study_files(a.output_dir, "freeform-noise",
                    {.csv = csv.str(), .json = io::json_text(j), .figures = {{"freeform-noise.svg", svg}}, .section = section});
  return 0;
}

int run_study_freeform(const StudyArgs& a) {
  if (a.noise.size() > 1) return run_study_freeform_noise(a);
  studies::FreeformStudyOptions o;
  o.seed = a.seed;
  if (!a.noise.empty()) o.noise_sigma = a.noise.front();
  const studies::FreeformStudyResult r = studies::run_freeform_study(o);
  std::cout << freeform_report(r);
  std::ostringstream csv;
  csv << "point,x,y,z,i,j,k,conventional_error_mm,cad_error_mm,cad_status\n";
  for (std::size_t k = 0; k < r.touches.size(); ++k) {
    const Point3& x = r.touches[k].measured;
    const Vector3& n = r.plan[k].normal;
    auto error = [](double e) { return std::isnan(e) ? std::string() : fmt("%.9f", e); };
    csv << k + 1 << ',' << mm(x.x()) << ',' << mm(x.y()) << ',' << mm(x.z()) << ',' << unit(n.x()) << ','
        << unit(n.y()) << ',' << unit(n.z()) << ',' << error(r.conventional_error[k]) << ',' << error(r.cad_error[k])
        << ',' << compensation::to_string(r.cad.points[k].status) << '\n';
  }
  const studies::PaperTable2 paper = studies::paper_table2();
  const io::Json j = {{"study", "freeform"},
                      {"units", "mm"},
                      {"points", r.plan.size()},
                      {"noise_sigma_mm", figure(r.freeform.noise_sigma)},
                      {"seed", a.seed},
                      {"conventional", json_summary(r.conventional_summary)},
                      {"cad", json_summary(r.cad_summary)},
                      {"cad_uncertainty",
                       {{"mean_u_mm", length(r.mean_uncertainty)},
                        {"coverage_2u", share(r.coverage_2u)},
                        {"worst_region_coverage_2u", share(r.worst_region_coverage_2u)},
                        {"flagged", r.flagged}}},
                      {"paper", {{"conventional", json_summary(paper.conventional)}, {"cad", json_summary(paper.proposed)}}}};

  // The two error distributions on common bins (µm), about 80 across the range of both.
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  std::vector<double> conventional_um, cad_um;
  for (std::size_t k = 0; k < r.touches.size(); ++k) {
    conventional_um.push_back(1000 * r.conventional_error[k]);
    cad_um.push_back(1000 * r.cad_error[k]);
    for (double e : {conventional_um.back(), cad_um.back()}) {
      if (std::isfinite(e)) lo = std::min(lo, e), hi = std::max(hi, e);
    }
  }
  const std::vector<double> edges = io::nice_ticks(lo, hi, 80);
  std::vector<io::Series> distributions;
  for (const auto& [label, errors] : {std::pair{"conventional", &conventional_um}, std::pair{"CAD-based", &cad_um}}) {
    const io::Histogram h = io::histogram(*errors, edges.front(), edges[1] - edges[0], edges.size());
    io::Series line{.name = label, .markers = false};
    for (std::size_t k = 0; k < h.counts.size(); ++k) {
      line.x.push_back(h.centre(k));
      line.y.push_back(h.counts[k]);
    }
    distributions.push_back(line);
  }
  const std::string svg = io::line_chart_svg(
      distributions, {.title = "Table 2's errors: points per " + fmt("%g", edges[1] - edges[0]) + " µm bin",
                      .x_label = "compensation error (µm)",
                      .y_label = "points (log scale)",
                      .width = 760,
                      .height = 400,
                      .log_y = true});
  auto ours = [](const char* label, const studies::ErrorSummary& e) {
    return TableRow{.cells = {label, fmt("%.9f", e.std), fmt("%.9f", e.mean), fmt("%.9f", e.min), fmt("%.9f", e.max)}};
  };
  auto theirs = [](const char* label, const studies::ErrorSummary& e) {
    return TableRow{.cells = {label, paper_number(e.std), paper_number(e.mean), paper_number(e.min), paper_number(e.max)},
                    .paper = true};
  };
  const std::string section = html_section(
      "freeform", "Free-form surface (§7.3, Table 2)",
      "The paper's Table 2 gives the standard deviation, mean, minimum and maximum of the compensation error (signed "
      "distance of each compensated point from the actual surface, mm) of the conventional and the CAD-based method on "
      "a deformed, misaligned free-form panel measured at " + std::to_string(r.plan.size()) +
          " points (120 &#215; 60) with a 1 mm tip and noise &#963; = " + fmt("%g", 1000 * r.freeform.noise_sigma) +
          " &#181;m. Ours over the points each method trusts (conventional " +
          std::to_string(r.conventional_summary.points) + ", CAD-based " + std::to_string(r.cad_summary.points) +
          " of " + std::to_string(r.plan.size()) + "); the figure shows both error distributions.",
      {svg},
      html_table({"compensation error (mm)", "std", "mean", "min", "max"},
                 {ours("conventional, ours", r.conventional_summary), theirs("conventional, paper", paper.conventional),
                  ours("CAD-based, ours", r.cad_summary), theirs("CAD-based, paper", paper.proposed)}) +
          "<p>Uncertainty u (k = 1) of the CAD-based points: mean " + fmt("%.9f", r.mean_uncertainty) +
          " mm; the true error is within &#177;2u at " + fmt("%.4f", r.coverage_2u) + " of the trusted points (" +
          fmt("%.4f", r.worst_region_coverage_2u) + " in the worst of 4 &#215; 4 regions).</p>\n");
  write_study_files(a.output_dir, "freeform",
                    {.csv = csv.str(), .json = io::json_text(j), .figures = {{"freeform.svg", svg}}, .section = section});
  return 0;
}

}  // namespace

int run_study(const StudyArgs& a) {
  if (a.name == "registration") return run_study_registration(a);
  if (a.name == "analytic-cylinder") return run_study_analytic_cylinder(a);
  if (a.name == "approach-angle") return run_study_approach_angle(a);
  if (a.name == "cylinder-misalignment") return run_study_cylinder(a, false);
  if (a.name == "cylinder-deformation") return run_study_cylinder(a, true);
  if (a.name == "freeform") return run_study_freeform(a);
  throw std::invalid_argument("unknown study '" + a.name + "'");
}

}  // namespace probecomp::cli
