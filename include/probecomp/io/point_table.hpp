#pragma once
// Point files in CSV (DESIGN.md §5): a header naming the columns, `x,y,z` required, `i,j,k` optional, other
// columns carried through; lines starting with '#' are comments. Errors name the file and the line.

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "probecomp/error.hpp"
#include "probecomp/geometry/types.hpp"

namespace probecomp::io {

struct PointTable {
  std::vector<std::string> columns;            // every header name, in file order
  std::vector<std::vector<std::string>> rows;  // every data row's fields, as written
  std::vector<int> line;                       // the file line of each row (from 1)
  std::vector<Point3> points;                  // x, y, z of each row
  std::optional<std::vector<Vector3>> normals; // i, j, k of each row, when the file has them
  // The columns other than x, y, z, i, j, k, in file order: carried to outputs.
  [[nodiscard]] std::vector<int> carried_columns() const;
};

// Throws InputError for a missing file, a missing header or column, a malformed or non-finite number, a row
// with the wrong field count, or no rows at all.
[[nodiscard]] PointTable read_point_csv(const std::filesystem::path& path);

// Writes `text` to `path` through a temporary file renamed at the end, so a failure leaves no partial file.
void write_file_atomically(const std::filesystem::path& path, const std::string& text);

}  // namespace probecomp::io
