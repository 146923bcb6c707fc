#pragma once
// Point files in CSV (DESIGN.md §5): a header naming the columns, `x,y,z` required, `i,j,k` and `r` (the row's tip
// radius) optional, other columns carried through; lines starting with '#' are comments. Errors name the file and
// the line.

#include <filesystem>
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
// Lengths (and radii) are in `unit` (CSV has no place to say). A field read with a decimal comma is kept in the
// row with a decimal point. Throws InputError for a missing file, a missing header or column, a malformed or
// non-finite number, a radius that is not positive, a row with the wrong field count, an unclosed quote, or no rows.
[[nodiscard]] PointTable read_point_csv(const std::filesystem::path& path, LengthUnit unit = kMillimetre);

}  // namespace probecomp::io
