// probecomp command-line tool: compensate, fit and demo (the method end to end), info, project and plan on CAD
// models, the paper's studies.
// Every failure is one line on standard error ("probecomp: FILE:LINE: cause") and an exit status that says
// what kind (kExit* below); output files are written whole or not at all.

#include <CLI/CLI.hpp>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/model.hpp"
#include "probecomp/cad/pmi.hpp"
#include "probecomp/cad/plan.hpp"
#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "cli/measurement_program.hpp"
#include "probecomp/io/format.hpp"
#include "probecomp/io/json.hpp"
#include "probecomp/io/output_files.hpp"
#include "probecomp/io/point_files.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/error.hpp"
#include "probecomp/selftest/selftest.hpp"
#include "probecomp/temporary_files.hpp"
#include "probecomp/version.hpp"

namespace {

using namespace probecomp;

// Exit statuses, one per kind of failure (docs/cli.md, "Exit status"); CLI11's own for a malformed command line.
constexpr int kExitFailure = 1;       // anything else (a bug, or the system: memory, a file that cannot be written)
constexpr int kExitUsage = 2;         // an option's value the command cannot use
constexpr int kExitInput = 3;         // probecomp::InputError: points or options the method cannot use
constexpr int kExitCad = 4;           // probecomp::CadError: a CAD file that cannot be read or used
constexpr int kExitRegistration = 5;  // probecomp::RegistrationError
constexpr int kExitFit = 6;           // probecomp::FitError
using cli::fmt;
using cli::mm;
using cli::unit;


// Writes to the file (whole or not at all, io::OutputFiles) or to standard output when no file is given.
void emit(const std::string& output, const std::string& text) {
  if (output.empty()) {
    std::cout << text;
    return;
  }
  io::OutputFiles file;
  file.add(output, text);
  file.commit();
}

}  // namespace

probecomp::cad::Model probecomp::cli::read_part(const std::string& path) {
  cad::Model model = cad::read_model(path);
  for (const std::string& w : model.read_warnings) std::cerr << "probecomp: warning: " << path << ": " << w << '\n';
  return model;
}

