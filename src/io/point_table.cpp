#include "probecomp/io/point_table.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include <tbb/parallel_for.h>

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

void Fields::push_back(std::span<const std::string_view> row) {
  const std::size_t start = text_.size();
  if (compact()) {
    if (row.size() != width_) throw std::logic_error("Fields::push_back: a row of another width on a compact table");
    for (std::size_t c = 0; c < width_; ++c) {
      if (slot_[c] < 0) continue;
      text_ += row[c];
      field_end_.push_back(static_cast<std::uint32_t>(text_.size() - start));
    }
    row_text_.push_back(text_.size());
    return;
  }
  for (const std::string_view f : row) {
    text_ += f;
    if (text_.size() - start > std::numeric_limits<std::uint32_t>::max()) {
      throw InputError("a row of more than 4 GB of text");
    }
    field_end_.push_back(static_cast<std::uint32_t>(text_.size() - start));
  }
  row_text_.push_back(text_.size());
  row_first_.push_back(field_end_.size());
}

Fields Fields::keeping_only(std::size_t width, const std::vector<int>& columns) {
  Fields out;
  out.width_ = width;
  out.slot_.assign(std::max(width, std::size_t{1}), -1);
  for (std::size_t c = 0; c < width; ++c) {
    if (std::find(columns.begin(), columns.end(), static_cast<int>(c)) != columns.end()) {
      out.slot_[c] = static_cast<int>(out.kept_++);
    }
  }
  out.row_first_.clear();
  return out;
}

void Fields::push_back(const std::vector<std::string>& row) {
  std::vector<std::string_view> views(row.begin(), row.end());
  push_back(views);
}

void Fields::append(const Fields& other) {
  if (compact() != other.compact() || (compact() && (slot_ != other.slot_ || width_ != other.width_))) {
    throw std::logic_error("Fields::append: tables that keep different columns");
  }
  const std::uint64_t text_base = text_.size(), field_base = field_end_.size();
  text_ += other.text_;
  for (std::size_t k = 1; k < other.row_text_.size(); ++k) row_text_.push_back(text_base + other.row_text_[k]);
  if (!compact()) {
    for (std::size_t k = 1; k < other.row_first_.size(); ++k) row_first_.push_back(field_base + other.row_first_[k]);
  }
  field_end_.insert(field_end_.end(), other.field_end_.begin(), other.field_end_.end());
}

void Fields::shrink_to_fit() {
  // A copy each: only where more than a little room is spare.
  auto shrink = [](auto& v) {
    if (v.capacity() > v.size() + v.size() / 16) v.shrink_to_fit();
  };
  shrink(text_);
  shrink(row_text_);
  shrink(row_first_);
  shrink(field_end_);
}

