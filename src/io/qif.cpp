#include "probecomp/io/qif.hpp"

#include <pugixml.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <set>
#include <sstream>

#include "probecomp/io/format.hpp"
#include "probecomp/io/text.hpp"
#include "probecomp/version.hpp"

namespace probecomp::io {

namespace {

constexpr const char* kQifNamespace = "http://qifstandards.org/xsd/qif3";
constexpr const char* kColumnPrefix = "probecomp:column:";  // carried columns in a set's Attributes
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---- reading ----

// An element's name without its namespace prefix: QIF documents may bind the QIF namespace to one.
std::string_view local_name(const pugi::xml_node& n) {
  const std::string_view name = n.name();
  const auto colon = name.find(':');
  return colon == std::string_view::npos ? name : name.substr(colon + 1);
}

pugi::xml_node child(const pugi::xml_node& parent, std::string_view name) {
  for (pugi::xml_node c = parent.first_child(); c; c = c.next_sibling()) {
    if (c.type() == pugi::node_element && local_name(c) == name) return c;
  }
  return {};
}

std::vector<pugi::xml_node> children(const pugi::xml_node& parent, std::string_view name) {
  std::vector<pugi::xml_node> out;
  for (pugi::xml_node c = parent.first_child(); c; c = c.next_sibling()) {
    if (c.type() == pugi::node_element && local_name(c) == name) out.push_back(c);
  }
  return out;
}

// The file's text, and where each of its lines starts: pugixml says where things are as byte offsets.
class Source {
 public:
  explicit Source(const std::filesystem::path& path) : name_(path.string()) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(name_ + ": cannot be opened (missing or unreadable)");
    text_.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    line_starts_.push_back(0);
    for (std::size_t k = 0; k < text_.size(); ++k) {
      if (text_[k] == '\n') line_starts_.push_back(k + 1);
    }
  }
  [[nodiscard]] const std::string& text() const { return text_; }
  [[nodiscard]] const std::string& name() const { return name_; }
  // The line (from 1) of a byte offset; one past the last line break (an error at the end) is on the last line.
  [[nodiscard]] int line(std::ptrdiff_t offset) const {
    const auto last = std::max<std::ptrdiff_t>(static_cast<std::ptrdiff_t>(text_.size()) - 1, 0);
    const auto at = static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(offset, 0, last));
    return static_cast<int>(std::upper_bound(line_starts_.begin(), line_starts_.end(), at) - line_starts_.begin());
  }
  [[nodiscard]] int line(const pugi::xml_node& n) const { return line(n.offset_debug()); }
  // "FILE:LINE: " of a byte offset or an element (the file alone where the offset is not known).
  [[nodiscard]] std::string at(std::ptrdiff_t offset) const {
    return offset < 0 ? name_ + ": " : name_ + ":" + std::to_string(line(offset)) + ": ";
  }
  [[nodiscard]] std::string at(const pugi::xml_node& n) const { return at(n.offset_debug()); }

 private:
  std::string name_, text_;
  std::vector<std::size_t> line_starts_;
};

// An xs:double or xs:decimal token: from_chars' syntax, with XML Schema's leading '+', INF and NaN too.
std::optional<double> schema_number(std::string_view token) {
  if (token == "INF" || token == "+INF") return std::numeric_limits<double>::infinity();
  if (token == "-INF") return -std::numeric_limits<double>::infinity();
  if (token == "NaN") return kNaN;
  if (token.starts_with('+')) {
    token.remove_prefix(1);
    if (token.starts_with('+') || token.starts_with('-')) return std::nullopt;
  }
  return parse_number(token);
}

// A whitespace-separated list (xs:list), each token with its value.
struct List {
  std::vector<std::string> tokens;
  std::vector<double> values;
};

std::vector<std::string> tokens_of(const char* text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  std::string token;
  while (in >> token) out.push_back(token);
  return out;
}

