#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "probecomp/cad/model.hpp"
#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "cli/format.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/io/dmis.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/io/text.hpp"
#include "probecomp/studies/freeform_study.hpp"

namespace probecomp::cli {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Stage and percentage on standard error, once a run has lasted a second (short runs stay silent).
struct Progress {
  Clock::time_point start = Clock::now();
  bool quiet = false;
  void operator()(const std::string& stage, double fraction) const {
    if (quiet || since(start) < 1.0) return;
    std::cerr << "probecomp: [" << fmt("%3.0f", 100.0 * fraction) << "%] " << stage << "\n";
  }
};

bool has_extension(const std::string& path, std::initializer_list<const char*> extensions) {
  const std::string e = io::lower(std::filesystem::path(path).extension().string());
  return std::any_of(extensions.begin(), extensions.end(), [&](const char* x) { return e == x; });
}

// The output's label for row k: the input's label or id column, else P1, P2, ...
std::string row_label(const io::PointTable& t, std::size_t k) {
  for (std::size_t c = 0; c < t.columns.size(); ++c) {
    const std::string n = io::lower(t.columns[c]);
    if (n == "label" || n == "id") return t.rows[k][c];
  }
  std::string label = "P";
  label += std::to_string(k + 1);
  return label;
}

std::string csv_output(const io::PointTable& t, const compensation::CompensationResult& r) {
  const std::vector<int> carried = t.carried_columns();
  const std::vector<std::string> ours{"x", "y", "z", "nx", "ny", "nz", "deviation", "face", "status"};
  std::ostringstream out;
  out << "x,y,z,nx,ny,nz,deviation,face,status";
  for (int c : carried) {
    const std::string& name = t.columns[static_cast<std::size_t>(c)];
    out << ',' << (std::find(ours.begin(), ours.end(), name) != ours.end() ? "input_" + name : name);
  }
  out << '\n';
  for (std::size_t k = 0; k < r.points.size(); ++k) {
    const compensation::CompensatedPoint& p = r.points[k];
    if (p.computed()) {
      out << mm(p.contact.x()) << ',' << mm(p.contact.y()) << ',' << mm(p.contact.z()) << ',' << unit(p.normal.x()) << ','
          << unit(p.normal.y()) << ',' << unit(p.normal.z()) << ',' << mm(p.deviation) << ',' << p.face << ',';
    } else {
      // Never dropped: the row is there, empty, with the reason.
      out << ",,,,,,," << (p.face >= 0 ? std::to_string(p.face) : "") << ',';
    }
    out << compensation::to_string(p.status);
    for (int c : carried) out << ',' << t.rows[k][static_cast<std::size_t>(c)];
    out << '\n';
  }
  return out.str();
}

std::string dmis_output(const io::PointTable& t, const compensation::CompensationResult& r, const std::string& source) {
  std::ostringstream out;
  out << "$$ probecomp " << compensation::to_string(r.method) << " compensation of " << source
      << ": contact points and the normals used, machine frame, mm\n";
  out << "$$ after each point: its deviation from the registered nominal (mm, + outside), face and status\n";
  for (std::size_t k = 0; k < r.points.size(); ++k) {
    const compensation::CompensatedPoint& p = r.points[k];
    const std::string label = row_label(t, k);
    if (p.computed()) {
      out << io::dmis_point(label, p.contact, p.normal);
      out << "$$ deviation=" << mm(p.deviation) << " face=" << p.face << " status=" << compensation::to_string(p.status) << '\n';
    } else {
      out << "$$ FA(" << label << ") not compensated: status=" << compensation::to_string(p.status) << '\n';
    }
  }
  return out.str();
}

std::string json_stats(const compensation::CompensationResult& r, double read_seconds, double write_seconds) {
  std::ostringstream j;
  const Eigen::Matrix4d M = r.registration.transform.matrix();
  j << "{\"method\": \"" << compensation::to_string(r.method) << "\",\n \"transform\": [";
  for (int a = 0; a < 4; ++a) {
    j << (a ? ",\n               [" : "[");
    for (int b = 0; b < 4; ++b) j << (b ? ", " : "") << fmt("%.15g", M(a, b));
    j << "]";
  }
  j << "],\n \"registration\": {\"rms\": " << fmt("%.9g", r.registration.rms)
    << ", \"iterations\": " << r.registration.iterations + r.registration.coarse_iterations
    << ", \"converged\": " << (r.registration.converged() ? "true" : "false") << ", \"status\": \""
    << registration::to_string(r.registration.status) << "\", \"stop_reason\": " << json_string(r.registration.stop_reason)
    << ", \"scale\": " << fmt("%.9g", r.registration.scale) << ", \"inliers\": " << r.registration.inliers << "},\n \"faces\": [";
  for (std::size_t f = 0; f < r.faces.size(); ++f) {
    const compensation::FaceReport& x = r.faces[f];
    j << (f ? ",\n   " : "\n   ") << "{\"face\": " << x.face << ", \"points\": " << x.points
      << ", \"fitted\": " << (x.fitted ? "true" : "false") << ", \"material_side\": \""
      << cad::to_string(x.material) << "\"";
    if (x.fitted) {
      j << ", \"control_points\": " << x.control_points << ", \"refinement_rounds\": " << x.rounds
        << ", \"rms_residual\": " << fmt("%.9g", x.rms) << ", \"max_residual\": " << fmt("%.9g", x.max_residual)
        << ", \"noise_estimate\": " << fmt("%.9g", x.noise_sigma) << ", \"outliers\": " << x.outliers
        << ", \"noise_reached\": " << (x.fit_status == fitting::AdaptiveFitResult::Status::OK ? "true" : "false");
    }
    j << "}";
  }
  j << "],\n \"counts\": {";
  const compensation::PointStatus all[] = {compensation::PointStatus::Ok,        compensation::PointStatus::Outlier,
                                           compensation::PointStatus::Edge,      compensation::PointStatus::FewPoints,
                                           compensation::PointStatus::NotOnModel, compensation::PointStatus::Failed};
  for (std::size_t s = 0; s < std::size(all); ++s) {
    j << (s ? ", " : "") << "\"" << compensation::to_string(all[s]) << "\": " << r.count(all[s]);
  }
  const compensation::StageSeconds& t = r.seconds;
  j << ", \"total\": " << r.points.size() << "},\n \"seconds\": {\"read\": " << fmt("%.4f", read_seconds)
    << ", \"material_side\": " << fmt("%.4f", t.material_side) << ", \"offset\": " << fmt("%.4f", t.offset)
    << ", \"registration\": " << fmt("%.4f", t.registration) << ", \"fitting\": " << fmt("%.4f", t.fitting)
    << ", \"compensation\": " << fmt("%.4f", t.compensation) << ", \"deviation\": " << fmt("%.4f", t.deviation)
    << ", \"write\": " << fmt("%.4f", write_seconds) << "}}\n";
  return j.str();
}

std::string html_report(const std::string& cad, const std::string& points, const compensation::CompensationResult& r) {
  std::vector<double> d;
  for (const auto& p : r.points) {
    if (p.status == compensation::PointStatus::Ok) d.push_back(p.deviation);
  }
  std::sort(d.begin(), d.end());
  auto quantile = [&](double q) { return d.empty() ? 0.0 : d[static_cast<std::size_t>(q * (d.size() - 1))]; };
  std::ostringstream h;
  h << "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>probecomp report</title></head><body>\n"
    << "<h1>probecomp: " << compensation::to_string(r.method) << " compensation</h1>\n<p>CAD: " << cad
    << "<br>points: " << points << " (" << r.points.size() << ")</p>\n"
    << "<h2>Registration</h2><p>" << registration::to_string(r.registration.status) << ": "
    << r.registration.stop_reason << "; RMS " << fmt("%.6f", r.registration.rms) << " mm</p>\n"
    << "<h2>Deviation of trusted points from the registered nominal (mm)</h2><table border=1>"
    << "<tr><th>min</th><th>5 %</th><th>median</th><th>95 %</th><th>max</th></tr><tr>";
  for (double q : {0.0, 0.05, 0.5, 0.95, 1.0}) h << "<td>" << fmt("%.6f", quantile(q)) << "</td>";
  h << "</tr></table>\n<h2>Faces</h2><table border=1><tr><th>face</th><th>points</th><th>fitted</th><th>control "
       "points</th><th>rounds</th><th>RMS residual (mm)</th><th>noise (mm)</th><th>outliers</th></tr>\n";
  for (const auto& f : r.faces) {
    h << "<tr><td>" << f.face << "</td><td>" << f.points << "</td><td>" << (f.fitted ? "yes" : "no") << "</td><td>"
      << f.control_points << "</td><td>" << f.rounds << "</td><td>" << fmt("%.6f", f.rms) << "</td><td>"
      << fmt("%.6f", f.noise_sigma) << "</td><td>" << f.outliers << "</td></tr>\n";
  }
  h << "</table></body></html>\n";
  return h.str();
}

struct Loaded {
  io::PointTable table;
  cad::Model model;
  double seconds = 0.0;
};

Loaded load(const std::string& cad_path, const std::string& points_path, double r) {
  check_probe_radius(r);
  const auto t0 = Clock::now();
  Loaded l{io::read_points(points_path), cad::read_model(cad_path), 0.0};
  l.seconds = since(t0);
  return l;
}

compensation::CompensationResult run_pipeline(const Loaded& l, double r, compensation::Method method, bool quiet) {
  compensation::CompensateOptions o;
  o.method = method;
  o.probe_radius = r;
  o.progress = Progress{Clock::now(), quiet};
  std::optional<std::span<const Vector3>> normals;
  if (l.table.normals) normals = std::span<const Vector3>(*l.table.normals);
  return compensation::compensate(l.model, l.table.points, normals, o);
}

void write_outputs(const CompensateArgs& a, const io::PointTable& table, const compensation::CompensationResult& r,
                   double read_seconds) {
  const auto t0 = Clock::now();
  const std::string text = !a.output.empty() && io::is_dmis(a.output) ? dmis_output(table, r, a.points) : csv_output(table, r);
  if (!a.report.empty()) io::write_file_atomically(a.report, html_report(a.cad, a.points, r));
  if (a.output.empty()) {
    std::cout << text;
  } else {
    io::write_file_atomically(a.output, text);
  }
  if (!a.json.empty()) io::write_file_atomically(a.json, json_stats(r, read_seconds, since(t0)));
}

void print_summary_row(std::ostream& out, const char* name, const studies::ErrorSummary& s) {
  char line[200];
  std::snprintf(line, sizeof line, "  %-24s %10.6f %10.6f %10.6f %10.6f\n", name, s.std, s.mean, s.min + 0.0, s.max + 0.0);
  out << line;
}

}  // namespace