Fields Fields::keeping(const std::vector<int>& columns) const {
  const std::size_t width = empty() ? 0 : (*this)[0].size();
  bool uniform = width > 0;
  for (std::size_t k = 1; uniform && k < size(); ++k) uniform = (*this)[k].size() == width;
  Fields out;
  if (uniform) {
    out = keeping_only(width, columns);
    out.row_text_.reserve(row_text_.size());
    out.field_end_.reserve(size() * out.kept_);
  } else {
    out.row_text_.reserve(row_text_.size());
    out.row_first_.reserve(row_first_.size());
    out.field_end_.reserve(field_end_.size());
  }
  std::vector<std::string_view> row;
  for (std::size_t k = 0; k < size(); ++k) {
    const Row in = (*this)[k];
    row.assign(in.size(), std::string_view());
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
  append_carried_fields(out, k, carried_columns());
  return out;
}

void PointTable::append_carried_fields(std::string& out, std::size_t k, const std::vector<int>& carried) const {
  const auto row = rows[k];
  for (int c : carried) append_csv_field(out += ',', row[static_cast<std::size_t>(c)]);
}

namespace {

// One data row's columns, as the header named them.
struct RowLayout {
  std::vector<std::string> columns;
  int ix = -1, iy = -1, iz = -1, ii = -1, ij = -1, ik = -1, ir = -1;
  char separator = ',';
  LengthUnit unit = kMillimetre;
};

// The rows of one piece of a file (whole lines), read apart from the others and joined in order.
struct Piece {
  std::vector<Point3> points;
  std::vector<Vector3> normals;
  std::vector<double> radii;
  std::vector<int> line;  // each row's line, counted from the piece's first (1)
  Fields rows;
  int lines = 0;          // the lines the piece holds, rows or not
  int error_line = 0;     // the first bad row's line in the piece (0: none), and what is wrong with it
  std::string error;
};

// Reads the data rows of `text` (whole lines) into `piece`, stopping at the first bad one.
void read_rows(std::string_view text, const RowLayout& layout, Piece& piece) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };  // as trim(), and CRLF's CR
  std::vector<std::string> fields;     // a line's fields where they need unquoting or a decimal comma turned
  std::vector<std::string_view> view;  // the line's fields, as read
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    std::string_view row = text.substr(at, end - at);
    at = end + 1;
    const int number = ++piece.lines;
    while (!row.empty() && blank(row.front())) row.remove_prefix(1);
    while (!row.empty() && blank(row.back())) row.remove_suffix(1);
    if (row.empty() || row[0] == '#') continue;
    try {
      view.clear();
      if (layout.separator == ',' && row.find('"') == std::string_view::npos) {
        // The usual machine-written line: fields cut at each comma, blanks trimmed, no copies.
        for (std::size_t start = 0;;) {
          const std::size_t stop = std::min(row.find(',', start), row.size());
          std::string_view f = row.substr(start, stop - start);
          while (!f.empty() && blank(f.front())) f.remove_prefix(1);
          while (!f.empty() && blank(f.back())) f.remove_suffix(1);
          view.push_back(f);
          if (stop == row.size()) break;
          start = stop + 1;
        }
      } else {
        fields = split_fields(std::string(row), layout.separator, "");
        if (layout.separator != ',') {
          // With ';' or tab between fields, a number's decimal comma (one, and no point) is a decimal point; the
          // carried columns stay as written.
          for (int c : {layout.ix, layout.iy, layout.iz, layout.ii, layout.ij, layout.ik, layout.ir}) {
            if (c < 0 || static_cast<std::size_t>(c) >= fields.size()) continue;
            std::string& f = fields[static_cast<std::size_t>(c)];
            if (std::count(f.begin(), f.end(), ',') == 1 && f.find('.') == std::string::npos) f[f.find(',')] = '.';
          }
        }
        view.assign(fields.begin(), fields.end());
      }
      if (view.size() != layout.columns.size()) {
        throw InputError("expected " + std::to_string(layout.columns.size()) + " fields, found " + std::to_string(view.size()));
      }
      auto number_at = [&](int c) {
        const std::string_view f = view[static_cast<std::size_t>(c)];
        const std::optional<double> value = parse_number(f);
        const std::string& column = layout.columns[static_cast<std::size_t>(c)];
        if (!value) throw InputError("column '" + column + "' is not a number: '" + std::string(f) + "'");
        if (!std::isfinite(*value)) throw InputError("column '" + column + "' is not finite");
        return *value;
      };
      const double mm = layout.unit.mm;
      const Point3 x(mm * number_at(layout.ix), mm * number_at(layout.iy), mm * number_at(layout.iz));
      if (layout.ii >= 0) {
        const Vector3 n(number_at(layout.ii), number_at(layout.ij), number_at(layout.ik));
        if (!(n.norm() > 0.0)) throw InputError("the normal i, j, k is zero");
        piece.normals.push_back(n.normalized());
      }
      if (layout.ir >= 0) {
        const std::string_view text_r = view[static_cast<std::size_t>(layout.ir)];
        if (text_r.empty()) {
          piece.radii.push_back(std::numeric_limits<double>::quiet_NaN());
        } else {
          const double r = number_at(layout.ir);
          if (!(r > 0.0)) throw InputError("column 'r' (the tip radius) must be positive, not " + std::string(text_r));
          piece.radii.push_back(mm * r);
        }
      }
      piece.points.push_back(x);
    } catch (const InputError& e) {
      piece.error_line = number;
      piece.error = e.what();
      return;
    }
    piece.rows.push_back(view);
    piece.line.push_back(number);
  }
}

}  // namespace