// The lengths' unit of a LinearUnit element, by its UnitName or its UnitConversion/Factor to metres (both, when
// given, must agree).
LengthUnit linear_unit(const pugi::xml_node& unit, const Source& src) {
  struct Known {
    std::vector<std::string_view> names;
    const char* dmis;  // io::length_unit's name
    double metres;
  };
  static const Known known[] = {{{"mm", "millimeter", "millimetre", "millimeters", "millimetres"}, "mm", 0.001},
                                {{"cm", "centimeter", "centimetre", "centimeters", "centimetres"}, "cm", 0.01},
                                {{"m", "meter", "metre", "meters", "metres"}, "meter", 1.0},
                                {{"in", "inch", "inches"}, "inch", 0.0254},
                                {{"ft", "foot", "feet"}, "feet", 0.3048}};
  const std::string name = lower(trim(child(unit, "UnitName").text().as_string()));
  const Known* by_name = nullptr;
  for (const Known& k : known) {
    if (std::find(k.names.begin(), k.names.end(), name) != k.names.end()) by_name = &k;
  }
  const Known* by_factor = nullptr;
  const pugi::xml_node factor_node = child(child(unit, "UnitConversion"), "Factor");
  if (factor_node) {
    const std::optional<double> factor = schema_number(trim(factor_node.text().as_string()));
    for (const Known& k : known) {
      if (factor && std::abs(*factor - k.metres) <= 1e-9 * k.metres) by_factor = &k;
    }
    if (!by_factor) {
      throw InputError(src.at(factor_node) + "LinearUnit: a factor of " + trim(factor_node.text().as_string()) +
                       " to metres is not a length unit probecomp reads (mm, cm, m, inch, foot)");
    }
  }
  if (by_name && by_factor && by_name != by_factor) {
    throw InputError(src.at(unit) + "LinearUnit '" + name + "' has a factor to metres of " +
                     trim(factor_node.text().as_string()) + ", which is not its own");
  }
  if (!by_name && !by_factor) {
    throw InputError(src.at(unit) + "LinearUnit '" + name +
                     "' is not a length unit probecomp reads (mm, cm, m, inch, foot; or give UnitConversion/Factor)");
  }
  return *length_unit((by_name ? by_name : by_factor)->dmis);
}

// One MeasuredPointSet as read.
struct PointSet {
  pugi::xml_node node, points_node;
  std::string id;
  std::string label;  // "MeasuredPointSet id=29" for messages
  std::size_t count = 0;
  List points;
  std::optional<List> normals;
  std::vector<std::string> radius_text;  // per point ("" for none)
  std::vector<double> radii;             // per point, in the set's unit (NaN for none)
  std::optional<LengthUnit> unit;        // its own Units/LinearUnit
  pugi::xml_node unit_node;
  std::vector<std::pair<std::string, std::vector<std::string>>> columns;  // probecomp:column:NAME attributes
};

// A list element's numbers: finite ones (NaN too where `nan_allowed`), `expected` of them.
List read_list(const pugi::xml_node& n, const PointSet& set, std::size_t expected, const char* what,
               const Source& src, bool nan_allowed = false) {
  List l;
  l.tokens = tokens_of(n.text().as_string());
  const std::string where = src.at(n) + set.label + ": ";
  for (std::size_t k = 0; k < l.tokens.size(); ++k) {
    const std::optional<double> v = schema_number(l.tokens[k]);
    if (!v) {
      throw InputError(where + n.name() + ": '" + l.tokens[k] + "' (number " + std::to_string(k + 1) +
                       ") is not a number");
    }
    if (!std::isfinite(*v) && !(nan_allowed && std::isnan(*v))) {
      throw InputError(where + n.name() + ": number " + std::to_string(k + 1) + " ('" + l.tokens[k] +
                       "') is not finite");
    }
    l.values.push_back(*v);
  }
  if (l.values.size() != expected) {
    // Triples (points, normals) counted as such where they are whole.
    const bool triples = expected == 3 * set.count;
    const auto many = [](std::size_t n, const std::string& what) { return std::to_string(n) + " " + what; };
    throw InputError(where + "count is " + std::to_string(set.count) + " but " + n.name() + " holds " +
                     (triples && l.values.size() % 3 == 0 ? many(l.values.size() / 3, what)
                                                          : many(l.values.size(), l.values.size() == 1 ? "number" : "numbers")) +
                     (triples ? " (" + many(expected, "numbers") + " expected)" : ""));
  }
  return l;
}

// The text a row keeps of a number: the file's token when it reads as is, else the shortest exact text.
std::string row_text(const std::string& token, double value) {
  return parse_number(token) ? token : exact(value);
}

