#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "cli/measurement_program.hpp"
#include "probecomp/cad/plan.hpp"
#include "probecomp/cad/model.hpp"
#include "probecomp/inspection/characteristics.hpp"
#include "probecomp/compensation/conventional.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/geometry/stopwatch.hpp"
#include "probecomp/io/dmis.hpp"
#include "probecomp/io/format.hpp"
#include "probecomp/io/output_files.hpp"
#include "probecomp/probe/qualification_file.hpp"
#include "probecomp/io/point_files.hpp"
#include "probecomp/results/report.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/io/qif.hpp"
#include "probecomp/io/progress.hpp"
#include "probecomp/results/files.hpp"
#include "probecomp/results/statistics.hpp"
#include "probecomp/io/text.hpp"
#include "probecomp/io/transform_file.hpp"
#include "probecomp/studies/freeform_study.hpp"

namespace probecomp::cli {

namespace {

using io::fmt;
using geometry::Stopwatch;

// The whole command's share of time in reading the points and in writing the results (at 10 M points: read 8.8 s,
// compensation 49 s, write 8.3 s), for the progress bar's time left.
constexpr double kReadShare = 0.13;
constexpr double kWriteShare = 0.12;

bool has_extension(const std::string& path, std::initializer_list<const char*> extensions) {
  const std::string e = io::lower(std::filesystem::path(path).extension().string());
  return std::any_of(extensions.begin(), extensions.end(), [&](const char* x) { return e == x; });
}

// --tolerance's band, or the reason it is not one, naming the option.
results::Tolerance tolerance_band(const std::string& text) {
  try {
    return results::parse_tolerance(text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--tolerance: ") + e.what());
  }
}

struct Loaded {
  Stopwatch run;  // the whole command, from before reading
  io::PointTable table;
  cad::Model model;
  results::RunInputs inputs;  // the probe radius in mm
  std::vector<double> radii;  // each row's tip radius, mm (empty: inputs.probe_radius for every row)
  // --qualification: each stylus's radius by direction; rows then need no radius of their own or by default (NaN in
  // `radii` where a row has none).
  std::optional<probe::Qualification> qualification;
  geometry::RigidTransform initial = geometry::RigidTransform::Identity();  // CAD → machine, the registration's start
  double seconds = 0.0;
};

// Each row's tip radius in mm: its own where the file gives one, else the default (--probe-radius, mm). A row with
// neither is an InputError naming its line; so is a file without radii and no default (one problem, one kind).
std::vector<double> tip_radii(const io::PointTable& t, std::optional<double> default_mm, const std::string& path) {
  if (!t.radii) {
    if (!default_mm) {
      throw InputError("--probe-radius is needed: " + path +
                       " gives no tip radius of its own (a column r, DMIS SNSDEF/SNSLCT or QIF ProbeRadius)");
    }
    return {};
  }
  std::vector<double> radii = *t.radii;
  for (std::size_t k = 0; k < radii.size(); ++k) {
    if (!std::isnan(radii[k])) continue;
    if (!default_mm) {
      throw InputError(path + ":" + std::to_string(t.line[k]) +
                       ": this point has no tip radius (its r is empty) and no --probe-radius gives a default");
    }
    radii[k] = *default_mm;
  }
  return radii;
}

// The load step: the points (in their unit: --units, a DMIS UNITS statement, else mm) and the CAD model. The
// probe radius is in the points' unit, as a measurement program in inches states its styli.
Loaded load(const std::string& cad_path, const std::string& points_path, std::optional<double> r,
            const std::string& units, const std::string& initial_transform, io::ProgressBar& bar,
            const std::string& qualification = {}) {
  if (r) check_probe_radius(*r);
  Loaded l;
  if (!initial_transform.empty()) l.initial = io::read_transform(initial_transform);
  if (!qualification.empty()) l.qualification = probe::read_qualification(qualification);
  std::optional<io::LengthUnit> declared;
  if (!units.empty()) declared = io::length_unit(units);
  // The points and the model are read side by side (10 000 points: 4 ms and 3 ms). Each read's error is kept, and
  // the points' errors (their reading, then their tip radii) are reported before the model's, as when they were
  // read one after the other, whichever thread failed first.
  std::exception_ptr points_error, model_error;
  tbb::parallel_invoke(
      [&] {
        try {
          l.table = io::read_points(points_path, declared, [&](double f) { bar.update("reading", kReadShare * f); },
                                    io::NumberText::Drop);
        } catch (...) {
          points_error = std::current_exception();
        }
      },
      [&] {
        try {
          l.model = cad::Model::load(cad_path);
        } catch (...) {
          model_error = std::current_exception();
        }
      });
  if (points_error) std::rethrow_exception(points_error);
  bar.set_points(l.table.points.size());
  std::optional<double> default_mm;
  if (r) default_mm = *r * l.table.unit.mm;
  if (l.qualification) {
    // Which styli lack a radius is known only against the qualification (compensation/qualified_radii.hpp).
    if (l.table.radii) {
      l.radii = *l.table.radii;
      for (double& x : l.radii) {
        if (std::isnan(x) && default_mm) x = *default_mm;
      }
    }
  } else {
    l.radii = tip_radii(l.table, default_mm, points_path);  // its errors, too, before the model's
  }
  if (model_error) std::rethrow_exception(model_error);
  l.inputs = {.cad = cad_path, .points = points_path, .points_unit = l.table.unit, .probe_radius = default_mm};
  if (l.qualification) {
    // The qualified styli's sphere-fit radii, and the nominal radii of the rest.
    std::vector<double> radii = l.qualification->effective_radii();
    for (double x : l.radii) {
      if (!std::isnan(x)) radii.push_back(x);
    }
    if (default_mm) radii.push_back(*default_mm);
    l.inputs.tip_radii = results::distinct_radii(radii);
  } else if (l.radii.empty()) {
    l.inputs.tip_radii = {*default_mm};
  } else {
    l.inputs.tip_radii = results::distinct_radii(l.radii);
  }
  l.seconds = l.run.seconds();
  return l;
}

// `datum_faces`: the specification's datum features' faces, which locate the part when the best fit of all its
// points is doubtful (compensation::RegisterOptions::datum_faces).
compensation::CompensationResult run_pipeline(const Loaded& l, compensation::Method method, bool accept_doubtful,
                                              io::ProgressBar& bar, std::vector<int> datum_faces = {}) {
  compensation::CompensateOptions o;
  o.method = method;
  o.accept_doubtful_registration = accept_doubtful;
  o.datum_faces = std::move(datum_faces);
  o.probe_radius = l.inputs.tip_radii.front();
  o.probe_radii = l.radii;
  if (l.qualification) {
    o.qualification = &*l.qualification;
    o.styli = point_styli(l.table);
    o.probe_radius = l.inputs.probe_radius.value_or(0.0);
  }
  o.registration.initial = l.initial;
  o.progress = [&bar](const std::string& stage, double f) {
    if (stage == "done") return;  // for the command, writing comes next
    bar.update(stage, kReadShare + (1.0 - kReadShare - kWriteShare) * f);
  };
  std::optional<std::span<const Vector3>> normals;
  if (l.table.normals) normals = std::span<const Vector3>(*l.table.normals);
  compensation::CompensationResult result = compensation::compensate(l.model, l.table.points, normals, o);
  // Warnings go out even with --quiet: they change how the numbers are read.
  for (const std::string& w : result.warnings) bar.print("probecomp: warning: " + w);
  return result;
}

// The points to measure again (--replan), machine frame: each point of an indeterminate characteristic whose d ± U
// crosses a limit, at its contact along its fitted normal; and over the faces of one judged on too few trusted
// points, a plan of 10 to 40 points a face (a spacing halved from 8 mm until the face holds 10) at the registered
// nominal.
std::string replan_program(const CompensateArgs& a, const Loaded& l, const compensation::CompensationResult& r,
                           const inspection::Inspection& inspection) {
  std::vector<cli::ProgrammedTouch> touches;
  std::set<std::size_t> rows;
  std::set<int> faces;
  std::vector<std::string> comments;
  for (const inspection::CharacteristicResult& c : inspection.characteristics) {
    if (c.decision == inspection::Decision::Indeterminate) {
      rows.insert(c.undecided.begin(), c.undecided.end());
      // DMIS is ASCII: "+-", not the plus-minus sign.
      comments.push_back(c.spec.name + ": indeterminate: measure again the points whose d +- U cross a limit (" +
                         std::to_string(c.undecided.size()) + ")");
    } else if (c.too_few_points) {
      faces.insert(c.spec.faces.begin(), c.spec.faces.end());
      comments.push_back(c.spec.name + ": " + c.reason + "; its faces planned");
    }
  }
  for (std::size_t k : rows) {
    const compensation::CompensatedPoint& p = r.points[k];
    touches.push_back({std::string("R").append(std::to_string(k + 1)), p.contact, p.normal});
  }
  const geometry::RigidTransform& T = r.registration.transform;
  for (int f : faces) {
    std::vector<cad::PlannedPoint> plan;
    for (double spacing = 8.0; spacing > 0.2; spacing /= 2) {
      plan = cad::plan_points(l.model, spacing, {f});
      if (plan.size() >= 10) break;
    }
    const std::size_t stride = std::max<std::size_t>(1, (plan.size() + 39) / 40);
    for (std::size_t k = 0; k < plan.size(); k += stride) {
      touches.push_back({std::string("F").append(std::to_string(f)).append("_").append(std::to_string(k / stride + 1)), T * plan[k].point,
                         T.linear() * plan[k].normal});
    }
  }
  if (touches.empty()) comments.push_back("nothing to measure again: every characteristic was decided");
  return cli::dmis_measurement_program("probecomp re-measurement for " + a.characteristics, touches, comments);
}

// The write step: the points (CSV, DMIS or QIF, by the extension), the report and the statistics, all or none
// (standard output last, once every file is in place).
void write_outputs(const CompensateArgs& a, const Loaded& l, const compensation::CompensationResult& r,
                   const inspection::Inspection& inspection, io::ProgressBar& bar) {
  bar.update("writing", 1.0 - kWriteShare);
  const Stopwatch clock;
  // CSV, the usual output of a scan, goes to its file block by block; DMIS and QIF are built whole.
  const io::PointFormat format = io::point_format(a.output);
  const bool qif = format == io::PointFormat::Qif, dmis = !a.output.empty() && format == io::PointFormat::Dmis;
  const std::string text = qif ? results::compensated_qif(l.table, r, a.points, &inspection)
                           : dmis ? results::compensated_dmis(l.table, r, a.points)
                                  : std::string();
  std::optional<results::Tolerance> tolerance;
  if (!a.tolerance.empty()) tolerance = tolerance_band(a.tolerance);
  io::OutputFiles files;
  if (!a.output.empty() && !qif && !dmis) {
    files.add_streamed(a.output, [&](std::ostream& out) {
      results::write_compensated_csv(out, l.table, r, [&](double f) { bar.update("writing", 1.0 - kWriteShare * (1.0 - f)); });
    });
  } else if (!a.output.empty()) {
    files.add(a.output, text);
  }
  const results::FileTimings timings{.read = l.seconds, .write = clock.seconds(), .total = l.run.seconds()};
  if (!a.report.empty()) {
    results::ReportContext context{.inputs = l.inputs, .tolerance = tolerance, .timings = timings};
    context.inspection = &inspection;
    context.nominal = results::registered_outline(l.model, r.registration.transform);
    if (l.table.normals) {
      std::vector<double> each;
      if (r.qualified_radii()) {
        for (const compensation::CompensatedPoint& p : r.points) each.push_back(p.radius);
      }
      const geometry::TipRadii radii = r.qualified_radii() ? geometry::TipRadii(each)
                                       : l.radii.empty() ? geometry::TipRadii(l.inputs.tip_radii.front())
                                                         : geometry::TipRadii(l.radii);
      context.conventional = compensation::conventional_contact_points(l.table.points, *l.table.normals, radii);
    }
    files.add(a.report, results::html_report(r, context));
  }
  if (!a.json.empty()) files.add(a.json, results::statistics_json(r, l.inputs, timings, tolerance, &inspection));
  if (!a.replan.empty()) files.add(a.replan, replan_program(a, l, r, inspection));
  files.commit();
  if (a.output.empty()) results::write_compensated_csv(std::cout, l.table, r);
  bar.update("done", 1.0);
}

void print_summary_row(std::ostream& out, const char* name, const studies::ErrorSummary& s) {
  char line[200];
  std::snprintf(line, sizeof line, "  %-24s %10.6f %10.6f %10.6f %10.6f\n", name, s.std, s.mean, s.min + 0.0, s.max + 0.0);
  out << line;
}

}  // namespace

int run_compensate(const CompensateArgs& a) {
  if (!a.replan.empty()) {
    if (a.characteristics.empty()) throw std::invalid_argument("--replan needs --characteristics: it re-plans where they are undecided");
    if (!has_extension(a.replan, {".dmi"})) throw std::invalid_argument("--replan must end in .dmi (a DMIS part program)");
  }
  io::check_outputs_spare_inputs({{"--output", a.output}, {"--json", a.json}, {"--report", a.report}, {"--replan", a.replan}},
                                 {{"--cad", a.cad}, {"--points", a.points}, {"--initial-transform", a.initial_transform},
                                  {"--characteristics", a.characteristics == "pmi" ? std::string() : a.characteristics},
                                  {"--qualification", a.qualification}});
  if (!a.tolerance.empty()) (void)tolerance_band(a.tolerance);  // a bad band fails before the run
  io::ProgressBar bar(a.quiet);
  const Loaded l = load(a.cad, a.points, a.probe_radius, a.units, a.initial_transform, bar, a.qualification);
  // The characteristics are read before the run, so that a bad specification fails before it.
  inspection::Specification spec;
  if (!a.characteristics.empty()) {
    inspection::LoadedSpecification loaded;
    try {
      loaded = inspection::load_specification(a.characteristics, l.model);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("--characteristics " + a.characteristics + ": " + e.what());
    }
    for (const std::string& w : loaded.warnings) bar.print("probecomp: warning: " + w);
    spec = std::move(loaded.spec);
  }
  const compensation::Method method = a.method == "conventional" ? compensation::Method::Conventional : compensation::Method::Cad;
  const compensation::CompensationResult r =
      run_pipeline(l, method, a.accept_doubtful_registration, bar, inspection::datum_faces(spec));
  const inspection::Inspection judged = inspection::evaluate(spec, l.model, r);
  // One line each on standard error, even with --quiet: the decisions are what the run was for.
  for (const inspection::CharacteristicResult& c : judged.characteristics) {
    std::string line = "probecomp: " + c.spec.name + ": " + inspection::to_string(c.decision);
    if (c.decision == inspection::Decision::NotEvaluated) {
      line += " (" + c.reason + ")";
    } else {
      char figures[160];
      std::snprintf(figures, sizeof figures, " (value %.4f mm, U %.4f mm, tolerance %.4f mm, %d points)", c.value, c.u,
                    c.spec.tolerance, c.points);
      line += figures;
      if (c.decision == inspection::Decision::Indeterminate) line += ": " + c.reason;
    }
    bar.print(line);
  }
  if (judged.alignment_frame) {
    // The whole output in the datum frame the specification asks for, or none: a best fit in its place would be
    // read as that frame.
    if (!judged.alignment_frame->ok()) {
      throw std::invalid_argument(a.characteristics + ": alignment " + judged.alignment + ": " + judged.alignment_frame->reason);
    }
    write_outputs(a, l, inspection::aligned(r, *judged.alignment_frame, l.model), judged, bar);
    return 0;
  }
  write_outputs(a, l, r, judged, bar);
  return 0;
}

int run_fit(const FitArgs& a) {
  if (!has_extension(a.output, {".igs", ".iges", ".stp", ".step"})) {
    throw std::invalid_argument("--output must end in .igs, .iges, .stp or .step (the fitted surfaces as NURBS)");
  }
  io::check_outputs_spare_inputs({{"--output", a.output}, {"--json", a.json}},
                                 {{"--cad", a.cad}, {"--points", a.points}, {"--initial-transform", a.initial_transform}});
  io::ProgressBar bar(a.quiet);
  const Loaded l = load(a.cad, a.points, a.probe_radius, a.units, a.initial_transform, bar);
  const compensation::CompensationResult r = run_pipeline(l, compensation::Method::Cad, a.accept_doubtful_registration, bar);
  const std::vector<nurbs::Surface> surfaces = compensation::fitted_part_surfaces(r);
  if (surfaces.empty()) {
    throw FitError("no face holds enough points for a fit, so there is no measured surface to write");
  }
  const Stopwatch clock;
  io::OutputFiles files;
  files.add(a.output, [&](const std::filesystem::path& temporary) { cad::write_surfaces(temporary, surfaces); });
  if (!a.json.empty()) {
    files.add(a.json, results::statistics_json(r, l.inputs, {.read = l.seconds, .write = clock.seconds(), .total = l.run.seconds()}));
  }
  files.commit();
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
    << "Uncertainty u (k = 1) of the CAD-based points: mean " << fmt("%.2f", 1000 * r.mean_uncertainty)
    << " um; the true error is within +-2u at " << fmt("%.1f", 100 * r.coverage_2u) << " % of the ok points ("
    << fmt("%.1f", 100 * r.worst_region_coverage_2u) << " % in the worst of 4 x 4 regions).\n"
    << "Fit: " << fmt("%.0f", face.effective_dof) << " effective parameters, smoothing 10^" << fmt("%.2f", face.log10_smoothing)
    << ".\n"
    << "Timings: simulation " << fmt("%.2f", r.simulate_seconds) << " s, CAD-based compensation "
    << fmt("%.2f", r.cad_seconds) << " s, conventional " << fmt("%.2f", r.conventional_seconds) << " s.\n";

  return t.str();
}

int run_demo(const DemoArgs& a) {
  const Stopwatch clock;
  const studies::FreeformStudyResult r = studies::run_freeform_study();
  const double seconds = clock.seconds();
  const simulation::FreeformCase& c = r.freeform;
  std::ostringstream t;
  t << "probecomp demo: " << freeform_report(r);

  // The inputs and both outputs, so that `probecomp compensate` can be run on them by hand.
  std::filesystem::create_directories(a.output_dir);
  const std::filesystem::path dir(a.output_dir);
  io::OutputFiles files;
  files.add(dir / "nominal.igs", [&](const std::filesystem::path& temporary) {
    cad::write_surfaces(temporary, {c.nominal.faces.front().surface});
  });
  io::PointTable table;  // raw.csv's layout: no carried columns, so compensated_csv reads no row fields
  table.columns = {"x", "y", "z", "i", "j", "k"};
  files.add(dir / "raw.csv", raw_points_csv(r.touches, r.plan, false));
  files.add(dir / "compensated_cad.csv", results::compensated_csv(table, r.cad));
  files.add(dir / "compensated_conventional.csv", results::compensated_csv(table, r.conventional));
  // The report an inspector would read, against a ±0.05 mm band: the bump and the dent the simulation put into the
  // part stand out of it.
  results::ReportContext context{.inputs = {.cad = (dir / "nominal.igs").string(), .points = (dir / "raw.csv").string(),
                                       .probe_radius = c.probe_radius, .tip_radii = {c.probe_radius}},
                            .tolerance = results::Tolerance{-0.05, 0.05},
                            .timings = {.total = seconds}};
  context.nominal = results::registered_outline(c.nominal, r.cad.registration.transform);
  std::vector<Point3> conventional;
  for (const compensation::CompensatedPoint& p : r.conventional.points) conventional.push_back(p.contact);
  context.conventional = std::move(conventional);
  files.add(dir / "report.html", results::html_report(r.cad, context));
  files.commit();
  t << "\nWrote " << (dir / "nominal.igs").string()
    << ", raw.csv, compensated_cad.csv, compensated_conventional.csv and report.html\n"
    << "in " << dir.string() << "; rerun with:\n  probecomp compensate --cad " << (dir / "nominal.igs").string()
    << " --points " << (dir / "raw.csv").string() << " --probe-radius " << c.probe_radius
    << " --report report.html --tolerance -0.05,0.05\n"
    << "Total " << fmt("%.2f", clock.seconds()) << " s (" << fmt("%.2f", seconds) << " s of it simulating and compensating).\n";
  std::cout << t.str();
  return 0;
}

}  // namespace probecomp::cli