int run_compensate(const CompensateArgs& a) {
  const Loaded l = load(a.cad, a.points, a.probe_radius);
  const compensation::Method method = a.method == "conventional" ? compensation::Method::Conventional : compensation::Method::Cad;
  const compensation::CompensationResult r = run_pipeline(l, a.probe_radius, method, a.quiet);
  write_outputs(a, l.table, r, l.seconds);
  return 0;
}

int run_fit(const FitArgs& a) {
  if (!has_extension(a.output, {".igs", ".iges", ".stp", ".step"})) {
    throw std::invalid_argument("--output must end in .igs, .iges, .stp or .step (the fitted surfaces as NURBS)");
  }
  const Loaded l = load(a.cad, a.points, a.probe_radius);
  const compensation::CompensationResult r = run_pipeline(l, a.probe_radius, compensation::Method::Cad, a.quiet);
  const std::vector<nurbs::Surface> surfaces = compensation::fitted_part_surfaces(r, a.probe_radius);
  if (surfaces.empty()) {
    throw std::invalid_argument("no face holds enough points for a fit, so there is no measured surface to write");
  }
  const auto t0 = Clock::now();
  cad::write_surfaces(a.output, surfaces);
  if (!a.json.empty()) io::write_file_atomically(a.json, json_stats(r, l.seconds, since(t0)));
  return 0;
}