PointSet read_set(const pugi::xml_node& node, std::size_t ordinal, const Source& src) {
  PointSet s;
  s.node = node;
  s.id = node.attribute("id").as_string();
  s.label = s.id.empty() ? "MeasuredPointSet " + std::to_string(ordinal) : "MeasuredPointSet id=" + s.id;
  const std::string where = src.at(node) + s.label + ": ";
  const std::string count_text = trim(node.attribute("count").as_string());
  std::uint64_t count = 0;
  const auto [end, ec] = std::from_chars(count_text.data(), count_text.data() + count_text.size(), count);
  if (count_text.empty() || ec != std::errc() || end != count_text.data() + count_text.size() || count == 0 ||
      count > 1'000'000'000) {
    throw InputError(where + "its count attribute must be a positive whole number, not '" + count_text + "'");
  }
  s.count = count;
  for (const char* binary : {"BinaryPoints", "BinaryNormals", "BinaryCompensated", "BinaryProbeRadii"}) {
    if (pugi::xml_node b = child(node, binary)) {
      throw InputError(src.at(b) + s.label + ": binary lists (" + binary +
                       ") are not read; write the set's lists as text");
    }
  }
  // The probe centres: compensated points would be compensated twice.
  if (pugi::xml_node c = child(node, "Compensated")) {
    const std::string v = trim(c.text().as_string());
    if (v == "true" || v == "1") {
      throw InputError(src.at(c) + s.label +
                       ": the points are compensated already (Compensated is true); probecomp needs the probe centres");
    }
    if (v != "false" && v != "0") throw InputError(src.at(c) + s.label + ": Compensated is '" + v + "', not a boolean");
  } else if (pugi::xml_node cs = child(node, "Compensations")) {
    const std::vector<std::string> flags = tokens_of(cs.text().as_string());
    if (flags.size() != s.count) {
      throw InputError(src.at(cs) + s.label + ": count is " + std::to_string(s.count) + " but Compensations holds " +
                       std::to_string(flags.size()) + " values");
    }
    for (std::size_t k = 0; k < flags.size(); ++k) {
      if (flags[k] == "true" || flags[k] == "1") {
        throw InputError(src.at(cs) + s.label + ": point " + std::to_string(k + 1) +
                         " is compensated already (Compensations); probecomp needs the probe centres");
      }
      if (flags[k] != "false" && flags[k] != "0") {
        throw InputError(src.at(cs) + s.label + ": Compensations holds '" + flags[k] + "', not a boolean");
      }
    }
  } else {
    throw InputError(where + "neither Compensated nor Compensations says whether the points are probe centres");
  }
  s.points_node = child(node, "Points");
  if (!s.points_node) throw InputError(where + "no Points");
  s.points = read_list(s.points_node, s, 3 * s.count, "points", src);
  if (pugi::xml_node n = child(node, "Normals")) {
    s.normals = read_list(n, s, 3 * s.count, "normals", src);
    for (std::size_t k = 0; k < s.count; ++k) {
      if (!(Vector3(s.normals->values[3 * k], s.normals->values[3 * k + 1], s.normals->values[3 * k + 2]).norm() > 0.0)) {
        throw InputError(src.at(n) + s.label + ": the normal of point " + std::to_string(k + 1) + " is zero");
      }
    }
  }
  s.radius_text.assign(s.count, "");
  s.radii.assign(s.count, kNaN);
  const auto check_radius = [&](const pugi::xml_node& n, double r, const std::string& token) {
    if (!(r > 0.0)) throw InputError(src.at(n) + s.label + ": a tip radius must be positive, not " + token);
  };
  if (pugi::xml_node r = child(node, "ProbeRadius")) {
    const std::string token = trim(r.text().as_string());
    const std::optional<double> v = schema_number(token);
    if (!v || !std::isfinite(*v)) throw InputError(src.at(r) + s.label + ": ProbeRadius '" + token + "' is not a number");
    check_radius(r, *v, token);
    s.radius_text.assign(s.count, row_text(token, *v));
    s.radii.assign(s.count, *v);
  } else if (pugi::xml_node rs = child(node, "ProbeRadii")) {
    const List l = read_list(rs, s, s.count, "radii", src, true);  // NaN: no radius of its own
    for (std::size_t k = 0; k < s.count; ++k) {
      if (std::isnan(l.values[k])) continue;
      check_radius(rs, l.values[k], l.tokens[k]);
      s.radius_text[k] = row_text(l.tokens[k], l.values[k]);
      s.radii[k] = l.values[k];
    }
  }
  if ((s.unit_node = child(child(node, "Units"), "LinearUnit"))) s.unit = linear_unit(s.unit_node, src);
  for (pugi::xml_node a : children(child(node, "Attributes"), "AttributeStr")) {
    const std::string name = a.attribute("name").as_string();
    const std::string column = name.substr(std::min(name.size(), std::string(kColumnPrefix).size()));
    const std::string l = lower(column);
    // A column of the points' own (x, ..., r) is never carried: the lists say those.
    if (!name.starts_with(kColumnPrefix) || l == "x" || l == "y" || l == "z" || l == "i" || l == "j" || l == "k" ||
        l == "r") {
      continue;
    }
    std::vector<std::string> fields = split_fields(a.attribute("value").as_string(), ',', src.at(a) + s.label + ": ");
    if (fields.size() != s.count) {
      throw InputError(src.at(a) + s.label + ": count is " + std::to_string(s.count) + " but attribute " + name +
                       " holds " + std::to_string(fields.size()) + " fields");
    }
    s.columns.emplace_back(column, std::move(fields));
  }
  return s;
}