namespace {

int run_selftest() {
  std::cout << "probecomp " << version() << " selftest: known answers computed on this machine\n";
  int failed = 0, total = 0;
  const auto print = [&](const selftest::Check& c) {
    ++total;
    failed += !c.passed();
    char numbers[96];
    std::snprintf(numbers, sizeof numbers, "error %9.2e %s  limit %7.1e %s", c.error, c.unit.c_str(), c.limit, c.unit.c_str());
    std::cout << (c.passed() ? "  ok    " : "  FAIL  ") << numbers << "  " << c.name
              << (c.detail.empty() ? "" : " (" + c.detail + ")") << '\n' << std::flush;
  };
  (void)selftest::run_selftest(print);
  std::cout << "probecomp selftest: " << total - failed << " of " << total << " checks passed\n";
  return failed == 0 ? 0 : kExitFailure;
}

int run_info(const std::string& part, bool json) {
  const cad::Model model = cli::read_part(part);
  // The file's semantic PMI (STEP AP242): geometric tolerances, their faces and datums.
  const cad::Pmi pmi = cad::read_pmi(part, model);
  for (const std::string& w : pmi.warnings) std::cerr << "probecomp: warning: " << part << ": " << w << '\n';
  int rational = 0, trimmed = 0, solid = 0;
  for (const cad::Face& f : model.faces) {
    rational += f.surface.is_rational();
    trimmed += f.trimmed();
    solid += f.material_known;
  }
  std::ostringstream out;
  if (json) {
    const auto corner = [](const Point3& p) {
      return io::Json::array({io::json_fixed(p.x(), 9), io::json_fixed(p.y(), 9), io::json_fixed(p.z(), 9)});
    };
    io::Json faces = io::Json::array();
    for (const cad::Face& f : model.faces) {
      const BoundingBox b = nurbs::bounding_box(f.surface);
      faces.push_back({{"index", f.index},
                       {"name", f.name},
                       {"type", f.source_type},
                       {"degree", {f.surface.p(), f.surface.q()}},
                       {"poles", {f.surface.num_u(), f.surface.num_v()}},
                       {"rational", f.surface.is_rational()},
                       {"trimmed", f.trimmed()},
                       {"material_side", f.material_known ? "solid" : "unknown"},
                       {"bbox", {{"min", corner(b.min)}, {"max", corner(b.max)}}}});
    }
    const io::Json info = {{"file", part},
                           {"units", "mm"},
                           {"file_units", model.file_units},
                           {"faces", faces},
                           {"totals",
                            {{"faces", model.faces.size()}, {"rational", rational}, {"trimmed", trimmed}, {"in_solids", solid}}}};
    io::Json info_out = info;
    io::Json tolerances = io::Json::array();
    for (const cad::GeometricTolerance& t : pmi.tolerances) {
      tolerances.push_back({{"type", cad::to_string(t.type)},
                            {"value", t.value ? io::json_number(*t.value, 9) : io::Json(nullptr)},
                            {"faces", t.faces},
                            {"datums", t.datums}});
      if (t.outside) tolerances.back()["outside"] = io::json_number(*t.outside, 9);
    }
    io::Json features = io::Json::array();
    for (const cad::DatumFeature& d : pmi.datum_features) {
      io::Json points = io::Json::array(), lines = io::Json::array();
      const auto triple = [](const Vector3& v) {
        return io::Json::array({io::json_number(v.x(), 9), io::json_number(v.y(), 9), io::json_number(v.z(), 9)});
      };
      for (const cad::DatumTarget& t : d.targets) {
        if (t.line()) {
          lines.push_back({{"number", t.number}, {"point", triple(t.point)}, {"direction", triple(t.direction)},
                           {"length", io::json_number(t.length, 9)}, {"face", t.face}});
        } else {
          points.push_back({{"number", t.number}, {"point", triple(t.point)}, {"face", t.face}});
        }
      }
      features.push_back({{"name", d.name}, {"faces", d.faces}, {"area_targets", d.area_targets},
                          {"point_targets", points}, {"line_targets", lines},
                          {"point_or_line_targets", d.point_or_line_targets}});
    }
    info_out["pmi"] = {{"datums", pmi.datums}, {"datum_features", features}, {"tolerances", tolerances},
                       {"warnings", pmi.warnings}};
    out << io::json_text(info_out);
  } else {
    out << "# " << part << ": units mm (file: " << model.file_units << ")\n";
    out << "# face  type        degree  poles     rational  trimmed  material  bbox min (mm)  bbox max (mm)\n";
    for (const cad::Face& f : model.faces) {
      const BoundingBox b = nurbs::bounding_box(f.surface);
      char line[512];
      std::snprintf(line, sizeof line, "%6d  %-10s  %dx%-4d  %4dx%-4d  %-8s  %-7s  %-8s  %.3f %.3f %.3f  %.3f %.3f %.3f%s%s\n",
                    f.index, f.source_type.c_str(), f.surface.p(), f.surface.q(), f.surface.num_u(), f.surface.num_v(),
                    f.surface.is_rational() ? "yes" : "no", f.trimmed() ? "yes" : "no",
                    f.material_known ? "solid" : "unknown", b.min.x(), b.min.y(), b.min.z(), b.max.x(), b.max.y(),
                    b.max.z(), f.name.empty() ? "" : "  ", f.name.c_str());
      out << line;
    }
    out << "total: " << model.faces.size() << " faces, " << rational << " rational, " << trimmed << " trimmed, " << solid
        << " on solids; units mm (file: " << model.file_units << ")\n";
    if (!pmi.tolerances.empty()) {
      std::map<std::string, int> by_type;
      int unread = 0;
      for (const cad::GeometricTolerance& t : pmi.tolerances) {
        ++by_type[cad::to_string(t.type)];
        unread += !t.value;
      }
      out << "PMI: " << pmi.tolerances.size() << " geometric tolerances (";
      bool first = true;
      for (const auto& [type, n] : by_type) {
        out << (first ? "" : ", ") << n << ' ' << type;
        first = false;
      }
      out << "), " << pmi.datums.size() << " datums";
      if (unread > 0) out << "; " << unread << " magnitudes not read";
      out << '\n';
    }
  }
  std::cout << out.str();
  return 0;
}

int run_project(const std::string& part, const std::string& points_file, const std::string& units,
                const std::string& output) {
  io::check_outputs_spare_inputs({{"--output", output}}, {{"PART", part}, {"--points", points_file}});
  // Unstated, the unit is the file's own (a "# lengths in UNIT" line, DMIS UNITS, QIF LinearUnit), else mm.
  const io::PointTable table = io::read_points(points_file, units.empty() ? std::nullopt : io::length_unit(units));
  const double scale = 1.0 / table.unit.mm;  // mm → the points' unit
  const cad::Model model = cli::read_part(part);
  const cad::ModelLocator locator(model);
  const std::vector<cad::ModelPoint> found = locator.closest_points(table.points);
  std::ostringstream out;
  const std::vector<std::string> ours{"x", "y", "z", "nx", "ny", "nz", "distance", "face", "u", "v", "status"};
  out << "x,y,z,nx,ny,nz,distance,face,u,v,status" << table.carried_header(ours) << '\n';
  for (std::size_t k = 0; k < found.size(); ++k) {
    const cad::ModelPoint& m = found[k];
    if (m.ok()) {
      out << mm(scale * m.point.x()) << ',' << mm(scale * m.point.y()) << ',' << mm(scale * m.point.z()) << ','
          << unit(m.normal.x()) << ',' << unit(m.normal.y()) << ',' << unit(m.normal.z()) << ','
          << mm(scale * m.distance) << ',' << m.face << ','
          << unit(m.u) << ',' << unit(m.v) << ',' << (m.on_trim_edge ? "trim-edge" : "ok");
    } else {
      // Never dropped: the row is there, empty, with the reason.
      out << ",,,,,,,,,," << nurbs::to_string(m.status);
    }
    out << table.carried_fields(k);
    out << '\n';
  }
  emit(output, out.str());
  return 0;
}

int run_plan(const std::string& part, double spacing, const std::string& face_list, const std::string& output) {
  io::check_outputs_spare_inputs({{"--output", output}}, {{"PART", part}});
  const bool dmis = output.size() > 4 && (output.ends_with(".dmi") || output.ends_with(".DMI"));
  const std::vector<int> faces = cli::parse_face_list(face_list);
  const cad::Model model = cli::read_part(part);
  const std::vector<cad::PlannedPoint> plan = cad::plan_points(model, spacing, faces);
  if (plan.empty()) throw std::invalid_argument("no points fit on the chosen faces at spacing " + mm(spacing) + " mm");
  // A face that bounds no closed solid has no known material side: its normals follow the file's orientation
  // (S_u × S_v, or its reverse when the face is reversed in its shell), which may point into the material. Said,
  // never silent: a program measured along inward normals drives the probe through the part.
  std::set<int> unknown;
  for (const cad::PlannedPoint& p : plan) {
    if (!model.faces[static_cast<std::size_t>(p.face)].material_known) unknown.insert(p.face);
  }
  if (!unknown.empty()) {
    std::cerr << "probecomp: warning: " << unknown.size() << " of the planned faces (" << *unknown.begin()
              << (unknown.size() > 1 ? ", ..." : "") << ") bound no closed solid: their normals follow the file's "
              << "orientation and may point into the material; check them before measuring\n";
  }
  std::ostringstream out;
  if (dmis) {
    std::vector<cli::ProgrammedTouch> touches;
    for (std::size_t k = 0; k < plan.size(); ++k) {
      touches.push_back({std::string("P").append(std::to_string(k + 1)), plan[k].point, plan[k].normal});
    }
    out << cli::dmis_measurement_program("probecomp measurement plan for " + part, touches);
  } else {
    out << "x,y,z,i,j,k,face\n";
    for (const auto& p : plan) {
      out << mm(p.point.x()) << ',' << mm(p.point.y()) << ',' << mm(p.point.z()) << ',' << unit(p.normal.x()) << ','
          << unit(p.normal.y()) << ',' << unit(p.normal.z()) << ',' << p.face << '\n';
    }
  }
  emit(output, out.str());
  return 0;
}

// The words a Hint (probecomp/error.hpp) takes on the command line: the options that act on it.
std::string hint_words(Hint hint) {
  switch (hint) {
    case Hint::InitialTransform:
      return ". Give a rough alignment with --initial-transform T.txt (4 x 4, CAD -> machine), or check the CAD file, "
             "the frame and the probe radius";
    case Hint::InitialTransformOrAcceptDoubtful:
      return ". Give a rough alignment with --initial-transform T.txt (4 x 4, CAD -> machine); if the part really "
             "deviates from its model by about the probe radius, --accept-doubtful-registration runs on with a warning";
    case Hint::DeclaredUnit: return " as --units says";
    case Hint::None: break;
  }
  return "";
}

}  // namespace