std::string freeform_report(const studies::FreeformStudyResult& r) {
  const studies::PaperTable2 paper = studies::paper_table2();
  const simulation::FreeformCase& c = r.freeform;
  std::ostringstream t;
  t << "The paper's free-form case (§7.3, Table 2), built in.\n"
    << "A rational bicubic panel 100 x 50 mm, deformed by a broad bulge (+0.25 mm) and a dent (-1 mm, about 6 mm\n"
    << "across, flanks up to 14 deg), misaligned 0.2 mm in z and 1.5 deg about y; " << r.plan.size()
    << " points on a 120 x 60 grid,\nprobe radius " << c.probe_radius << " mm, noise sigma " << 1000 * c.noise_sigma
    << " um. The probe travels along each nominal normal until its tip touches the actual part.\n\n"
    << "Compensation error: signed distance of each compensated point from the actual surface (mm)\n";
  char line[200];
  std::snprintf(line, sizeof line, "  %-24s %10s %10s %10s %10s\n", "", "std", "mean", "min", "max");
  t << line;
  print_summary_row(t, "conventional (probecomp)", r.conventional_summary);
  print_summary_row(t, "conventional (paper)", paper.conventional);
  print_summary_row(t, "CAD-based (probecomp)", r.cad_summary);
  print_summary_row(t, "CAD-based (paper)", paper.proposed);
  const auto& face = r.cad.faces.front();
  t << "\nCAD-based: registration " << registration::to_string(r.cad.registration.status) << " in "
    << r.cad.registration.iterations << " iterations; fit " << face.control_points << " control points after "
    << face.rounds << " refinement rounds, RMS residual " << fmt("%.2f", 1000 * face.rms) << " um, noise estimate "
    << fmt("%.2f", 1000 * face.noise_sigma) << " um; " << r.cad.count(compensation::PointStatus::Ok) << " of "
    << r.cad.points.size() << " points ok.\n"
    << "Timings: simulation " << fmt("%.2f", r.simulate_seconds) << " s, CAD-based compensation "
    << fmt("%.2f", r.cad_seconds) << " s, conventional " << fmt("%.2f", r.conventional_seconds) << " s.\n";

  return t.str();
}