// ---- writing ----

// xs:double text: the shortest that reads back as the same double, NaN as XML Schema spells it.
std::string xs_double(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "INF" : "-INF";
  return exact(v);
}

// xs:decimal text (ProbeRadius): no exponent, the shortest fixed-point text that reads back as the same double.
std::string xs_decimal(double v) {
  char buf[400];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v + 0.0, std::chars_format::fixed);
  return std::string(buf, ec == std::errc() ? end : buf);
}

template <class F>
std::string joined(std::size_t begin, std::size_t end, F&& item, const char* separator = " ") {
  std::string out;
  for (std::size_t k = begin; k < end; ++k) {
    if (k > begin) out += separator;
    out += item(k);
  }
  return out;
}

// The document's lengths: LinearUnit with the factor to metres (xs:decimal).
void append_file_units(pugi::xml_node root, LengthUnit unit) {
  const char* factor = unit.mm == 1.0 ? "0.001" : unit.mm == 10.0 ? "0.01" : unit.mm == 1000.0 ? "1" :
                       unit.mm == 25.4 ? "0.0254" : "0.3048";
  pugi::xml_node linear = root.append_child("FileUnits").append_child("PrimaryUnits").append_child("LinearUnit");
  linear.append_child("SIUnitName").text() = "meter";
  linear.append_child("UnitName").text() = unit.name;
  linear.append_child("UnitConversion").append_child("Factor").text() = factor;
}

// A run of consecutive rows with the same `set` value: one MeasuredPointSet.
struct Run {
  std::size_t begin = 0, end = 0;
  std::uint64_t id = 0;
};

struct Runs {
  std::vector<Run> runs;
  bool set_as_column = false;  // the `set` values are not ids: the runs are numbered, `set` kept as a column
  std::uint64_t max_id = 0;
};

// The table's sets: its `set` values as ids when each run's is a distinct QIF id (an unsigned int, no leading
// zero), else the runs numbered 1, 2, ...
Runs runs_of(const PointTable& t) {
  Runs r;
  const int c = column_index(t, "set");
  const std::size_t n = t.points.size();
  const auto value = [&](std::size_t k) {
    return c >= 0 && k < t.rows.size() ? std::string(t.rows[k][static_cast<std::size_t>(c)]) : std::string();
  };
  for (std::size_t k = 0; k < n; ++k) {
    if (k == 0 || value(k) != value(k - 1)) r.runs.push_back({k, k, 0});
    r.runs.back().end = k + 1;
  }
  std::set<std::uint64_t> ids;
  bool ids_usable = c >= 0;
  for (Run& run : r.runs) {
    const std::string v = value(run.begin);
    std::uint64_t id = 0;
    const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), id);
    if (v.empty() || v[0] == '0' || ec != std::errc() || end != v.data() + v.size() || id > 0xFFFFFFFFu - 2 ||
        !ids.insert(id).second) {
      ids_usable = false;
    }
    run.id = id;
  }
  r.set_as_column = c >= 0 && !ids_usable;
  for (std::size_t k = 0; k < r.runs.size(); ++k) {
    if (!ids_usable) r.runs[k].id = k + 1;
    r.max_id = std::max(r.max_id, r.runs[k].id);
  }
  return r;
}

