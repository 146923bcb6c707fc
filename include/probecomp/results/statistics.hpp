#pragma once
// The run's figures: the inputs and timings, the trusted deviations summarised per face and overall against an
// optional tolerance, and all of it as the JSON statistics (DESIGN.md §5; read by the report and the Python package).

#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/inspection/characteristics.hpp"
#include "probecomp/io/point_table.hpp"

namespace probecomp::results {

// Seconds the caller spent outside compensate(): reading the files, writing the results, the whole run.
struct FileTimings {
  double read = 0.0, write = 0.0, total = 0.0;
};

// What the run was given: the files, the points' unit, the probe radius given for every point or as the default
// (mm; none when each point has its own) and the distinct tip radii of the points (mm, ascending).
struct RunInputs {
  std::string cad, points;
  io::LengthUnit points_unit = io::kMillimetre;
  std::optional<double> probe_radius;
  std::vector<double> tip_radii{};
};

// The distinct values of `radii`, ascending (RunInputs::tip_radii of points with radii of their own).
[[nodiscard]] std::vector<double> distinct_radii(std::vector<double> radii);

// A deviation passes when lower ≤ deviation ≤ upper (mm).
struct Tolerance {
  double lower = 0.0, upper = 0.0;
  [[nodiscard]] bool passes(double deviation) const { return deviation >= lower && deviation <= upper; }
};

// "LOWER,UPPER" (mm, lower < upper), or std::invalid_argument saying why not.
[[nodiscard]] Tolerance parse_tolerance(const std::string& text);

// The deviations of trusted (ok) points: count, mean, std (population), min, max (mm), and with a tolerance how
// many fall outside it.
struct DeviationSummary {
  int points = 0;
  double mean = 0.0, std = 0.0, min = 0.0, max = 0.0;
  int out_of_tolerance = 0;
};

// Count, mean, population std (in two passes: micrometre spreads about a mean that may be millimetres), min, max of
// `values`, and with a tolerance how many fall outside it.
[[nodiscard]] DeviationSummary summarise(const std::vector<double>& values, const std::optional<Tolerance>& tolerance);

// Per face of result.faces, in that order (its points: those whose `face` is the face's index), and overall.
struct DeviationSummaries {
  std::vector<DeviationSummary> faces;
  DeviationSummary all;
};
[[nodiscard]] DeviationSummaries summarise_deviations(const compensation::CompensationResult& result,
                                                      const std::optional<Tolerance>& tolerance);

// The inputs, the transform (CAD to machine), the registration (converged: bool; status; stop_reason), each face's
// fit, counts by status, the deviation statistics of the trusted points, the warnings and the timings in seconds
// (read, prepare, register, fit, compensate, write, total). Lengths in mm, whatever the points' unit.
// With a tolerance: it, and each face's and the whole run's count of trusted points outside it; each face's trusted
// deviations (mean, std, min, max) in any case.
// With an inspection (inspection/characteristics.hpp): its characteristics under "characteristics" and the datums its
// frames fitted under "datums" (DESIGN.md §7's keys).
[[nodiscard]] std::string statistics_json(const compensation::CompensationResult& result, const RunInputs& inputs,
                                          const FileTimings& timings,
                                          const std::optional<Tolerance>& tolerance = std::nullopt,
                                          const inspection::Inspection* inspection = nullptr);

}  // namespace probecomp::results
