#include "probecomp/io/point_table.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "probecomp/io/format.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::io {

namespace {

// The separator other software writes: the one of ',', ';' and tab that the header (outside quotes) holds most of.
// ';' and tab come from spreadsheets set to a decimal comma.
char detect_separator(const std::string& header) {
  int comma = 0, semicolon = 0, tab = 0;
  bool quoted = false;
  for (char c : header) {
    if (c == '"') quoted = !quoted;
    if (quoted) continue;
    comma += c == ',';
    semicolon += c == ';';
    tab += c == '\t';
  }
  if (semicolon > comma && semicolon >= tab) return ';';
  if (tab > comma && tab > semicolon) return '\t';
  return ',';
}

}  // namespace

std::vector<int> PointTable::carried_columns() const {
  std::vector<int> out;
  for (int c = 0; c < static_cast<int>(columns.size()); ++c) {
    const std::string n = lower(columns[static_cast<std::size_t>(c)]);
    if (n != "x" && n != "y" && n != "z" && n != "i" && n != "j" && n != "k" && n != "r") out.push_back(c);
  }
  return out;
}

void Fields::push_back(const std::vector<std::string>& row) {
  const std::size_t start = text_.size();
  for (const std::string& f : row) {
    text_ += f;
    if (text_.size() - start > std::numeric_limits<std::uint32_t>::max()) {
      throw InputError("a row of more than 4 GB of text");
    }
    field_end_.push_back(static_cast<std::uint32_t>(text_.size() - start));
  }
  row_text_.push_back(text_.size());
  row_first_.push_back(field_end_.size());
}

void Fields::shrink_to_fit() {
  text_.shrink_to_fit();
  row_text_.shrink_to_fit();
  row_first_.shrink_to_fit();
  field_end_.shrink_to_fit();
}

Fields Fields::keeping(const std::vector<int>& columns) const {
  Fields out;
  std::vector<std::string> row;
  for (std::size_t k = 0; k < size(); ++k) {
    const Row in = (*this)[k];
    row.assign(in.size(), std::string());
    for (int c : columns) {
      if (c >= 0 && static_cast<std::size_t>(c) < in.size()) row[static_cast<std::size_t>(c)] = in[static_cast<std::size_t>(c)];
    }
    out.push_back(row);
  }
  out.shrink_to_fit();
  return out;
}

void PointTable::drop_number_text() {
  if (unit.mm != 1.0) return;
  rows = rows.keeping(carried_columns());
}

std::string PointTable::carried_header(const std::vector<std::string>& ours) const {
  std::string out;
  for (int c : carried_columns()) {
    const std::string& name = columns[static_cast<std::size_t>(c)];
    out += ',' + csv_field(std::find(ours.begin(), ours.end(), name) != ours.end() ? "input_" + name : name);
  }
  return out;
}

std::string PointTable::carried_fields(std::size_t k) const {
  std::string out;
  for (int c : carried_columns()) out += ',' + csv_field(rows[k][static_cast<std::size_t>(c)]);
  return out;
}