// The carried columns a set's Attributes hold: every one but `set` when the set ids stand for it.
std::vector<int> attribute_columns(const PointTable& t, const Runs& runs) {
  std::vector<int> out;
  if (t.rows.empty()) return out;
  for (int c : t.carried_columns()) {
    if (lower(t.columns[static_cast<std::size_t>(c)]) != "set" || runs.set_as_column) out.push_back(c);
  }
  return out;
}

// The skeleton every document we write shares, up to the MeasuredPointSets element: the root with its ids, the
// header, the units, the results.
struct Document {
  pugi::xml_document doc;
  pugi::xml_node root, attributes, point_sets;
};

void start_document(Document& d, const PointTable& t, const Runs& runs, const std::string& description,
                    const std::vector<std::pair<std::string, std::string>>& attributes) {
  pugi::xml_node decl = d.doc.append_child(pugi::node_declaration);
  decl.append_attribute("version") = "1.0";
  decl.append_attribute("encoding") = "UTF-8";
  d.root = d.doc.append_child("QIFDocument");
  d.root.append_attribute("xmlns") = kQifNamespace;
  const std::uint64_t results_id = runs.max_id + 1;
  d.root.append_attribute("idMax") = static_cast<unsigned long long>(results_id);
  d.root.append_attribute("versionQIF") = "3.0.0";
  d.root.append_child("QPId").text() = "00000000-0000-0000-0000-000000000000";  // set when the document is whole
  if (!attributes.empty()) {
    pugi::xml_node a = d.root.append_child("Attributes");
    a.append_attribute("n") = attributes.size();
    for (const auto& [name, value] : attributes) {
      pugi::xml_node s = a.append_child("AttributeStr");
      s.append_attribute("name") = name.c_str();
      s.append_attribute("value") = value.c_str();
    }
  }
  pugi::xml_node header = d.root.append_child("Header");
  header.append_child("Application").append_child("Name").text() = ("probecomp " + version()).c_str();
  header.append_child("Description").text() = description.c_str();
  append_file_units(d.root, t.unit);
  pugi::xml_node results = d.root.append_child("Results").append_child("MeasurementResultsSet");
  results.append_attribute("n") = 1;
  pugi::xml_node measurement = results.append_child("MeasurementResults");
  measurement.append_attribute("id") = static_cast<unsigned long long>(results_id);
  d.point_sets = measurement.append_child("MeasuredPointSets");
  d.point_sets.append_attribute("n") = runs.runs.size();
  // Nothing is toleranced here: the part's status is not calculated.
  measurement.append_child("InspectionStatus").append_child("InspectionStatusEnum").text() = "NOT_CALCULATED";
}

// The set's element, with its Attributes: `ours` (name, value) and then the carried columns.
pugi::xml_node append_set(Document& d, const PointTable& t, const Run& run, const std::vector<int>& carried,
                          const std::vector<std::pair<std::string, std::string>>& ours) {
  pugi::xml_node s = d.point_sets.append_child("MeasuredPointSet");
  s.append_attribute("count") = run.end - run.begin;
  s.append_attribute("id") = static_cast<unsigned long long>(run.id);
  if (ours.empty() && carried.empty()) return s;
  pugi::xml_node a = s.append_child("Attributes");
  a.append_attribute("n") = ours.size() + carried.size();
  for (const auto& [name, value] : ours) {
    pugi::xml_node x = a.append_child("AttributeStr");
    x.append_attribute("name") = name.c_str();
    x.append_attribute("value") = value.c_str();
  }
  for (int c : carried) {
    pugi::xml_node x = a.append_child("AttributeStr");
    x.append_attribute("name") = (kColumnPrefix + t.columns[static_cast<std::size_t>(c)]).c_str();
    x.append_attribute("value") =
        joined(run.begin, run.end, [&](std::size_t k) { return csv_field(t.rows[k][static_cast<std::size_t>(c)]); }, ",")
            .c_str();
  }
  return s;
}