int run_demo(const DemoArgs& a) {
  const auto t0 = Clock::now();
  const studies::FreeformStudyResult r = studies::run_freeform_study();
  const double seconds = since(t0);
  const simulation::FreeformCase& c = r.freeform;
  std::ostringstream t;
  t << "probecomp demo: " << freeform_report(r);

  // The inputs and both outputs, so that `probecomp compensate` can be run on them by hand.
  std::filesystem::create_directories(a.output_dir);
  const std::filesystem::path dir(a.output_dir);
  cad::write_surfaces(dir / "nominal.igs", {c.nominal.faces.front().surface});
  io::PointTable table;  // raw.csv's layout: no carried columns, so csv_output reads no row fields
  table.columns = {"x", "y", "z", "i", "j", "k"};
  io::write_file_atomically(dir / "raw.csv", raw_points_csv(r.touches, r.plan, false));
  io::write_file_atomically(dir / "compensated_cad.csv", csv_output(table, r.cad));
  io::write_file_atomically(dir / "compensated_conventional.csv", csv_output(table, r.conventional));
  t << "\nWrote " << (dir / "nominal.igs").string() << ", raw.csv, compensated_cad.csv and compensated_conventional.csv\n"
    << "in " << dir.string() << "; rerun with:\n  probecomp compensate --cad " << (dir / "nominal.igs").string()
    << " --points " << (dir / "raw.csv").string() << " --probe-radius " << c.probe_radius << "\n"
    << "Total " << fmt("%.2f", since(t0)) << " s (" << fmt("%.2f", seconds) << " s of it simulating and compensating).\n";
  std::cout << t.str();
  return 0;
}

}  // namespace probecomp::cli