PointTable read_point_csv(const std::filesystem::path& path, std::optional<LengthUnit> declared,
                          const FileProgress& progress) {
  const std::string name = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(name + ": cannot be opened (missing or unreadable)");
  PointTable t;
  std::error_code size_error;
  const std::uintmax_t bytes = std::filesystem::file_size(path, size_error);
  if (!size_error) t.rows.reserve_text(static_cast<std::size_t>(bytes));
  LengthUnit unit = declared.value_or(kMillimetre);
  std::string line;
  int number = 0;
  int ix = -1, iy = -1, iz = -1, ii = -1, ij = -1, ik = -1, ir = -1;
  bool have_header = false;
  std::vector<Vector3> normals;
  std::vector<double> radii;
  char separator = ',';
  while (std::getline(in, line)) {
    ++number;
    if (progress && number % 65536 == 0 && !size_error && bytes > 0) {
      progress(static_cast<double>(in.tellg()) / static_cast<double>(bytes));
    }
    // A UTF-8 byte-order mark, as spreadsheet programs write, is not part of the first column's name.
    if (number == 1 && line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);
    const std::string text = trim(line);  // and CRLF's CR
    // Built only for a message: a million-row file would otherwise build a million of them.
    auto where = [&] { return name + ":" + std::to_string(number) + ": "; };
    if (!have_header && text.starts_with('#') && lower(trim(text.substr(1))).starts_with("lengths in ")) {
      // The file's own statement of its unit, as points_csv writes it: what --units would otherwise have to say.
      const std::string stated = trim(trim(text.substr(1)).substr(std::string("lengths in ").size()));
      const std::optional<LengthUnit> u = length_unit(stated);
      if (!u) throw InputError(where() + "unknown length unit '" + stated + "' (known: mm, cm, meter, inch, feet)");
      if (declared && !(*u == *declared)) {
        throw InputError(where() + "the file says its lengths are in " + u->name + ", not in " + declared->name +
                         " as --units says");
      }
      unit = *u;
      continue;
    }
    if (text.empty() || text[0] == '#') continue;
    if (!have_header) separator = detect_separator(text);
    std::vector<std::string> fields;
    try {
      fields = split_fields(text, separator, "");
    } catch (const InputError& e) {
      throw InputError(where() + e.what());
    }
    if (!have_header) {
      t.columns = fields;
      for (int c = 0; c < static_cast<int>(fields.size()); ++c) {
        const std::string n = lower(fields[static_cast<std::size_t>(c)]);
        int* slot = n == "x" ? &ix : n == "y" ? &iy : n == "z" ? &iz : n == "i" ? &ii : n == "j" ? &ij : n == "k" ? &ik : n == "r" ? &ir : nullptr;
        if (slot != nullptr) {
          if (*slot >= 0) throw InputError(where() + "column '" + n + "' appears twice in the header");
          *slot = c;
        }
      }
      if (ix < 0 || iy < 0 || iz < 0) throw InputError(where() + "the header must name columns x, y and z");
      const int n_normal = (ii >= 0) + (ij >= 0) + (ik >= 0);
      if (n_normal != 0 && n_normal != 3) throw InputError(where() + "the header names some of i, j, k but not all three");
      have_header = true;
      continue;
    }
    if (fields.size() != t.columns.size()) {
      throw InputError(where() + "expected " + std::to_string(t.columns.size()) + " fields, found " + std::to_string(fields.size()));
    }
    auto number_at = [&](int c) {
      std::string& f = fields[static_cast<std::size_t>(c)];
      // With ';' or tab between fields, a decimal comma (one, and no point) is a decimal point.
      if (separator != ',' && std::count(f.begin(), f.end(), ',') == 1 && f.find('.') == std::string::npos) {
        f[f.find(',')] = '.';
      }
      const std::optional<double> value = parse_number(f);
      if (!value) {
        throw InputError(where() + "column '" + t.columns[static_cast<std::size_t>(c)] + "' is not a number: '" + f + "'");
      }
      if (!std::isfinite(*value)) throw InputError(where() + "column '" + t.columns[static_cast<std::size_t>(c)] + "' is not finite");
      return *value;
    };
    t.points.emplace_back(unit.mm * number_at(ix), unit.mm * number_at(iy), unit.mm * number_at(iz));
    if (ii >= 0) {
      Vector3 n(number_at(ii), number_at(ij), number_at(ik));
      if (!(n.norm() > 0.0)) throw InputError(where() + "the normal i, j, k is zero");
      normals.push_back(n.normalized());
    }
    if (ir >= 0) {
      if (fields[static_cast<std::size_t>(ir)].empty()) {
        radii.push_back(std::numeric_limits<double>::quiet_NaN());
      } else {
        const double r = number_at(ir);
        if (!(r > 0.0)) throw InputError(where() + "column 'r' (the tip radius) must be positive, not " + fields[static_cast<std::size_t>(ir)]);
        radii.push_back(unit.mm * r);
      }
    }
    t.rows.push_back(fields);
    t.line.push_back(number);
  }
  t.unit = unit;
  if (!have_header) throw InputError(name + ": no header line (expected columns x,y,z)");
  if (t.points.empty()) throw InputError(name + ": no points");
  // The arrays grew by doubling: without their spare room they hold a million rows in about 150 MB, not 250.
  t.rows.shrink_to_fit();
  t.points.shrink_to_fit();
  t.line.shrink_to_fit();
  normals.shrink_to_fit();
  radii.shrink_to_fit();
  if (ii >= 0) t.normals = std::move(normals);
  if (ir >= 0) t.radii = std::move(radii);
  return t;
}

int column_index(const PointTable& t, const std::string& name) {
  for (std::size_t c = 0; c < t.columns.size(); ++c) {
    if (lower(t.columns[c]) == name) return static_cast<int>(c);
  }
  return -1;
}

double row_value(const PointTable& t, int c, std::size_t k, double fallback) {
  if (c < 0 || k >= t.rows.size() || static_cast<std::size_t>(c) >= t.rows[k].size()) return fallback;
  return parse_number(t.rows[k][static_cast<std::size_t>(c)]).value_or(fallback);
}

std::string points_csv(const PointTable& t) {
  const double scale = 1.0 / t.unit.mm;  // mm → the table's unit, for a table without the rows' text
  const int ix = column_index(t, "x"), iy = column_index(t, "y"), iz = column_index(t, "z");
  const int ii = column_index(t, "i"), ij = column_index(t, "j"), ik = column_index(t, "k"), ir = column_index(t, "r");
  std::vector<std::string> ours{"x", "y", "z"};
  if (t.normals) ours.insert(ours.end(), {"i", "j", "k"});
  if (t.radii) ours.push_back("r");
  std::ostringstream out;
  if (!(t.unit == kMillimetre)) out << "# lengths in " << t.unit.name << '\n';
  for (std::size_t c = 0; c < ours.size(); ++c) out << (c ? "," : "") << ours[c];
  out << t.carried_header(ours) << '\n';
  for (std::size_t k = 0; k < t.points.size(); ++k) {
    const Point3& x = t.points[k];
    out << exact(row_value(t, ix, k, scale * x.x())) << ',' << exact(row_value(t, iy, k, scale * x.y())) << ','
        << exact(row_value(t, iz, k, scale * x.z()));
    if (t.normals) {
      const Vector3& n = (*t.normals)[k];
      out << ',' << exact(row_value(t, ii, k, n.x())) << ',' << exact(row_value(t, ij, k, n.y())) << ','
          << exact(row_value(t, ik, k, n.z()));
    }
    if (t.radii) {
      const double r = (*t.radii)[k];
      out << ',' << (std::isnan(r) ? std::string() : exact(row_value(t, ir, k, scale * r)));
    }
    if (!t.rows.empty()) out << t.carried_fields(k);
    out << '\n';
  }
  return out.str();
}

}  // namespace probecomp::io