// ProbeRadius when the run's radii (in the table's unit) are all equal, else ProbeRadii (NaN for none); nothing when
// no point has one.
void append_radii(pugi::xml_node s, const std::vector<double>& radii, const Run& run) {
  if (radii.empty()) return;
  const bool none = std::all_of(radii.begin() + static_cast<std::ptrdiff_t>(run.begin),
                                radii.begin() + static_cast<std::ptrdiff_t>(run.end), [](double r) { return std::isnan(r); });
  if (none) return;
  const bool shared = std::all_of(radii.begin() + static_cast<std::ptrdiff_t>(run.begin),
                                  radii.begin() + static_cast<std::ptrdiff_t>(run.end),
                                  [&](double r) { return r == radii[run.begin]; });
  if (shared) {
    s.append_child("ProbeRadius").text() = xs_decimal(radii[run.begin]).c_str();
  } else {
    s.append_child("ProbeRadii").text() = joined(run.begin, run.end, [&](std::size_t k) { return xs_double(radii[k]); }).c_str();
  }
}

// The whole document as text, its QPId (a UUID, which the schema requires) derived from the rest of it, so that
// the same input gives the same file byte for byte.
std::string finish(Document& d) {
  std::ostringstream first;
  d.doc.save(first, "  ", pugi::format_default, pugi::encoding_utf8);
  const std::string text = first.str();
  std::uint64_t h[2] = {0xcbf29ce484222325ull, 0x84222325cbf29ce4ull};  // FNV-1a, two streams
  for (unsigned char c : text) {
    h[0] = (h[0] ^ c) * 0x100000001b3ull;
    h[1] = (h[1] ^ static_cast<unsigned char>(c + 0x5b)) * 0x100000001b3ull;
  }
  h[0] = (h[0] & ~0xf000ull) | 0x8000ull;  // version 8 (RFC 9562: custom)
  h[1] = (h[1] & ~(3ull << 62)) | (2ull << 62);  // variant 10
  char uuid[40];
  std::snprintf(uuid, sizeof uuid, "%08llx-%04llx-%04llx-%04llx-%012llx", static_cast<unsigned long long>(h[0] >> 32),
                static_cast<unsigned long long>((h[0] >> 16) & 0xffff), static_cast<unsigned long long>(h[0] & 0xffff),
                static_cast<unsigned long long>(h[1] >> 48), static_cast<unsigned long long>(h[1] & 0xffffffffffffull));
  child(d.root, "QPId").text() = uuid;
  std::ostringstream out;
  d.doc.save(out, "  ", pugi::format_default, pugi::encoding_utf8);
  return out.str();
}

// Row k's probe centre in the table's unit, from the rows' text.
struct RowNumbers {
  const PointTable& t;
  int ix, iy, iz, ii, ij, ik, ir;
  explicit RowNumbers(const PointTable& table)
      : t(table), ix(column_index(t, "x")), iy(column_index(t, "y")), iz(column_index(t, "z")),
        ii(column_index(t, "i")), ij(column_index(t, "j")), ik(column_index(t, "k")), ir(column_index(t, "r")) {}
  [[nodiscard]] Vector3 centre(std::size_t k) const {
    const Point3 x = t.points[k] / t.unit.mm;
    return {row_value(t, ix, k, x.x()), row_value(t, iy, k, x.y()), row_value(t, iz, k, x.z())};
  }
  [[nodiscard]] Vector3 normal(std::size_t k) const {
    const Vector3& n = (*t.normals)[k];
    return {row_value(t, ii, k, n.x()), row_value(t, ij, k, n.y()), row_value(t, ik, k, n.z())};
  }
  // Each row's radius in the table's unit (NaN: none); empty when the table has none.
  [[nodiscard]] std::vector<double> radii() const {
    std::vector<double> out;
    if (!t.radii) return out;
    for (std::size_t k = 0; k < t.points.size(); ++k) {
      const double r = (*t.radii)[k];
      out.push_back(std::isnan(r) ? r : row_value(t, ir, k, r / t.unit.mm));
    }
    return out;
  }
};

std::string triples(std::size_t begin, std::size_t end, const std::function<Vector3(std::size_t)>& v) {
  return joined(begin, end, [&](std::size_t k) {
    const Vector3 x = v(k);
    return xs_double(x.x()) + " " + xs_double(x.y()) + " " + xs_double(x.z());
  });
}

}  // namespace

bool is_qif(const std::filesystem::path& path) { return upper(path.extension().string()) == ".QIF"; }

