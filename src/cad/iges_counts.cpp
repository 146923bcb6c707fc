#include "probecomp/cad/iges_counts.hpp"

#include <array>
#include <cctype>
#include <charconv>
#include <string>

namespace probecomp::cad {

namespace {

// An IGES parameter section's entity, read one character at a time: its directory line, how many parameters it
// holds (up to its record delimiter), and the integers among its first five (the type and the counts).
class EntityParameters {
 public:
  EntityParameters(char parameter_delimiter, char record_delimiter, long directory_line)
      : pd_(parameter_delimiter), rd_(record_delimiter), directory_line_(directory_line) {}

  void feed(char c) {
    if (ended_) return;
    if (string_left_ > 0) {  // inside a Hollerith string, which may hold delimiters
      --string_left_;
      return;
    }
    if (c == pd_ || c == rd_) {
      finish_token();
      ended_ = c == rd_;
      return;
    }
    if (c == 'H' && !token_.empty() && token_.size() <= 9 && all_digits(token_)) {
      string_left_ = std::stol(token_);
      token_.clear();
      is_string_ = true;  // not an integer
      return;
    }
    if (c != ' ' && token_.size() < kKeptChars) token_ += c;
  }

  void finish_token() {
    if (count_ < static_cast<long>(ints_.size())) {
      long long v = 0;
      const char* end = token_.data() + token_.size();
      const auto [p, ec] = std::from_chars(token_.data(), end, v);
      if (!is_string_ && !token_.empty() && ec == std::errc() && p == end) ints_[static_cast<std::size_t>(count_)] = v;
    }
    ++count_;
    token_.clear();
    is_string_ = false;
  }

  // The check (see iges_counts.hpp), once the entity's last line is in.
  [[nodiscard]] std::optional<std::string> too_few() {
    if (!ended_) finish_token();  // a last parameter without its record delimiter still counts
    const long long n = count_ - 1;  // the parameters after the entity type
    const auto& t = ints_;
    auto need = [&](const char* what, long double declared) -> std::optional<std::string> {
      if (declared <= static_cast<long double>(n)) return std::nullopt;
      return "IGES entity " + std::to_string(t[0]) + " (directory line " + std::to_string(directory_line_) +
             ") declares " + std::to_string(static_cast<long long>(std::min(declared, 1e18L))) + " " + what +
             " but its parameter data hold " + std::to_string(n) + " values";
    };
    auto at = [&](std::size_t i) { return static_cast<long double>(t[i]); };
    auto known = [&](std::initializer_list<std::size_t> is) {
      for (std::size_t i : is) {
        if (t[i] < 0) return false;  // absent or negative: OpenCASCADE's own range check refuses it
      }
      return true;
    };
    std::optional<std::string> r;
    switch (t[0]) {
      case 102:  // composite curve: N, then N curves
        if (known({1})) r = need("curves", at(1));
        break;
      case 106:  // copious data: IP, N, then N tuples
        if (known({2})) r = need("points", at(2));
        break;
      case 112:  // parametric spline curve: CTYPE, H, NDIM, N, then N + 1 breakpoints
        if (known({4})) r = need("segments", at(4) + 1);
        break;
      case 114:  // parametric spline surface: CTYPE, PTYPE, M, N, then M + 1 and N + 1 breakpoints, M·N patches
        if (known({3, 4})) {
          r = need("breakpoints", at(3) + at(4) + 2);
          if (!r) r = need("patches", at(3) * at(4));
        }
        break;
      case 126:  // B-spline curve: K, M, ..., then K + M + 2 knots and K + 1 weights and poles
        if (known({1, 2})) r = need("knots", at(1) + at(2) + 2);
        break;
      case 128:  // B-spline surface: K1, K2, M1, M2, ..., then knots, (K1 + 1)(K2 + 1) weights and poles
        if (known({1, 2, 3, 4})) {
          r = need("poles", (at(1) + 1) * (at(2) + 1));
          if (!r) r = need("knots", at(1) + at(3) + at(2) + at(4) + 4);
        }
        break;
      case 406:  // property: NP, then NP values
        if (known({1})) r = need("property values", at(1));
        break;
      default:
        break;
    }
    return r;
  }

 private:
  static constexpr std::size_t kKeptChars = 32;  // no integer or Hollerith count is longer
  static bool all_digits(const std::string& s) {
    for (char c : s) {
      if (!std::isdigit(static_cast<unsigned char>(c))) return false;
    }
    return true;
  }
  char pd_, rd_;
  long directory_line_;
  bool ended_ = false;
  long string_left_ = 0;
  bool is_string_ = false;
  long count_ = 0;
  std::string token_;
  std::array<long long, 5> ints_{-1, -1, -1, -1, -1};
};

// The parameter and record delimiters from the global section's first two fields (IGES 5.3 §2.2.4: each a
// one-character Hollerith string, or defaulted to ',' and ';').
std::pair<char, char> delimiters(const std::string& g) {
  char pd = ',', rd = ';';
  std::size_t pos = 0;
  if (g.size() > 2 && g.compare(0, 2, "1H") == 0) {
    pd = g[2];
    pos = 3;
  }
  if (pos < g.size() && g[pos] == pd) ++pos;
  if (g.size() > pos + 2 && g.compare(pos, 2, "1H") == 0) rd = g[pos + 2];
  return {pd, rd};
}

}  // namespace

std::optional<std::string> iges_count_beyond_data(std::istream& in) {
  // Fixed 80-column records: the section letter in column 73; in the parameter section, the data in columns 1–64
  // and the entity's directory line in columns 66–72.
  std::string line, global;
  std::optional<EntityParameters> entity;
  long entity_line = -1;
  std::pair<char, char> delim{',', ';'};
  bool have_delimiters = false;
  while (std::getline(in, line)) {
    if (line.size() < 73) continue;
    const char section = line[72];
    if (section == 'G') {
      // The delimiters are the first two fields, within the first few characters: two records are plenty.
      if (global.size() < 144) global += line.substr(0, 72);
      continue;
    }
    if (section != 'P') continue;
    if (!have_delimiters) {
      delim = delimiters(global);
      have_delimiters = true;
    }
    long de = -1;
    {
      std::size_t b = 65;
      while (b < 72 && line[b] == ' ') ++b;
      const auto [p, ec] = std::from_chars(line.data() + b, line.data() + 72, de);
      if (ec != std::errc()) de = -1;
    }
    if (!entity || de != entity_line) {
      if (entity) {
        if (std::optional<std::string> r = entity->too_few()) return r;
      }
      entity.emplace(delim.first, delim.second, de);
      entity_line = de;
    }
    for (std::size_t i = 0; i < 64; ++i) entity->feed(line[i]);
  }
  if (entity) return entity->too_few();
  return std::nullopt;
}

}  // namespace probecomp::cad
