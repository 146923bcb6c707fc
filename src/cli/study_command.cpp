// probecomp study NAME: the paper's studies (DESIGN.md §3), each printing a table beside the paper's figures and
// writing DIR/NAME.csv (the series) and DIR/NAME.json (the summary).

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "probecomp/geometry/stopwatch.hpp"
#include "probecomp/io/format.hpp"
#include "probecomp/io/output_files.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/studies/analytic_cylinder.hpp"
#include "probecomp/studies/cylinder_study.hpp"
#include "probecomp/studies/freeform_study.hpp"
#include "probecomp/studies/registration_study.hpp"

namespace probecomp::cli {

const std::vector<std::string> kStudyNames = {"analytic-cylinder", "registration", "cylinder-misalignment",
                                              "cylinder-deformation", "freeform"};

namespace {


void write_study_files(const std::string& dir, const std::string& name, const std::string& csv, const std::string& json) {
  if (dir.empty()) return;
  std::filesystem::create_directories(dir);
  io::OutputFiles files;
  files.add(std::filesystem::path(dir) / (name + ".csv"), csv);
  files.add(std::filesystem::path(dir) / (name + ".json"), json);
  files.commit();
  std::cout << "Wrote " << (std::filesystem::path(dir) / (name + ".csv")).string() << " (the series) and " << name
            << ".json (the summary).\n";
}

std::string json_summary(const studies::ErrorSummary& s) {
  return "{\"points\": " + std::to_string(s.points) + ", \"std\": " + fmt("%.9f", s.std) + ", \"mean\": " +
         fmt("%.9f", s.mean) + ", \"min\": " + fmt("%.9f", s.min) + ", \"max\": " + fmt("%.9f", s.max) + "}";
}

registration::RegistrationOptions registration_options(const std::string& metric, const std::string& loss) {
  registration::RegistrationOptions o;
  o.metric = metric == "point-to-point" ? registration::Metric::PointToPoint : registration::Metric::PointToPlane;
  o.robust.loss = loss == "none"      ? registration::RobustLoss::None
                  : loss == "huber"   ? registration::RobustLoss::Huber
                  : loss == "trimmed" ? registration::RobustLoss::Trimmed
                                      : registration::RobustLoss::Cauchy;
  return o;
}

std::string json_pose_error(const studies::PoseError& e) {
  std::string out = "{";
  for (std::size_t c = 0; c < 6; ++c) {
    out += std::string(c ? ", " : "") + "\"" + studies::kPoseComponents[c] + "\": " + fmt("%.6e", e[c]);
  }
  return out + "}";
}

std::string json_statistics(const studies::ErrorStatistics& s) {
  return "{\"std\": " + json_pose_error(s.std) + ", \"mean\": " + json_pose_error(s.mean) +
         ", \"ci95\": " + json_pose_error(s.ci95) + "}";
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
    std::ostringstream j;
    j << "{\"study\": \"registration\", \"units\": {\"rotation\": \"deg\", \"translation\": \"mm\"},\n"
      << " \"trials\": " << options.trials << ", \"points\": " << r.points << ", \"noise_mm\": " << options.noise
      << ", \"probe_radius_mm\": " << options.probe_radius << ", \"metric\": \""
      << registration::to_string(options.registration.metric) << "\", \"loss\": \""
      << registration::to_string(options.registration.robust.loss) << "\",\n"
      << " \"proposed\": " << json_statistics(r.proposed.stats) << ",\n"
      << " \"conventional\": " << json_statistics(r.conventional.stats) << ",\n"
      << " \"converged_trials\": {\"proposed\": " << r.proposed.converged << ", \"conventional\": " << r.conventional.converged
      << "},\n"
      << " \"paper\": {\"proposed\": " << json_statistics(paper.proposed) << ",\n"
      << "           \"conventional\": " << json_statistics(paper.conventional) << "}}\n";
    std::ostringstream c;
    c << "trial,route,rx_deg,ry_deg,rz_deg,tx_mm,ty_mm,tz_mm\n";
    for (const auto& [name, route] : {std::pair{"proposed", &r.proposed}, std::pair{"conventional", &r.conventional}}) {
      for (std::size_t k = 0; k < route->errors.size(); ++k) {
        c << k + 1 << ',' << name;
        for (double v : route->errors[k]) c << ',' << fmt("%.6e", v);
        c << '\n';
      }
    }
    write_study_files(output_dir, "registration", c.str(), j.str());
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
  for (int k = 0; k <= 360; ++k) {
    const double theta = 0.5 * k;
    const double e = studies::conventional_touch(fig3, theta).error;
    row("fig3", fig3, theta, e);
    if (k % 30 == 0) t << fmt("%13.1f", theta) << fmt("%13.6f", e) << "\n";
  }
  t << "   largest: " << fmt("%.6f", fig3_max.error) << " mm at theta = " << fmt("%.3f", fig3_max.theta_deg) << " deg\n\n"
    << "Fig. 5: largest error over theta in [0, 180] deg (mm), R = 10 mm\n    r/R";
  for (double d : dys) {
    if (std::lround(d * 10) % 4 == 0) t << fmt("%10.1f", d);
  }
  t << "   <- dy (mm)\n";
  for (double ratio : ratios) {
    t << fmt("%7.2f", ratio);
    for (const studies::Fig5Point& p : fig5) {
      if (p.r_over_R != ratio) continue;
      row("fig5", {.R = 10.0, .r = ratio * 10.0, .dy = p.dy}, p.max.theta_deg, p.max.error);
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

  std::ostringstream j;
  j << "{\"study\": \"analytic-cylinder\", \"units\": \"mm\",\n"
    << " \"max_error_mm\": " << fmt("%.9f", example_max.error) << ", \"theta_deg\": " << fmt("%.6f", example_max.theta_deg)
    << ", \"R_mm\": 10, \"r_mm\": 3, \"dy_mm\": 1.62, \"paper_reads_mm\": 0.03,\n"
    << " \"fig3\": {\"R_mm\": 10, \"r_mm\": 1, \"dy_mm\": 2, \"max_error_mm\": " << fmt("%.9f", fig3_max.error)
    << ", \"theta_deg\": " << fmt("%.6f", fig3_max.theta_deg) << "}}\n";
  write_study_files(a.output_dir, "analytic-cylinder", csv.str(), j.str());
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
  std::ostringstream rows;
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
    rows << "  {\"peak_mm\": " << fmt("%g", w.peak) << ", \"misalignment_mm\": " << fmt("%g", w.misalignment)
         << ", \"sigma_mm\": " << fmt("%g", w.sigma) << ", \"conventional\": " << json_summary(w.conventional)
         << ", \"cad\": " << json_summary(w.cad) << ", \"cad_untrusted\": " << w.cad_untrusted << "}"
         << (k + 1 < r.rows.size() ? "," : "") << "\n";
  }
  const bool better = r.cad_better_everywhere(), smooths = r.cad_smooths_noise();
  t << "\nCAD-based |mean| and std below the conventional's in every row: " << (better ? "yes" : "NO") << "\n"
    << "CAD-based std below sigma wherever sigma >= 10 um: " << (smooths ? "yes" : "NO") << "\n"
    << fmt("%.2f", t0.seconds()) << " s\n";
  std::cout << t.str();
  std::ostringstream j;
  j << "{\"study\": \"" << name << "\", \"units\": \"mm\", \"cylinder_radius_mm\": " << o.part.radius
    << ", \"arc_deg\": " << o.part.arc_end - o.part.arc_start << ", \"length_mm\": " << o.part.length
    << ", \"probe_radius_mm\": " << o.probe_radius << ", \"grid\": [" << o.grid << ", " << o.grid << "],\n"
    << " \"cad_better_everywhere\": " << (better ? "true" : "false")
    << ", \"cad_std_below_sigma_from_10um\": " << (smooths ? "true" : "false") << ",\n \"rows\": [\n"
    << rows.str() << " ]}\n";
  write_study_files(a.output_dir, name, csv.str(), j.str());
  return 0;
}

// The free-form case at each noise level: one row per level (both methods' errors, the CAD method's flagged rows,
// its u and u's coverage of the true errors), freeform-noise.csv and freeform-noise.json.
int run_study_freeform_noise(const StudyArgs& a) {
  const geometry::Stopwatch t0;
  std::ostringstream t, csv, rows;
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
    csv << fmt("%g", a.noise[i]) << ',' << fmt("%.9f", c.std) << ',' << fmt("%.9f", c.max_abs()) << ','
        << fmt("%.9f", d.std) << ',' << fmt("%.9f", d.mean) << ',' << fmt("%.9f", d.max_abs()) << ',' << r.flagged << ','
        << fmt("%.9f", r.mean_uncertainty) << ',' << fmt("%.4f", r.coverage_2u) << ','
        << fmt("%.4f", r.worst_region_coverage_2u) << '\n';
    rows << "  {\"sigma_mm\": " << fmt("%g", a.noise[i]) << ", \"conventional\": " << json_summary(c)
         << ", \"cad\": " << json_summary(d) << ", \"cad_flagged\": " << r.flagged
         << ", \"mean_u_mm\": " << fmt("%.9f", r.mean_uncertainty) << ", \"coverage_2u\": " << fmt("%.4f", r.coverage_2u)
         << ", \"worst_region_coverage_2u\": " << fmt("%.4f", r.worst_region_coverage_2u) << "}"
         << (i + 1 < a.noise.size() ? "," : "") << "\n";
  }
  t << fmt("%.2f", t0.seconds()) << " s\n";
  std::cout << t.str();
  std::ostringstream j;
  j << "{\"study\": \"freeform-noise\", \"units\": \"mm\", \"points\": 7200, \"seed\": " << a.seed
    << ",\n \"rows\": [\n" << rows.str() << " ]}\n";
  write_study_files(a.output_dir, "freeform-noise", csv.str(), j.str());
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
  std::ostringstream j;
  j << "{\"study\": \"freeform\", \"units\": \"mm\", \"points\": " << r.plan.size()
    << ", \"noise_sigma_mm\": " << fmt("%g", r.freeform.noise_sigma) << ", \"seed\": " << a.seed << ",\n"
    << " \"conventional\": " << json_summary(r.conventional_summary) << ",\n"
    << " \"cad\": " << json_summary(r.cad_summary) << ",\n"
    << " \"cad_uncertainty\": {\"mean_u_mm\": " << fmt("%.9f", r.mean_uncertainty) << ", \"coverage_2u\": "
    << fmt("%.4f", r.coverage_2u) << ", \"worst_region_coverage_2u\": " << fmt("%.4f", r.worst_region_coverage_2u)
    << ", \"flagged\": " << r.flagged << "},\n"
    << " \"paper\": {\"conventional\": " << json_summary(paper.conventional) << ", \"cad\": " << json_summary(paper.proposed)
    << "}}\n";
  write_study_files(a.output_dir, "freeform", csv.str(), j.str());
  return 0;
}

}  // namespace

int run_study(const StudyArgs& a) {
  if (a.name == "registration") return run_study_registration(a);
  if (a.name == "analytic-cylinder") return run_study_analytic_cylinder(a);
  if (a.name == "cylinder-misalignment") return run_study_cylinder(a, false);
  if (a.name == "cylinder-deformation") return run_study_cylinder(a, true);
  if (a.name == "freeform") return run_study_freeform(a);
  throw std::invalid_argument("unknown study '" + a.name + "'");
}

}  // namespace probecomp::cli
