#pragma once
// The commands beyond info/project/plan (DESIGN.md §5): compensate, fit, convert, demo, simulate and study. Each
// returns the exit status and throws std::exception with a one-line message for bad input; output files are written
// whole or not at all.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/simulation/measure.hpp"
#include "probecomp/studies/freeform_study.hpp"
#include "probecomp/studies/registration_study.hpp"

namespace probecomp::cli {

// cad::read_model, and on standard error a warning for each thing the reader left out (Model::read_warnings).
[[nodiscard]] cad::Model read_part(const std::string& path);

struct CompensateArgs {
  std::string cad, points, output, json, report, method = "cad";
  std::string tolerance;       // "LOWER,UPPER", mm (io::parse_tolerance); empty: none
  std::string characteristics;  // SPEC.json (inspection::read_specification), or "pmi": the STEP file's; empty: none
  std::string replan;           // PLAN.dmi: the points to measure again (with characteristics); empty: none
  std::string qualification;    // QUAL.json (probe/qualification_file.hpp): each stylus's radius by direction
  std::string units;           // of the point file (mm or inch); empty: mm, or what a DMIS file says
  std::string initial_transform;  // T.txt: 4 × 4, CAD → machine (io/transform_file.hpp); empty: identity
  // In the points' unit: every row's, or the default for rows without their own (a column r, DMIS sensors, QIF).
  std::optional<double> probe_radius;
  bool accept_doubtful_registration = false;  // compensation::RegisterOptions::accept_doubtful
  bool quiet = false;
};
int run_compensate(const CompensateArgs& args);

struct QualifyArgs {
  std::string points, output, units;  // SPHERE.(csv|dmo|qif), QUAL.json, the points' unit (mm or inch)
  double sphere_diameter = 0.0;       // in the points' unit
  int max_degree = 8;                 // probe::QualificationOptions::max_degree
};
int run_qualify(const QualifyArgs& args);
// The stylus of a touch that names none (a point file without a column stylus or tip).
inline constexpr const char* kDefaultStylus = "T1";
// Each row's stylus: its column `stylus`, else `tip` (DMIS SNSLCT); empty when the file has neither.
[[nodiscard]] std::vector<std::string> point_styli(const io::PointTable& table);

struct FitArgs {
  std::string cad, points, output, json;
  std::string units;           // as CompensateArgs
  std::string initial_transform;  // as CompensateArgs
  std::optional<double> probe_radius;  // as CompensateArgs
  bool accept_doubtful_registration = false;  // as CompensateArgs
  bool quiet = false;
};
int run_fit(const FitArgs& args);

struct ConvertArgs {
  std::string input, output;  // by extension: .csv, .dmo/.dmi/.dms (DMIS), .qif
  std::string units;          // of the input (mm or inch); empty: mm, or what a DMIS or QIF file or a CSV comment says
};
// The output in the input's unit, with every row, its radius and its carried columns.
int run_convert(const ConvertArgs& args);

struct DemoArgs {
  std::string output_dir = "probecomp-demo";
  bool quiet = false;
};
int run_demo(const DemoArgs& args);

// The demo's printed comparison with the paper's Table 2 (also `probecomp study freeform`).
std::string freeform_report(const studies::FreeformStudyResult& r);

struct SimulateArgs {
  std::string cad, faces, plan, output_dir;
  double spacing = 0.0, probe_radius = 0.0, noise = 0.0;
  std::string misalign;             // tx,ty,tz,rx,ry,rz (mm, degrees)
  std::vector<std::string> deform;  // bump:... and sine:... specs (see simulate --help)
  std::string pretravel;            // P0,B,A[,N[,PHASE]] (mm, mm, mm, count, degrees); empty: none
  std::uint64_t seed = 1;
};
int run_simulate(const SimulateArgs& args);
// The help text of --deform: the specification syntax.
extern const char* const kDeformHelp;

// raw.csv as the simulator and the demo write it: x,y,z,i,j,k per touched point (the measured centre and the
// programmed outward normal), plus `point` (1-based programmed point) when `numbered`.
std::string raw_points_csv(const std::vector<simulation::Touch>& touches,
                           const std::vector<simulation::ProgrammedPoint>& plan, bool numbered);

struct StudyArgs {
  std::string name, output_dir = "probecomp-study";
  studies::RegistrationStudyOptions registration;
  std::string metric = "point-to-plane", loss = "cauchy";
  std::vector<double> noise;  // mm; empty: the study's own; freeform: several sweep them
  std::uint64_t seed = 1;
};
// The studies `probecomp study` knows, in the order of the paper's sections.
extern const std::vector<std::string> kStudyNames;
int run_study(const StudyArgs& args);
int run_study_approach_angle(const StudyArgs& args);  // approach_angle_study_command.cpp


}  // namespace probecomp::cli
