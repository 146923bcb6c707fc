#include "step_measures.hpp"

#include <cctype>
#include <charconv>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace probecomp::cad::detail {

namespace {

using Instances = std::unordered_map<long, std::string_view>;

// Past a string that starts at text[i] ('…', a quote inside written twice), or a comment (/* … */).
std::size_t skip_string(std::string_view text, std::size_t i) {
  for (++i; i < text.size(); ++i) {
    if (text[i] != '\'') continue;
    if (i + 1 < text.size() && text[i + 1] == '\'') {
      ++i;
      continue;
    }
    return i + 1;
  }
  return text.size();
}
std::size_t skip_comment(std::string_view text, std::size_t i) {
  const std::size_t end = text.find("*/", i + 2);
  return end == std::string_view::npos ? text.size() : end + 2;
}

// The DATA section's instances (ISO 10303-21 §10): #id = its text up to the ';' that ends it.
Instances instances(std::string_view text) {
  Instances out;
  std::size_t i = text.find("DATA;");
  if (i == std::string_view::npos) return out;
  i += 5;
  while (i < text.size()) {
    const char c = text[i];
    if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (text.compare(i, 2, "/*") == 0) {
      i = skip_comment(text, i);
    } else if (c == '#') {
      char* end = nullptr;
      const std::string digits(text.substr(i + 1, 20));
      const long id = std::strtol(digits.c_str(), &end, 10);
      std::size_t j = i + 1 + static_cast<std::size_t>(end - digits.c_str());
      while (j < text.size() && std::isspace(static_cast<unsigned char>(text[j]))) ++j;
      if (j >= text.size() || text[j] != '=') return out;  // not an instance: the section ends here for us
      const std::size_t start = ++j;
      while (j < text.size() && text[j] != ';') {
        if (text[j] == '\'') {
          j = skip_string(text, j);
        } else if (text.compare(j, 2, "/*") == 0) {
          j = skip_comment(text, j);
        } else {
          ++j;
        }
      }
      out.emplace(id, text.substr(start, j - start));
      i = j + 1;
    } else {
      break;  // ENDSEC;
    }
  }
  return out;
}

bool identifier_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// The parameters of the record KEYWORD(…) in an instance (simple, or one part of a complex one), split at its
// top-level commas; none where it has no such record.
std::optional<std::vector<std::string_view>> parameters(std::string_view instance, std::string_view keyword) {
  for (std::size_t at = instance.find(keyword); at != std::string_view::npos; at = instance.find(keyword, at + 1)) {
    const std::size_t open = at + keyword.size();
    if ((at > 0 && identifier_char(instance[at - 1])) || open >= instance.size() || instance[open] != '(') continue;
    std::vector<std::string_view> out;
    int depth = 0;
    std::size_t start = open + 1;
    for (std::size_t i = open; i < instance.size();) {
      const char c = instance[i];
      if (c == '\'') {
        i = skip_string(instance, i);
        continue;
      }
      if (c == '(') ++depth;
      if (c == ')' && --depth == 0) {
        out.push_back(instance.substr(start, i - start));
        return out;
      }
      if (c == ',' && depth == 1) {
        out.push_back(instance.substr(start, i - start));
        start = i + 1;
      }
      ++i;
    }
    return std::nullopt;
  }
  return std::nullopt;
}

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::optional<double> number(std::string_view s) {
  const std::string text(trimmed(s));
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size()) return std::nullopt;
  return v;
}

// An instance name (#123) is an integer: parsed as one, so that a name of 66 digits is no reference (as a double
// it was cast to long past its range: found by fuzz_cad_step).
const std::string_view* referenced(const Instances& all, std::string_view ref) {
  ref = trimmed(ref);
  if (ref.size() < 2 || ref.front() != '#') return nullptr;
  const std::string_view digits = trimmed(ref.substr(1));
  long id = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), id);
  if (error != std::errc() || end != digits.data() + digits.size()) return nullptr;
  const auto it = all.find(id);
  return it == all.end() ? nullptr : &it->second;
}