PointTable read_point_qif(const std::filesystem::path& path, std::optional<LengthUnit> declared) {
  const Source src(path);
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_buffer(src.text().data(), src.text().size());
  if (!parsed) throw InputError(src.at(parsed.offset) + "not XML (" + parsed.description() + ")");
  const pugi::xml_node root = doc.document_element();
  if (local_name(root) != "QIFDocument") {
    throw InputError(src.at(root) + "not a QIF document: its root element is " + root.name() + ", not QIFDocument");
  }
  std::optional<LengthUnit> file_unit;
  const pugi::xml_node file_unit_node = child(child(child(root, "FileUnits"), "PrimaryUnits"), "LinearUnit");
  if (file_unit_node) file_unit = linear_unit(file_unit_node, src);
  std::vector<PointSet> sets;
  for (pugi::xml_node results : children(root, "Results")) {
    for (pugi::xml_node results_set : children(results, "MeasurementResultsSet")) {
      for (pugi::xml_node measurement : children(results_set, "MeasurementResults")) {
        for (pugi::xml_node point_sets : children(measurement, "MeasuredPointSets")) {
          for (pugi::xml_node s : children(point_sets, "MeasuredPointSet")) sets.push_back(read_set(s, sets.size() + 1, src));
        }
      }
    }
  }
  if (sets.empty()) {
    throw InputError(src.name() + ": no MeasuredPointSet (under QIFDocument/Results/MeasurementResultsSet/"
                                  "MeasurementResults/MeasuredPointSets)");
  }
  // One unit for the table: the sets' own or the file's, the same for every set, and --units must agree.
  PointTable t;
  std::optional<LengthUnit> stated;
  pugi::xml_node stated_at;
  for (const PointSet& s : sets) {
    const std::optional<LengthUnit> u = s.unit ? s.unit : file_unit;
    const pugi::xml_node at = s.unit ? s.unit_node : file_unit_node;
    if (!u) continue;
    if (stated && !(*u == *stated)) {
      throw InputError(src.at(at) + s.label + ": its lengths are in " + u->name + " but those of an earlier set in " +
                       stated->name + " (one unit per file is read)");
    }
    if (!stated) stated_at = at;
    stated = u;
  }
  if (stated && declared && !(*stated == *declared)) {
    throw InputError(src.at(stated_at) + "the file says its lengths are in " + stated->name + ", not in " +
                     declared->name, Hint::DeclaredUnit);
  }
  t.unit = stated ? *stated : declared.value_or(kMillimetre);
  const bool with_normals = sets.front().normals.has_value();
  const bool with_radii = std::any_of(sets.begin(), sets.end(), [](const PointSet& s) {
    return std::any_of(s.radii.begin(), s.radii.end(), [](double r) { return !std::isnan(r); });
  });
  t.columns = {"x", "y", "z"};
  if (with_normals) t.columns.insert(t.columns.end(), {"i", "j", "k"});
  if (with_radii) t.columns.push_back("r");
  t.columns.push_back("set");
  for (const PointSet& s : sets) {  // the carried columns, in order of first appearance
    for (const auto& [name, fields] : s.columns) {
      if (std::find(t.columns.begin(), t.columns.end(), name) == t.columns.end()) t.columns.push_back(name);
    }
  }
  std::vector<Vector3> normals;
  std::vector<double> radii;
  for (const PointSet& s : sets) {
    if (s.normals.has_value() != with_normals) {
      throw InputError(src.at(s.node) + s.label + (with_normals ? " has no Normals" : " has Normals") +
                       " where the first set " + (with_normals ? "has them" : "has none"));
    }
    const int line = src.line(s.points_node);
    for (std::size_t k = 0; k < s.count; ++k) {
      std::vector<std::string> row;
      const List& p = s.points;
      for (std::size_t a = 3 * k; a < 3 * k + 3; ++a) row.push_back(row_text(p.tokens[a], p.values[a]));
      t.points.emplace_back(t.unit.mm * p.values[3 * k], t.unit.mm * p.values[3 * k + 1], t.unit.mm * p.values[3 * k + 2]);
      if (with_normals) {
        const List& n = *s.normals;
        for (std::size_t a = 3 * k; a < 3 * k + 3; ++a) row.push_back(row_text(n.tokens[a], n.values[a]));
        normals.push_back(Vector3(n.values[3 * k], n.values[3 * k + 1], n.values[3 * k + 2]).normalized());
      }
      if (with_radii) row.push_back(s.radius_text[k]);
      radii.push_back(t.unit.mm * s.radii[k]);
      row.push_back(s.id);
      row.resize(t.columns.size());
      for (const auto& [name, fields] : s.columns) {
        // (A column named set holds the table's own set values, kept when they were not ids: they replace the ids.)
        row[static_cast<std::size_t>(std::find(t.columns.begin(), t.columns.end(), name) - t.columns.begin())] = fields[k];
      }
      t.rows.push_back(row);
      t.line.push_back(line);
    }
  }
  if (t.points.empty()) throw InputError(src.name() + ": no points");
  if (with_normals) t.normals = std::move(normals);
  if (with_radii) t.radii = std::move(radii);
  return t;
}