PointTable read_point_csv(const std::filesystem::path& path, std::optional<LengthUnit> declared,
                          const FileProgress& progress, NumberText number_text) {
  const std::string name = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(name + ": cannot be opened (missing or unreadable)");
  PointTable t;
  std::error_code size_error;
  const std::uintmax_t bytes = std::filesystem::file_size(path, size_error);
  RowLayout layout;
  layout.unit = declared.value_or(kMillimetre);
  std::string line;
  int number = 0;
  bool have_header = false;
  // The lines before the data: the unit comment, other comments, the header.
  while (!have_header && std::getline(in, line)) {
    ++number;
    // A UTF-8 byte-order mark, as spreadsheet programs write, is not part of the first column's name.
    if (number == 1 && line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);
    const std::string text = trim(line);  // and CRLF's CR
    auto where = [&] { return name + ":" + std::to_string(number) + ": "; };
    if (text.starts_with('#') && lower(trim(text.substr(1))).starts_with("lengths in ")) {
      // The file's own statement of its unit, as points_csv writes it: what --units would otherwise have to say.
      const std::string stated = trim(trim(text.substr(1)).substr(std::string("lengths in ").size()));
      const std::optional<LengthUnit> u = length_unit(stated);
      if (!u) throw InputError(where() + "unknown length unit '" + stated + "' (known: mm, cm, meter, inch, feet)");
      if (declared && !(*u == *declared)) {
        throw InputError(where() + "the file says its lengths are in " + u->name + ", not in " + declared->name,
                         Hint::DeclaredUnit);
      }
      layout.unit = *u;
      continue;
    }
    if (text.empty() || text[0] == '#') continue;
    layout.separator = detect_separator(text);
    try {
      layout.columns = split_fields(text, layout.separator, "");
    } catch (const InputError& e) {
      throw InputError(where() + e.what());
    }
    t.columns = layout.columns;
    for (int c = 0; c < static_cast<int>(layout.columns.size()); ++c) {
      const std::string n = lower(layout.columns[static_cast<std::size_t>(c)]);
      int* slot = n == "x" ? &layout.ix : n == "y" ? &layout.iy : n == "z" ? &layout.iz : n == "i" ? &layout.ii
                : n == "j" ? &layout.ij : n == "k" ? &layout.ik : n == "r" ? &layout.ir : nullptr;
      if (slot != nullptr) {
        if (*slot >= 0) throw InputError(where() + "column '" + n + "' appears twice in the header");
        *slot = c;
      }
    }
    if (layout.ix < 0 || layout.iy < 0 || layout.iz < 0) throw InputError(where() + "the header must name columns x, y and z");
    const int n_normal = (layout.ii >= 0) + (layout.ij >= 0) + (layout.ik >= 0);
    if (n_normal != 0 && n_normal != 3) throw InputError(where() + "the header names some of i, j, k but not all three");
    have_header = true;
  }
  if (!have_header) throw InputError(name + ": no header line (expected columns x,y,z)");
  // In mm the numbers' text need not be kept (drop_number_text): each row keeps only its carried fields.
  Fields no_rows;
  if (number_text == NumberText::Drop && layout.unit.mm == 1.0) {
    no_rows = Fields::keeping_only(t.columns.size(), t.carried_columns());
    t.rows = no_rows;
  } else if (!size_error) {
    t.rows.reserve_text(static_cast<std::size_t>(bytes));
  }

  // The data rows, read in blocks of whole lines; each block is cut into pieces read in parallel and joined in
  // order (the same table whatever the thread count). A bad row stops the read at the first one in the file.
  constexpr std::size_t kBlockBytes = std::size_t{16} << 20;
  constexpr std::size_t kPieceBytes = std::size_t{1} << 18;
  std::vector<Vector3> normals;
  std::vector<double> radii;
  std::string block, carry;
  std::vector<std::string_view> parts;
  std::vector<Piece> pieces;
  std::size_t done = 0;
  bool first_block = true;
  while (in) {
    // No larger than what is left of the file (and one byte more, to meet its end in this read): resizing zeroes the
    // block, and 16 MiB of zeroes cost a 10 000-point file more than reading it (10 ms against 2 ms).
    std::size_t want = kBlockBytes;
    if (!size_error) {
      const std::streamoff at = in.tellg();
      if (at >= 0 && static_cast<std::uintmax_t>(at) <= bytes) {
        want = static_cast<std::size_t>(std::min<std::uintmax_t>(kBlockBytes, bytes - static_cast<std::uintmax_t>(at) + 1));
      }
    }
    block.resize(carry.size() + want);
    std::copy(carry.begin(), carry.end(), block.begin());
    in.read(block.data() + carry.size(), static_cast<std::streamsize>(want));
    block.resize(carry.size() + static_cast<std::size_t>(in.gcount()));
    carry.clear();
    if (in) {
      // Not the end: the last line may be cut; it starts the next block.
      const std::size_t last = block.rfind('\n');
      const std::size_t keep = last == std::string::npos ? 0 : last + 1;
      carry.assign(block, keep, std::string::npos);
      block.resize(keep);
    }
    done += block.size();
    parts.clear();
    const std::string_view all(block);
    for (std::size_t at = 0; at < all.size();) {
      std::size_t end = std::min(all.size(), at + kPieceBytes);
      if (end < all.size()) {
        const std::size_t newline = all.find('\n', end - 1);
        end = newline == std::string_view::npos ? all.size() : newline + 1;
      }
      parts.push_back(all.substr(at, end - at));
      at = end;
    }
    pieces.assign(parts.size(), Piece{});
    for (Piece& piece : pieces) piece.rows = no_rows;
    tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t k) { read_rows(parts[k], layout, pieces[k]); });
    for (Piece& piece : pieces) {
      if (piece.error_line > 0) throw InputError(name + ":" + std::to_string(number + piece.error_line) + ": " + piece.error);
      t.points.insert(t.points.end(), piece.points.begin(), piece.points.end());
      normals.insert(normals.end(), piece.normals.begin(), piece.normals.end());
      radii.insert(radii.end(), piece.radii.begin(), piece.radii.end());
      for (int l : piece.line) t.line.push_back(number + l);
      t.rows.append(piece.rows);
      number += piece.lines;
    }
    if (first_block && in && !size_error && bytes > done) {
      // The rows to come, estimated from this block's, with 2 % to spare: the arrays are allocated once instead of
      // growing by doubling (which holds the old and the new array at once).
      first_block = false;
      const double per_byte = static_cast<double>(t.points.size()) / static_cast<double>(done);
      const auto expected = static_cast<std::size_t>(1.02 * per_byte * static_cast<double>(bytes)) + 16;
      t.points.reserve(expected);
      t.line.reserve(expected);
      if (layout.ii >= 0) normals.reserve(expected);
      if (layout.ir >= 0) radii.reserve(expected);
    }
    if (progress && !size_error && bytes > 0) progress(static_cast<double>(done) / static_cast<double>(bytes));
  }
  t.unit = layout.unit;
  if (t.points.empty()) throw InputError(name + ": no points");
  // Without spare room (a copy, so only where there is more than a little).
  auto shrink = [](auto& v) {
    if (v.capacity() > v.size() + v.size() / 16) v.shrink_to_fit();
  };
  t.rows.shrink_to_fit();
  shrink(t.points);
  shrink(t.line);
  shrink(normals);
  shrink(radii);
  if (layout.ii >= 0) t.normals = std::move(normals);
  if (layout.ir >= 0) t.radii = std::move(radii);
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
  const std::vector<int> carried = t.carried_columns();
  std::string fields;
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
    if (!t.rows.empty()) {
      fields.clear();
      t.append_carried_fields(fields, k, carried);
      out << fields;
    }
    out << '\n';
  }
  return out.str();
}

}  // namespace probecomp::io
