#pragma once
// Point files in QIF 3.0 (ISO 23952): the MeasuredPointSet elements under
// QIFDocument/Results/MeasurementResultsSet/MeasurementResults/MeasuredPointSets, read as one point table (every
// set, in document order) and written back, raw or compensated, as documents that validate against the QIF 3.0
// schemas. A set's `count` is checked against its lists (the schema does not tie them). QIF has no per-point
// place for what probecomp adds (status, u, face) nor for carried columns: they go in the set's Attributes as
// AttributeStr elements named `probecomp:...`, one entry per point (see compensated_qif). Lengths are in the
// document's FileUnits/PrimaryUnits/LinearUnit (mm without one).

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "probecomp/io/point_table.hpp"

namespace probecomp::io {

// .qif, in any case.
[[nodiscard]] bool is_qif(const std::filesystem::path& path);

// The probe centres of every uncompensated MeasuredPointSet: `Points` (3 × count numbers), optional `Normals`
// (3 × count: every set has them or none does), `ProbeRadius` (one for the set) or `ProbeRadii` (count numbers; NaN
// leaves a point's radius to the run's default). Columns x, y, z[, i, j, k][, r], set (the set's id, carried to
// outputs), then the columns of `probecomp:column:NAME` attributes (points_qif's); the rows hold each number as
// the file writes it. The unit is LinearUnit's (by UnitName or by UnitConversion/Factor: mm, cm, m, inch, foot),
// or a set's own Units/LinearUnit, which must then be the same for every set; `declared` (--units) must agree
// with it, and a file without one is read in it. Throws InputError ("FILE:LINE: cause", naming the element and the
// set's id) for a file that is not XML or not QIF, no point sets, a set without Points, binary lists (BinaryPoints
// ...), a token that is not a finite number, a count that disagrees with a list, compensated points (Compensated
// true, or a true in Compensations), a zero normal, a radius that is not positive, or no points.
[[nodiscard]] PointTable read_point_qif(const std::filesystem::path& path,
                                       std::optional<LengthUnit> declared = std::nullopt);

// An uncompensated QIF 3.0 document of the table (probecomp convert): one MeasuredPointSet per run of consecutive
// rows with the same `set` value (its id when every run's value is a distinct positive integer, else the runs are
// numbered and `set` is kept as a column), one set when the table has no `set` column; `Compensated` false,
// `ProbeRadius` when a set's radii are all equal, else `ProbeRadii` (NaN for a row without one); the other carried
// columns as `probecomp:column:NAME` attributes (CSV fields, comma-separated). Lengths in the table's unit, from
// the rows' text, written as the shortest text that reads back as the same double.
[[nodiscard]] std::string points_qif(const PointTable& table);

// One contact point of a compensated document: lengths in mm, machine frame.
struct QifContactPoint {
  bool computed = false;  // else the document keeps the raw centre, NaN normal, deviation and u, and says so
  Point3 contact = Point3::Zero();
  Vector3 normal = Vector3::Zero();
  double deviation = 0.0, uncertainty = 0.0, radius = 0.0;
  int face = -1;
  std::string status;  // ok, outlier, edge, ...
};
// Contact points as a QIF 3.0 document: one MeasuredPointSet per set of the input (as points_qif groups them), with
// the same id, count and order. `Points`: the contact points (a point not computed keeps its raw centre);
// `Normals`: the normals used (NaN where none was); `Compensated` true, or `Compensations` when some points were not
// computed (false for those); the tip radii; `Deviations` (NaN where not computed). In the set's Attributes:
// `probecomp:status`, `probecomp:u` (the standard uncertainty along the normal, k = 1, NaN where not computed) and
// `probecomp:face` (the CAD face, -1 for none), space-separated, and the input's carried columns. Lengths in the
// input's unit. The document's own Attributes name the `method` and `source` (the input file).
[[nodiscard]] std::string contact_points_qif(const PointTable& input, const std::vector<QifContactPoint>& points,
                                             const std::string& method, const std::string& source);

}  // namespace probecomp::io
