#include "probecomp/io/point_table.hpp"

#include "probecomp/io/output_files.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "probecomp/io/output_files.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::io {

namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) out.push_back(trim(field));
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

}  // namespace

std::vector<int> PointTable::carried_columns() const {
  std::vector<int> out;
  for (int c = 0; c < static_cast<int>(columns.size()); ++c) {
    const std::string n = lower(columns[static_cast<std::size_t>(c)]);
    if (n != "x" && n != "y" && n != "z" && n != "i" && n != "j" && n != "k") out.push_back(c);
  }
  return out;
}

PointTable read_point_csv(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(name + ": cannot be opened (missing or unreadable)");
  PointTable t;
  std::string line;
  int number = 0;
  int ix = -1, iy = -1, iz = -1, ii = -1, ij = -1, ik = -1;
  bool have_header = false;
  std::vector<Vector3> normals;
  while (std::getline(in, line)) {
    ++number;
    const std::string text = trim(line);
    if (text.empty() || text[0] == '#') continue;
    std::vector<std::string> fields = split(text);
    const std::string where = name + ":" + std::to_string(number) + ": ";
    if (!have_header) {
      t.columns = fields;
      for (int c = 0; c < static_cast<int>(fields.size()); ++c) {
        const std::string n = lower(fields[static_cast<std::size_t>(c)]);
        int* slot = n == "x" ? &ix : n == "y" ? &iy : n == "z" ? &iz : n == "i" ? &ii : n == "j" ? &ij : n == "k" ? &ik : nullptr;
        if (slot != nullptr) {
          if (*slot >= 0) throw InputError(where + "column '" + n + "' appears twice in the header");
          *slot = c;
        }
      }
      if (ix < 0 || iy < 0 || iz < 0) throw InputError(where + "the header must name columns x, y and z");
      const int n_normal = (ii >= 0) + (ij >= 0) + (ik >= 0);
      if (n_normal != 0 && n_normal != 3) throw InputError(where + "the header names some of i, j, k but not all three");
      have_header = true;
      continue;
    }
    if (fields.size() != t.columns.size()) {
      throw InputError(where + "expected " + std::to_string(t.columns.size()) + " fields, found " + std::to_string(fields.size()));
    }
    auto number_at = [&](int c) {
      const std::string& f = fields[static_cast<std::size_t>(c)];
      double value = 0.0;
      const auto [end, ec] = std::from_chars(f.data(), f.data() + f.size(), value);
      if (ec != std::errc() || end != f.data() + f.size() || f.empty()) {
        throw InputError(where + "column '" + t.columns[static_cast<std::size_t>(c)] + "' is not a number: '" + f + "'");
      }
      if (!std::isfinite(value)) throw InputError(where + "column '" + t.columns[static_cast<std::size_t>(c)] + "' is not finite");
      return value;
    };
    t.points.emplace_back(number_at(ix), number_at(iy), number_at(iz));
    if (ii >= 0) {
      Vector3 n(number_at(ii), number_at(ij), number_at(ik));
      if (!(n.norm() > 0.0)) throw InputError(where + "the normal i, j, k is zero");
      normals.push_back(n.normalized());
    }
    t.rows.push_back(std::move(fields));
    t.line.push_back(number);
  }
  if (!have_header) throw InputError(name + ": no header line (expected columns x,y,z)");
  if (t.points.empty()) throw InputError(name + ": no points");
  if (ii >= 0) t.normals = std::move(normals);
  return t;
}

void write_file_atomically(const std::filesystem::path& path, const std::string& text) {
  OutputFiles file;
  file.add(path, text);
  file.commit();
}

}  // namespace probecomp::io
