#pragma once
// The compensation's results as files (DESIGN.md §5): every input row back, in order, as CSV or DMIS; the run's
// statistics as JSON; a summary page in HTML. Lengths with 9 decimals (nm), unit vectors with 12.

#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/io/point_table.hpp"

namespace probecomp::io {

// x,y,z,nx,ny,nz,deviation,u,face,status, r (each row's tip radius) when the input gave radii, and the input's other
// columns (renamed input_NAME where they clash with ours), lengths in the input's unit. A point that was not computed keeps its row: empty fields and the reason in
// `status`.
[[nodiscard]] std::string compensated_csv(const PointTable& input, const compensation::CompensationResult& result);
// The same, written to `out` block by block (the whole text is never held: a million rows are 115 MB); `progress`
// hears the share of rows written after each block.
void write_compensated_csv(std::ostream& out, const PointTable& input, const compensation::CompensationResult& result,
                           const FileProgress& progress = {});

// One DMIS FA(label) point per computed point (labels from the input's label or id column, else P1, P2, ...),
// with its deviation, face and status in a comment; a comment line for each point not computed. Lengths in the
// input's unit, stated by a UNITS statement first. When the input gave the points their own radii, the tips follow
// it: an SNSDEF per tip and an SNSLCT where the tip changes (io::DmisTips), with the radius each point was
// compensated with.
[[nodiscard]] std::string compensated_dmis(const PointTable& input, const compensation::CompensationResult& result,
                                           const std::string& source);

// Seconds the caller spent outside compensate(): reading the files, writing the results, the whole run.
struct FileTimings {
  double read = 0.0, write = 0.0, total = 0.0;
};

// What the run was given: the files, the points' unit, the probe radius given for every point or as the default
// (mm; none when each point has its own) and the distinct tip radii of the points (mm, ascending).
struct RunInputs {
  std::string cad, points;
  LengthUnit points_unit = kMillimetre;
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
[[nodiscard]] std::string statistics_json(const compensation::CompensationResult& result, const RunInputs& inputs,
                                          const FileTimings& timings,
                                          const std::optional<Tolerance>& tolerance = std::nullopt);

}  // namespace probecomp::io
