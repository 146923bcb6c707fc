#pragma once
// Small text helpers for the point-file readers and the commands: surrounding blanks off, ASCII case folding, CSV
// fields.

#include <algorithm>
#include <cctype>
#include <charconv>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "probecomp/error.hpp"

namespace probecomp::io {

[[nodiscard]] inline std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

// The number a whole field holds (std::from_chars: no blanks, no leading '+', nothing after it; "inf" and "nan"
// are numbers here, so callers that need a finite length check), or nothing.
[[nodiscard]] inline std::optional<double> parse_number(std::string_view field) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (field.empty() || ec != std::errc() || end != field.data() + field.size()) return std::nullopt;
  return value;
}

[[nodiscard]] inline std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// A field for a comma-separated output: as it is, or in double quotes (its quotes doubled) when it holds a comma,
// a quote or a line break (RFC 4180), so that a field read from a quoted input is written back whole.
// append_csv_field appends it to `out` (a million rows' ids without a string each).
inline std::string& append_csv_field(std::string& out, std::string_view s) {
  if (s.find_first_of(",\"\r\n") == std::string_view::npos) return out.append(s);
  out += '"';
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}
[[nodiscard]] inline std::string csv_field(std::string_view s) {
  std::string out;
  return append_csv_field(out, s);
}

// Fields of one line, split at `separator` outside double quotes (RFC 4180: a quoted field may hold the separator,
// and "" inside it is one quote), each with surrounding blanks and its quotes removed. Throws InputError (`where`
// and the cause) on an unclosed quote. The inverse of joining csv_field()s with the separator.
[[nodiscard]] inline std::vector<std::string> split_fields(const std::string& line, char separator,
                                                           const std::string& where) {
  std::vector<std::string> out;
  if (line.find('"') == std::string::npos) {
    // No quotes (the usual machine-written line): cut at each separator, blanks trimmed, one string per field.
    const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };  // as trim()
    std::size_t start = 0;
    while (true) {
      const std::size_t end = std::min(line.find(separator, start), line.size());
      std::size_t a = start, b = end;
      while (a < b && blank(line[a])) ++a;
      while (b > a && blank(line[b - 1])) --b;
      out.emplace_back(line, a, b - a);
      if (end == line.size()) return out;
      start = end + 1;
    }
  }
  std::string field;
  bool quoted = false, was_quoted = false;
  for (std::size_t k = 0; k < line.size(); ++k) {
    const char c = line[k];
    if (quoted) {
      if (c == '"' && k + 1 < line.size() && line[k + 1] == '"') {
        field += '"';
        ++k;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"' && trim(field).empty()) {
      quoted = was_quoted = true;
      field.clear();
    } else if (c == separator) {
      out.push_back(was_quoted ? field : trim(field));
      field.clear();
      was_quoted = false;
    } else if (!(was_quoted && (c == ' ' || c == '\t'))) {
      field += c;
    }
  }
  if (quoted) throw InputError(where + "a quote is not closed");
  out.push_back(was_quoted ? field : trim(field));
  return out;
}

[[nodiscard]] inline std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return s;
}

}  // namespace probecomp::io
