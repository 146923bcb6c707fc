#pragma once
// Point files in CSV (DESIGN.md §5): a header naming the columns, `x,y,z` required, `i,j,k` and `r` (the row's tip
// radius) optional, other columns carried through; lines starting with '#' are comments, and one before the header
// that reads `# lengths in UNIT` states the file's length unit. Errors name the file and the line.

#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "probecomp/error.hpp"
#include "probecomp/geometry/types.hpp"
#include "probecomp/io/units.hpp"

namespace probecomp::io {

struct PointTable {
  std::vector<std::string> columns;            // every header name, in file order
  std::vector<std::vector<std::string>> rows;  // every data row's fields, as written (quotes removed)
  std::vector<int> line;                       // the file line of each row (from 1)
  LengthUnit unit = kMillimetre;               // the file's length unit: what its rows hold, and outputs for it use
  std::vector<Point3> points;                  // x, y, z of each row, in mm
  std::optional<std::vector<Vector3>> normals; // i, j, k of each row, when the file has them
  // Each row's tip radius in mm, when the file gives any (a CSV column `r`, a DMIS sensor, QIF's ProbeRadius or
  // ProbeRadii): NaN where a row leaves it empty, for the run's default radius to fill.
  std::optional<std::vector<double>> radii;
  // DMIS: each tip's sensor definition as the file writes it after `S(name)=` (SNSDEF/PROBE,...), by the name in
  // column `tip`, so that a DMIS output can state it again. Empty for other files.
  std::map<std::string, std::string> sensor_definitions;
  // The columns other than x, y, z, i, j, k and r, in file order: carried to outputs.
  [[nodiscard]] std::vector<int> carried_columns() const;
  // For an output CSV whose own columns are `ours`: ",name,..." of the carried columns (a name that is one of
  // ours prefixed "input_", so that every header name stays unique), and ",field,..." of row k's carried fields,
  // each quoted where it needs to be (io/text.hpp csv_field).
  [[nodiscard]] std::string carried_header(const std::vector<std::string>& ours) const;
  [[nodiscard]] std::string carried_fields(std::size_t k) const;
};

// CSV as other software writes it: a UTF-8 byte-order mark, CRLF line ends, ',' ';' or tab between fields (the
// one the header holds most of), names and fields in double quotes, and with ';' or tab a decimal comma.
// Lengths (and radii) are in the unit a `# lengths in UNIT` comment before the header names (DMIS's names: mm, cm,
// meter, inch, feet), else in `declared` (--units), else in mm; a comment and a `declared` unit that disagree are
// an error. A field read with a decimal comma is kept in the row with a decimal point. Throws InputError for a
// missing file, a missing header or column, a malformed or non-finite number, a radius that is not positive, a
// row with the wrong field count, an unclosed quote, an unknown unit in the comment, or no rows.
[[nodiscard]] PointTable read_point_csv(const std::filesystem::path& path,
                                       std::optional<LengthUnit> declared = std::nullopt);

// The table as CSV (probecomp convert): `# lengths in UNIT` first when the unit is not mm, then x,y,z[,i,j,k][,r]
// and the carried columns, every row, each number the shortest text that reads back as the row's value in the
// table's unit (from the rows' text: nothing is rescaled); an empty r where a row has no radius.
[[nodiscard]] std::string points_csv(const PointTable& table);

// Row k's value in column `c`, as written (in the table's unit), or `fallback` when the row holds no number there
// (a table built in code).
[[nodiscard]] double row_value(const PointTable& table, int c, std::size_t k, double fallback);
// The index of a column by name (case-insensitive), or -1.
[[nodiscard]] int column_index(const PointTable& table, const std::string& name);

}  // namespace probecomp::io