constexpr const char* kProbeRadiusHelp =
    "Tip radius, in the points' unit (mm unless --units or the file says otherwise): of every point, or of those "
    "without one of their own (a column r, DMIS SNSDEF/SNSLCT, QIF ProbeRadius); needed unless every point has one";

constexpr const char* kUnitsHelp =
    "Length unit of the point file, mm or inch (default: the file's own, which must agree: a DMIS UNITS statement, "
    "QIF FileUnits, a CSV '# lengths in UNIT' line; else mm); "
    "outputs for the points use it too, --json stays in mm";

constexpr const char* kInitialTransformHelp =
    "T.txt: where the part roughly is, as a 4 x 4 matrix CAD -> machine (4 lines of 4 numbers, mm; the convention of "
    "--json's transform). Default: the identity, and a coarse alignment (multi-start ICP) when the registration from "
    "it is not credible";
constexpr const char* kAcceptDoubtfulHelp =
    "Run on when the registration stays doubtful after the coarse alignment (many tip centres inside the material, "
    "large residuals): for a part that really deviates from its model by about the probe radius. Without it such a "
    "run stops with exit status 5";

int main(int argc, char** argv) {
#if defined(__GLIBC__)
  // Arrays of a megabyte or more (a scan's points, matches, fit arrays) get pages of their own, given back when
  // freed. Without a fixed threshold glibc raises it after each such free and serves later large arrays from its
  // heaps, where freed room is kept: a million points then peaked anywhere from 370 to 460 MB, run to run.
  mallopt(M_MMAP_THRESHOLD, 1 << 20);
#endif
  // Ctrl-C or a job scheduler's SIGTERM: no half-written output left behind.
  probecomp::remove_temporaries_on_termination();
  CLI::App app{
      "probecomp: CAD-based contact-probe radius compensation for CMM data.\n"
      "Turns raw probe-centre points into contact points and deviations using the part's NURBS model.",
      "probecomp"};
  app.set_version_flag("--version", "probecomp " + probecomp::version());
  app.require_subcommand(0, 1);

  std::string part, points, output, faces;
  bool json = false;
  double spacing = 0.0;

  CLI::App* info = app.add_subcommand("info", "List the faces of a STEP or IGES model (geometry in mm).");
  info->add_option("part", part, "CAD file (.stp, .step, .igs, .iges)")->required();
  info->add_flag("--json", json, "Print a JSON object: units and one object per face");

  CLI::App* project = app.add_subcommand(
      "project", "Closest point on the model for each point (find nominals): x,y,z,nx,ny,nz,distance,face,u,v,status.");
  project->add_option("--cad", part, "CAD file")->required();
  project->add_option("--points", points, "Points: CSV with a header naming x,y,z (other columns are carried), DMIS or QIF")
      ->required();
  project->add_option("--output", output, "Output CSV (default: standard output)");
  std::string project_units;
  project->add_option("--units", project_units,
                      "Length unit of the point file and the output, mm or inch (default: the file's own, else mm)")
      ->check(CLI::IsMember({"mm", "inch"}));

  CLI::App* plan = app.add_subcommand("plan", "Nominal measurement points with outward normals on the model's faces.");
  plan->add_option("part", part, "CAD file")->required();
  plan->add_option("--spacing", spacing, "Distance between points along the surface, mm")->required();
  plan->add_option("--faces", faces, "Faces to plan on, e.g. 0,3,5-9 (default: all)");
  plan->add_option("--output", output, "PLAN.csv (x,y,z,i,j,k,face) or PLAN.dmi (DMIS PTMEAS program); default: CSV on standard output");

  cli::StudyArgs study_args;
  CLI::App* study = app.add_subcommand(
      "study", "Reproduce a study of the paper (DESIGN.md section 3); prints a table and writes DIR/NAME.json, DIR/NAME.csv, "
               "its figures DIR/NAME*.svg and DIR/index.html (every study run into DIR on one self-contained page).");
  study->add_option("name", study_args.name,
                    "analytic-cylinder: conventional error on a misaligned circle, exact (Figs 3 and 5)\n"
                    "approach-angle: Fig. 3 touched by a lobing probe, with and without its qualification on a "
                    "sphere; ISO 10360-5's probing test\n"
                    "registration: the registration Monte Carlo of Table 1 (cube corner, 900 points, 30 misalignments)\n"
                    "cylinder-misalignment: cylinder moved 2 mm, sigma 0-40 um, both methods (Fig. 8)\n"
                    "cylinder-deformation: cylinder with a local sine of peak 0.5/1/1.5 mm, sigma 0-40 um (Fig. 9)\n"
                    "freeform: the demo's free-form case (Table 2)")
      ->required()
      ->check(CLI::IsMember(cli::kStudyNames));
  study->add_option("--output-dir", study_args.output_dir,
                    "Directory for NAME.json (summary), NAME.csv (series), NAME*.svg (figures), NAME.section.html "
                    "and index.html; default probecomp-study");
  study->add_option("--noise", study_args.noise,
                    "registration, freeform: Gaussian noise sigma on each coordinate of the raw centres, mm "
                    "(default: 0 and 0.0045); freeform: a comma-separated list sweeps the levels, e.g. 0,0.0015,0.0045")
      ->delimiter(',')
      ->allow_extra_args(false)  // one argument per --noise (the list is comma-separated), not all that follow
      ->check(CLI::NonNegativeNumber);
  study->add_option("--seed", study_args.seed, "Random seed (default 1)");
  study->add_option("--trials", study_args.registration.trials, "registration: random misalignments (default 30)")
      ->check(CLI::PositiveNumber);
  study->add_option("--metric", study_args.metric,
                    "registration: ICP error metric, point-to-plane (default) or point-to-point (the paper's)")
      ->check(CLI::IsMember({"point-to-plane", "point-to-point"}));
  study->add_option("--loss", study_args.loss, "registration: robust weights, cauchy (default), huber, trimmed or none")
      ->check(CLI::IsMember({"cauchy", "huber", "trimmed", "none"}));

  cli::SimulateArgs sim;
  CLI::App* simulate = app.add_subcommand(
      "simulate",
      "Simulate a CMM measurement of a part (paper §7): the probe travels along each programmed normal until its tip "
      "touches the actual (misaligned, deformed) part. Writes DIR/raw.csv (x,y,z,i,j,k,point), DIR/truth.csv "
      "(contact point, actual normal, exact centre) and DIR/actual.igs.");
  simulate->add_option("--cad", sim.cad, "Nominal CAD file (.igs, .iges, .stp, .step)")->required();
  auto* plan_file = simulate->add_option("--plan", sim.plan, "PLAN.csv (x,y,z,i,j,k[,face]: programmed points and outward normals) or PLAN.dmo");
  auto* spacing_option = simulate->add_option("--spacing", sim.spacing, "Plan points this far apart on the faces, mm");
  plan_file->excludes(spacing_option);
  simulate->add_option("--faces", sim.faces, "With --spacing: faces to plan on, e.g. 0,3,5-9 (default: all)")
      ->needs(spacing_option);
  simulate->add_option("--probe-radius", sim.probe_radius, "Tip radius, mm")->required();
  simulate->add_option("--misalign", sim.misalign,
                       "Where the actual part sits: tx,ty,tz,rx,ry,rz (mm, degrees; T = Translation*Rz*Ry*Rx), default none");
  simulate->add_option("--deform", sim.deform, cli::kDeformHelp);
  simulate->add_option("--pretravel", sim.pretravel,
                       "P0,B,A[,N[,PHASE]]: the probe switch's pre-travel p(d) = P0 + B cos^2(t) + A sin^2(t) cos(N(phi - PHASE)), "
                       "t the angle of the travel d from the stylus (pointing down, -z), phi its azimuth from +x, right-handed about the "
                       "stylus (towards -y); mm, mm, mm, "
                       "lobes (default 3), degrees (default 0). The machine reports the centre p(d) on along d");
  simulate->add_option("--noise", sim.noise, "Gaussian noise sigma on each coordinate of the centre, mm (default 0)");
  simulate->add_option("--seed", sim.seed, "Random seed of the noise (default 1)");
  simulate->add_option("--output-dir", sim.output_dir, "Directory for raw.csv, truth.csv and actual.igs")->required();

  cli::CompensateArgs comp;
  CLI::App* compensate = app.add_subcommand(
      "compensate",
      "Contact points and deviations from raw probe-centre points: every input row back, in order, with "
      "x,y,z,nx,ny,nz,deviation,u,face,status, r when the input gives tip radii, and the input's other columns (u: the standard "
      "uncertainty of the point along its normal, k = 1, mm).");
  compensate->add_option("--cad", comp.cad, "CAD file (.igs, .iges, .stp, .step)")->required();
  compensate->add_option("--points", comp.points,
                         "RAW.csv (header naming x,y,z, optional i,j,k and r; other columns carried), RAW.dmo (DMIS "
                         "FA(label)=FEAT/POINT,CART,x,y,z,i,j,k, tips by SNSDEF/SNSLCT) or RAW.qif (QIF 3.0 "
                         "MeasuredPointSets)")
      ->required();
  compensate->add_option("--probe-radius", comp.probe_radius, kProbeRadiusHelp);
  compensate->add_option("--units", comp.units, kUnitsHelp)->check(CLI::IsMember({"mm", "inch"}));
  compensate->add_option("--initial-transform", comp.initial_transform, kInitialTransformHelp);
  compensate->add_flag("--accept-doubtful-registration", comp.accept_doubtful_registration, kAcceptDoubtfulHelp);
  compensate->add_option("--method", comp.method,
                         "cad (default): register to the offset model, fit, offset along the fitted normal; "
                         "conventional: c - r*(i,j,k)")
      ->check(CLI::IsMember({"cad", "conventional"}));
  compensate->add_option("--output", comp.output, "OUT.csv, OUT.dmo or OUT.qif (default: CSV on standard output)");
  compensate->add_option("--json", comp.json,
                         "STATS.json: transform (4x4, CAD to machine), registration, per face fit, counts by status, deviation statistics, "
                         "timings in seconds");
  compensate->add_option("--report", comp.report,
                         "REPORT.html: one self-contained page for people, opens offline: a 3-D colour map of the deviations "
                         "(the worst labelled; colour by status or u), histograms (deviation; CAD-based minus "
                         "conventional where the file has approach normals), a table per face, counts by status, the "
                         "registration, the inputs, warnings, timings");
  compensate->add_option("--tolerance", comp.tolerance,
                         "LOWER,UPPER: the deviation tolerance band, mm (e.g. -0.05,0.05): out-of-tolerance counts per "
                         "face and overall in --report and --json");
  compensate->add_option("--characteristics", comp.characteristics,
                         "Judge the drawing's characteristics: SPEC.json (datums and surface profiles, mm), or pmi for "
                         "the STEP AP242 file's own; decisions with U = 2u (ISO 14253-1) on standard error and in --json");
  compensate->add_option("--replan", comp.replan,
                         "PLAN.dmi: with --characteristics, a DMIS program of the points to measure again: where a "
                         "decision is indeterminate, and over faces with too few trusted points to judge");
  compensate->add_option("--qualification", comp.qualification,
                         "QUAL.json from probecomp qualify: each point's tip radius is its stylus's effective radius in "
                         "the direction it was touched from (-(i,j,k), else against the fitted normal), and that "
                         "radius's uncertainty joins u; styli it does not hold take r or --probe-radius");
  compensate->add_flag("--quiet", comp.quiet, "No progress on standard error");

  cli::QualifyArgs qualify_args;
  CLI::App* qualify = app.add_subcommand(
      "qualify",
      "Qualify styli on a reference sphere (DESIGN.md section 8): per stylus (a column stylus or tip, or DMIS SNSLCT; a "
      "file with neither is one stylus, T1) the sphere fitted to the recorded centres, the effective tip radius, the "
      "touches' form error and a model of the radius by approach direction (spherical harmonics of degree 0 and 2..L, "
      "L chosen by leave-one-out). Writes QUAL.json for compensate --qualification and prints a table.");
  qualify->add_option("--points", qualify_args.points,
                      "SPHERE.csv, .dmo or .qif: the recorded tip centres on the sphere, with i,j,k (the sphere's "
                      "outward normal at each programmed point) where known")
      ->required();
  qualify->add_option("--sphere-diameter", qualify_args.sphere_diameter,
                      "The reference sphere's calibrated diameter, in the points' unit")
      ->required();
  qualify->add_option("--output", qualify_args.output, "QUAL.json")->required();
  qualify->add_option("--units", qualify_args.units, kUnitsHelp)->check(CLI::IsMember({"mm", "inch"}));
  qualify->add_option("--max-degree", qualify_args.max_degree,
                      "Highest degree of the radius model tried (default 8; 0: one radius)");

  cli::FitArgs fit_args;
  CLI::App* fit = app.add_subcommand(
      "fit", "The as-measured part surfaces (fitted contact surfaces, machine frame) as NURBS in IGES or STEP.");
  fit->add_option("--cad", fit_args.cad, "CAD file")->required();
  fit->add_option("--points", fit_args.points, "RAW.csv, RAW.dmo or RAW.qif, as compensate's")->required();
  fit->add_option("--probe-radius", fit_args.probe_radius, kProbeRadiusHelp);
  fit->add_option("--units", fit_args.units, kUnitsHelp)->check(CLI::IsMember({"mm", "inch"}));
  fit->add_option("--initial-transform", fit_args.initial_transform, kInitialTransformHelp);
  fit->add_flag("--accept-doubtful-registration", fit_args.accept_doubtful_registration, kAcceptDoubtfulHelp);
  fit->add_option("--output", fit_args.output, "ACTUAL.igs or ACTUAL.stp")->required();
  fit->add_option("--json", fit_args.json, "STATS.json as for compensate");
  fit->add_flag("--quiet", fit_args.quiet, "No progress on standard error");

  cli::ConvertArgs convert_args;
  CLI::App* convert = app.add_subcommand(
      "convert", "Point files between CSV, DMIS and QIF 3.0: every row, units, tip radii and carried columns kept, "
                 "numbers exactly as read.");
  convert->add_option("input", convert_args.input, "IN.csv, IN.dmo or IN.qif")->required();
  convert->add_option("output", convert_args.output, "OUT.csv, OUT.dmo or OUT.qif (never the input)")->required();
  convert->add_option("--units", convert_args.units,
                      "Length unit of IN, mm or inch (default: mm, or what the file says: DMIS UNITS, QIF FileUnits, a "
                      "CSV '# lengths in UNIT' line, which must agree); OUT keeps it")
      ->check(CLI::IsMember({"mm", "inch"}));

  cli::DemoArgs demo_args;
  CLI::App* demo = app.add_subcommand(
      "demo", "The built-in free-form case (paper §7.3): simulate, compensate both ways, print the Table 2 comparison.");
  demo->add_option("--output-dir", demo_args.output_dir,
                   "Where nominal.igs, raw.csv and both outputs go (default: probecomp-demo)");

  CLI::App* selftest = app.add_subcommand(
      "selftest",
      "Known-answer checks of this build on this machine (ISO 10360-6 style): closest points and offsets on exact "
      "plane, sphere, cylinder and torus NURBS, a fit through exact data, a known registration, both compensations of a "
      "stored free-form case against its stored truth, ISO 10360-5's 25 probing touches on an exact sphere through the stylus qualification, NIST-style least-squares plane, sphere and cylinder data. One "
      "line per check (ok/FAIL, the error, the limit); exit 0 only if every check passes, 1 otherwise.");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (compensate->parsed()) return cli::run_compensate(comp);
    if (fit->parsed()) return cli::run_fit(fit_args);
    if (qualify->parsed()) return cli::run_qualify(qualify_args);
    if (demo->parsed()) return cli::run_demo(demo_args);
    if (convert->parsed()) return cli::run_convert(convert_args);
    if (info->parsed()) return run_info(part, json);
    if (project->parsed()) return run_project(part, points, project_units, output);
    if (plan->parsed()) return run_plan(part, spacing, faces, output);
    if (study->parsed()) return cli::run_study(study_args);
    if (selftest->parsed()) return run_selftest();
    if (simulate->parsed()) {
      if (sim.plan.empty() && !(sim.spacing > 0.0)) throw std::invalid_argument("simulate needs --plan PLAN.csv or --spacing S");
      return cli::run_simulate(sim);
    }
  } catch (const std::exception& e) {
    const auto* error = dynamic_cast<const Error*>(&e);
    std::cerr << "probecomp: " << e.what() << (error ? hint_words(error->hint()) : "") << '\n';
    if (dynamic_cast<const CadError*>(&e)) return kExitCad;
    if (dynamic_cast<const RegistrationError*>(&e)) return kExitRegistration;
    if (dynamic_cast<const FitError*>(&e)) return kExitFit;
    if (dynamic_cast<const InputError*>(&e)) return kExitInput;
    if (dynamic_cast<const std::invalid_argument*>(&e)) return kExitUsage;  // the command's own checks
    return kExitFailure;
  }
  std::cout << app.help();
  return 0;
}