std::string points_qif(const PointTable& t) {
  const Runs runs = runs_of(t);
  const std::vector<int> carried = attribute_columns(t, runs);
  const RowNumbers numbers(t);
  const std::vector<double> radii = numbers.radii();
  Document d;
  start_document(d, t, runs, "probe centres (uncompensated), lengths in " + std::string(t.unit.name), {});
  for (const Run& run : runs.runs) {
    pugi::xml_node s = append_set(d, t, run, carried, {});
    s.append_child("Points").text() = triples(run.begin, run.end, [&](std::size_t k) { return numbers.centre(k); }).c_str();
    if (t.normals) {
      s.append_child("Normals").text() = triples(run.begin, run.end, [&](std::size_t k) { return numbers.normal(k); }).c_str();
    }
    s.append_child("Compensated").text() = "false";
    append_radii(s, radii, run);
  }
  return finish(d);
}

std::string contact_points_qif(const PointTable& t, const std::vector<QifContactPoint>& points, const std::string& method,
                               const std::string& source) {
  const Runs runs = runs_of(t);
  const std::vector<int> carried = attribute_columns(t, runs);
  const RowNumbers numbers(t);
  const double scale = 1.0 / t.unit.mm;  // mm → the input's unit
  std::vector<double> radii;
  for (const QifContactPoint& p : points) radii.push_back(scale * p.radius);
  Document d;
  start_document(d, t, runs,
                 "contact points compensated by probecomp's " + method + " method, machine frame, lengths in " + t.unit.name,
                 {{"probecomp:method", method}, {"probecomp:source", source}});
  for (const Run& run : runs.runs) {
    const auto point = [&](std::size_t k) -> const QifContactPoint& { return points[k]; };
    const std::vector<std::pair<std::string, std::string>> ours{
        {"probecomp:status", joined(run.begin, run.end, [&](std::size_t k) { return point(k).status; })},
        {"probecomp:u", joined(run.begin, run.end, [&](std::size_t k) {
           return xs_double(point(k).computed ? scale * point(k).uncertainty : kNaN);
         })},
        {"probecomp:face", joined(run.begin, run.end, [&](std::size_t k) { return std::to_string(point(k).face); })}};
    pugi::xml_node s = append_set(d, t, run, carried, ours);
    s.append_child("Points").text() = triples(run.begin, run.end, [&](std::size_t k) {
      return point(k).computed ? Vector3(scale * point(k).contact) : numbers.centre(k);
    }).c_str();
    s.append_child("Normals").text() = triples(run.begin, run.end, [&](std::size_t k) {
      return point(k).computed ? point(k).normal : Vector3(kNaN, kNaN, kNaN);
    }).c_str();
    const bool all = std::all_of(points.begin() + static_cast<std::ptrdiff_t>(run.begin),
                                 points.begin() + static_cast<std::ptrdiff_t>(run.end),
                                 [](const QifContactPoint& p) { return p.computed; });
    if (all) {
      s.append_child("Compensated").text() = "true";
    } else {
      s.append_child("Compensations").text() =
          joined(run.begin, run.end, [&](std::size_t k) { return std::string(point(k).computed ? "true" : "false"); }).c_str();
    }
    append_radii(s, radii, run);
    s.append_child("Deviations").text() = joined(run.begin, run.end, [&](std::size_t k) {
      return xs_double(point(k).computed ? scale * point(k).deviation : kNaN);
    }).c_str();
  }
  return finish(d);
}

}  // namespace probecomp::io
