#pragma once
// The compensation's results as files (DESIGN.md §5): every input row back, in order, as CSV or DMIS; the run's
// statistics as JSON; a summary page in HTML. Lengths with 9 decimals (nm), unit vectors with 12.

#include <optional>
#include <string>
#include <vector>

#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/io/point_table.hpp"

namespace probecomp::io {

// x,y,z,nx,ny,nz,deviation,u,face,status, r (each row's tip radius) when the input gave radii, and the input's other
// columns (renamed input_NAME where they clash with ours), lengths in the input's unit. A point that was not computed keeps its row: empty fields and the reason in
// `status`.
[[nodiscard]] std::string compensated_csv(const PointTable& input, const compensation::CompensationResult& result);

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

// The inputs, the transform (CAD to machine), the registration (converged: bool; status; stop_reason), each face's
// fit, counts by status, the deviation statistics of the trusted points, the warnings and the timings in seconds
// (read, prepare, register, fit, compensate, write, total). Lengths in mm, whatever the points' unit.
[[nodiscard]] std::string statistics_json(const compensation::CompensationResult& result, const RunInputs& inputs,
                                          const FileTimings& timings);

// A summary page for people: registration, deviation quantiles of the trusted points, a table of the faces.
[[nodiscard]] std::string html_report(const std::string& cad_file, const std::string& points_file,
                                      const compensation::CompensationResult& result);

}  // namespace probecomp::io
