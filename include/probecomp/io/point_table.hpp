#pragma once
// Point files in CSV (DESIGN.md §5): a header naming the columns, `x,y,z` required, `i,j,k` and `r` (the row's tip
// radius) optional, other columns carried through; lines starting with '#' are comments, and one before the header
// that reads `# lengths in UNIT` states the file's length unit. Errors name the file and the line.

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <stdexcept>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "probecomp/error.hpp"
#include "probecomp/geometry/types.hpp"
#include "probecomp/io/units.hpp"

namespace probecomp::io {

// The share (0 to 1) of a file read or written so far, for a long run's progress bar (io/progress.hpp).
using FileProgress = std::function<void(double fraction)>;

// Every data row's fields as written (quotes removed), packed into one buffer: a row costs its text and one
// offset a field, where a vector of strings cost about 450 bytes a row of seven numbers (1 M rows: 450 MB).
class Fields {
 public:
  class Row {
   public:
    [[nodiscard]] std::string_view operator[](std::size_t c) const { return fields_->field(k_, c); }
    [[nodiscard]] std::size_t size() const { return count_; }

   private:
    friend class Fields;
    Row(const Fields* fields, std::size_t k, std::size_t count) : fields_(fields), k_(k), count_(count) {}
    const Fields* fields_;
    std::size_t k_, count_;
  };
  class Iterator {
   public:
    Iterator(const Fields* fields, std::size_t k) : fields_(fields), k_(k) {}
    Row operator*() const { return (*fields_)[k_]; }
    Iterator& operator++() {
      ++k_;
      return *this;
    }
    bool operator!=(const Iterator& o) const { return k_ != o.k_; }

   private:
    const Fields* fields_;
    std::size_t k_;
  };

  // An empty table whose rows will have `width` fields of which only those of `columns` are stored (compact, as
  // keeping() makes): rows of text a scan's reader need not hold.
  [[nodiscard]] static Fields keeping_only(std::size_t width, const std::vector<int>& columns);
  // A compact table's rows must have its width (std::logic_error otherwise).
  void push_back(std::span<const std::string_view> row);
  void push_back(const std::vector<std::string>& row);
  // Appends every row of `other`, in order: both compact with the same columns kept, or neither.
  void append(const Fields& other);
  // Room for this much text (a file's size bounds its fields' text), and no spare room once all rows are in.
  void reserve_text(std::size_t bytes) { text_.reserve(bytes); }
  void shrink_to_fit();
  // The same rows with only the fields of `columns` kept, every other field empty. Where every row has as many
  // fields, only the kept ones are stored (a million rows with one carried column: 19 MB, not 51); rows can no longer
  // be added then.
  [[nodiscard]] Fields keeping(const std::vector<int>& columns) const;
  [[nodiscard]] Row operator[](std::size_t k) const {
    return {this, k, compact() ? width_ : row_first_[k + 1] - row_first_[k]};
  }
  [[nodiscard]] std::size_t size() const { return row_text_.size() - 1; }
  [[nodiscard]] bool empty() const { return size() == 0; }
  [[nodiscard]] Iterator begin() const { return {this, 0}; }
  [[nodiscard]] Iterator end() const { return {this, size()}; }

 private:
  [[nodiscard]] bool compact() const { return !slot_.empty(); }
  [[nodiscard]] std::string_view field(std::size_t k, std::size_t c) const {
    std::size_t first = 0, f = 0;
    if (compact()) {
      const int s = slot_[c];
      if (s < 0) return {};
      first = k * kept_;
      f = first + static_cast<std::size_t>(s);
    } else {
      first = row_first_[k];
      f = first + c;
    }
    const std::size_t start = f == first ? 0 : field_end_[f - 1];
    return std::string_view(text_).substr(row_text_[k] + start, field_end_[f] - start);
  }
  std::string text_;                          // every field's text, one after another
  std::vector<std::uint64_t> row_text_{0};    // where each row's text starts in text_; one more: the end
  std::vector<std::uint64_t> row_first_{0};   // each row's first field in field_end_; one more: the end (not compact)
  std::vector<std::uint32_t> field_end_;      // where each field ends, from its row's start
  // Compact (after keeping): every row's field count, each column's place among the kept fields (−1: dropped),
  // and how many are kept; row k's fields are then field_end_[k·kept_ ...].
  std::size_t width_ = 0;
  std::vector<int> slot_;
  std::size_t kept_ = 0;
};

struct PointTable {
  std::vector<std::string> columns;            // every header name, in file order
  Fields rows;                                 // every data row's fields, as written (quotes removed)
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
  // The same appended to `out`, with `carried` = carried_columns() found once for all rows.
  void append_carried_fields(std::string& out, std::size_t k, const std::vector<int>& carried) const;
  // Frees the text of the numbers (x, y, z, i, j, k, r), keeping the carried columns', where that loses nothing an
  // output of compensated points needs: in mm, `points` and `radii` hold the very doubles the text gave (a million
  // rows: 85 MB less). Does nothing in another unit, where the text is the exact value in the file's unit.
  void drop_number_text();
};

// CSV as other software writes it: a UTF-8 byte-order mark, CRLF line ends, ',' ';' or tab between fields (the
// one the header holds most of), names and fields in double quotes, and with ';' or tab a decimal comma.
// Lengths (and radii) are in the unit a `# lengths in UNIT` comment before the header names (DMIS's names: mm, cm,
// meter, inch, feet), else in `declared` (--units), else in mm; a comment and a `declared` unit that disagree are
// an error. A field read with a decimal comma is kept in the row with a decimal point. Throws InputError for a
// missing file, a missing header or column, a malformed or non-finite number, a radius that is not positive, a
// row with the wrong field count, an unclosed quote, an unknown unit in the comment, or no rows.
// `progress`, when given, hears the share of the file's bytes read after each block of 16 MB. `NumberText::Drop`
// keeps, in mm, only the carried columns' text, as drop_number_text() would after the read, without ever holding
// the rest (a million rows: about 85 MB).
enum class NumberText { Keep, Drop };
[[nodiscard]] PointTable read_point_csv(const std::filesystem::path& path,
                                       std::optional<LengthUnit> declared = std::nullopt,
                                       const FileProgress& progress = {}, NumberText number_text = NumberText::Keep);

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