std::optional<double> length_mm(const Instances& all, std::string_view ref, int depth = 0);

// One unit of length in mm: an SI unit with its prefix, or a conversion-based unit (the inch) by its measure.
std::optional<double> unit_mm(const Instances& all, std::string_view ref, int depth) {
  const std::string_view* unit = referenced(all, ref);
  if (unit == nullptr || depth > 4) return std::nullopt;
  if (const auto si = parameters(*unit, "SI_UNIT"); si && si->size() == 2 && trimmed((*si)[1]) == ".METRE.") {
    static const std::map<std::string_view, double> kPrefix = {{"$", 1000.0},     {".KILO.", 1e6},  {".DECI.", 100.0},
                                                               {".CENTI.", 10.0}, {".MILLI.", 1.0}, {".MICRO.", 1e-3}};
    const auto p = kPrefix.find(trimmed((*si)[0]));
    if (p != kPrefix.end()) return p->second;
    return std::nullopt;
  }
  if (const auto conversion = parameters(*unit, "CONVERSION_BASED_UNIT"); conversion && conversion->size() == 2) {
    return length_mm(all, (*conversion)[1], depth + 1);
  }
  return std::nullopt;
}

// A length measure with its unit (MEASURE_WITH_UNIT(LENGTH_MEASURE(v), #unit), simple or within a complex
// instance), in mm.
std::optional<double> length_mm(const Instances& all, std::string_view ref, int depth) {
  const std::string_view* measure = referenced(all, ref);
  if (measure == nullptr) return std::nullopt;
  auto p = parameters(*measure, "MEASURE_WITH_UNIT");
  if (!p) p = parameters(*measure, "LENGTH_MEASURE_WITH_UNIT");
  if (!p || p->size() != 2) return std::nullopt;
  std::optional<std::vector<std::string_view>> value = parameters((*p)[0], "LENGTH_MEASURE");
  if (!value) value = parameters((*p)[0], "POSITIVE_LENGTH_MEASURE");
  if (!value || value->size() != 1) return std::nullopt;
  const std::optional<double> v = number((*value)[0]);
  const std::optional<double> unit = unit_mm(all, (*p)[1], depth);
  if (!v || !unit) return std::nullopt;
  return *v * *unit;
}

std::optional<std::string> string_value(std::string_view s) {
  s = trimmed(s);
  if (s.size() < 2 || s.front() != '\'' || s.back() != '\'') return std::nullopt;
  std::string out;
  for (std::size_t i = 1; i + 1 < s.size(); ++i) {
    out += s[i];
    if (s[i] == '\'') ++i;  // '' is one quote
  }
  return out;
}

}  // namespace

std::map<std::string, ToleranceMeasures> tolerance_measures(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  const Instances all = instances(text);
  std::map<std::string, ToleranceMeasures> out;
  std::map<std::string, int> seen;
  for (const auto& [id, instance] : all) {
    // A complex instance has a GEOMETRIC_TOLERANCE record of its own four attributes; a simple one (FLATNESS_TOLERANCE,
    // ...) has them first.
    const std::string_view simple = trimmed(instance).substr(0, trimmed(instance).find('('));
    const bool tolerance = simple.size() > 10 && simple.substr(simple.size() - 10) == "_TOLERANCE";
    const auto p = parameters(instance, tolerance ? simple : std::string_view("GEOMETRIC_TOLERANCE"));
    if (!p || p->size() < 4) continue;
    const std::optional<std::string> name = string_value((*p)[0]);
    if (!name) continue;
    if (++seen[*name] > 1) continue;
    ToleranceMeasures m;
    m.magnitude = length_mm(all, (*p)[2]);
    if (const auto u = parameters(instance, "UNEQUALLY_DISPOSED_GEOMETRIC_TOLERANCE"); u && u->size() == 1) {
      m.displacement = length_mm(all, (*u)[0]);
    }
    out[*name] = m;
  }
  for (const auto& [name, count] : seen) {
    if (count > 1) out.erase(name);
  }
  return out;
}

}  // namespace probecomp::cad::detail
