#include "probecomp/io/dmis.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>

#include "probecomp/io/text.hpp"

namespace probecomp::io {

namespace {

std::string without_spaces(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c != ' ' && c != '\t') out += c;
  }
  return out;
}

struct Statement {
  std::string text;
  int line = 0;  // where it starts
};

struct DmisPoint {
  bool actual = false;
  std::string label;
  Point3 x;
  std::optional<Vector3> n;
  std::vector<std::string> fields;  // the numbers as written: x, y, z[, i, j, k]
  int line = 0;
  LengthUnit unit;  // of x
};

// A UNITS statement's length unit, or nothing for any other statement.
std::optional<LengthUnit> parse_units(const Statement& s, const std::string& name) {
  const std::string head = upper(without_spaces(s.text));
  if (!head.starts_with("UNITS/")) return std::nullopt;
  const std::size_t comma = head.find(',');
  const std::string length = head.substr(6, comma == std::string::npos ? std::string::npos : comma - 6);
  const std::optional<LengthUnit> u = length_unit(length);
  if (!u) {
    throw InputError(name + ":" + std::to_string(s.line) + ": unknown length unit '" + length +
                     "' (DMIS has MM, CM, METER, INCH and FEET)");
  }
  return u;
}

// A point definition, or nothing for any other statement.
std::optional<DmisPoint> parse_point(const Statement& s, const std::string& name) {
  const std::string where = name + ":" + std::to_string(s.line) + ": ";
  const std::string text = without_spaces(s.text);
  const std::string head = upper(text);
  const bool actual = head.starts_with("FA(");
  if (!actual && !head.starts_with("F(")) return std::nullopt;
  const auto close = text.find(')');
  const auto eq = text.find('=', close == std::string::npos ? 0 : close);
  if (close == std::string::npos || eq == std::string::npos) return std::nullopt;
  const std::string body = head.substr(eq + 1);
  if (!body.starts_with("FEAT/POINT")) return std::nullopt;  // another feature type
  if (!body.starts_with("FEAT/POINT,CART,")) {
    throw InputError(where + "only FEAT/POINT,CART,x,y,z,i,j,k points are read (polar points are not)");
  }
  DmisPoint p;
  p.actual = actual;
  p.line = s.line;
  p.label = text.substr(actual ? 3 : 2, close - (actual ? 3 : 2));
  std::vector<double> v;
  std::istringstream in(text.substr(eq + 1 + std::string("FEAT/POINT,CART,").size()));
  std::string field;
  while (std::getline(in, field, ',')) {
    const std::optional<double> value = parse_number(field);
    if (!value) throw InputError(where + "'" + field + "' is not a number in point " + p.label);
    if (!std::isfinite(*value)) throw InputError(where + "a coordinate of point " + p.label + " is not finite");
    v.push_back(*value);
    p.fields.push_back(field);
  }
  if (v.size() != 3 && v.size() != 6) {
    throw InputError(where + "point " + p.label + " has " + std::to_string(v.size()) +
                     " numbers; expected x,y,z or x,y,z,i,j,k");
  }
  p.x = Point3(v[0], v[1], v[2]);
  if (v.size() == 6) {
    const Vector3 n(v[3], v[4], v[5]);
    if (!(n.norm() > 0.0)) throw InputError(where + "the normal i,j,k of point " + p.label + " is zero");
    p.n = n.normalized();
  }
  return p;
}

}  // namespace

bool is_dmis(const std::filesystem::path& path) {
  const std::string e = upper(path.extension().string());
  return e == ".DMO" || e == ".DMI" || e == ".DMS";
}

PointTable read_points(const std::filesystem::path& path, std::optional<LengthUnit> declared) {
  return is_dmis(path) ? read_point_dmis(path, declared) : read_point_csv(path, declared.value_or(kMillimetre));
}

PointTable read_point_dmis(const std::filesystem::path& path, std::optional<LengthUnit> declared) {
  const std::string name = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(name + ": cannot be opened (missing or unreadable)");
  std::vector<Statement> statements;
  std::string line, pending;
  int number = 0, start = 0;
  while (std::getline(in, line)) {
    ++number;
    std::string text = trim(line);
    if (text.starts_with("$$")) continue;  // a comment
    if (pending.empty()) start = number;
    if (text.ends_with("$")) {
      text.pop_back();
      pending += text;
      continue;
    }
    pending += text;
    if (!trim(pending).empty()) statements.push_back({pending, start});
    pending.clear();
  }
  if (!trim(pending).empty()) {
    throw InputError(name + ":" + std::to_string(start) + ": the file ends inside a statement continued with '$'");
  }
  std::vector<DmisPoint> points;
  LengthUnit unit = declared.value_or(kMillimetre);
  for (const Statement& s : statements) {
    if (auto u = parse_units(s, name)) {
      if (declared && !(*u == *declared)) {
        throw InputError(name + ":" + std::to_string(s.line) + ": the file says its lengths are in " + u->name +
                         ", not in " + declared->name + " as --units says");
      }
      unit = *u;
    } else if (auto p = parse_point(s, name)) {
      p->unit = unit;
      points.push_back(std::move(*p));
    }
  }
  const bool any_actual = std::any_of(points.begin(), points.end(), [](const DmisPoint& p) { return p.actual; });
  std::erase_if(points, [&](const DmisPoint& p) { return p.actual != any_actual; });
  if (points.empty()) throw InputError(name + ": no points (no FA(...) or F(...) = FEAT/POINT,CART statements)");
  const bool with_normals = points.front().n.has_value();
  PointTable t;
  t.unit = points.front().unit;
  t.columns = with_normals ? std::vector<std::string>{"label", "x", "y", "z", "i", "j", "k"}
                           : std::vector<std::string>{"label", "x", "y", "z"};
  std::vector<Vector3> normals;
  for (const DmisPoint& p : points) {
    if (p.n.has_value() != with_normals) {
      throw InputError(name + ":" + std::to_string(p.line) + ": point " + p.label +
                       (with_normals ? " has no normal i,j,k" : " has a normal i,j,k") + " where the first point " +
                       (with_normals ? "has one" : "has none"));
    }
    t.points.push_back(p.unit.mm * p.x);
    t.line.push_back(p.line);
    std::vector<std::string> row{p.label};
    row.insert(row.end(), p.fields.begin(), p.fields.end());
    if (with_normals) normals.push_back(*p.n);
    t.rows.push_back(std::move(row));
  }
  if (with_normals) t.normals = std::move(normals);
  return t;
}

std::string dmis_point(const std::string& label, const Point3& x_mm, const Vector3& n, LengthUnit unit) {
  const Point3 x = x_mm / unit.mm;
  char buf[320];
  std::snprintf(buf, sizeof buf, "FA(%s)=FEAT/POINT,CART,%.9f,%.9f,%.9f,%.12f,%.12f,%.12f\n", label.c_str(), x.x() + 0.0,
                x.y() + 0.0, x.z() + 0.0, n.x() + 0.0, n.y() + 0.0, n.z() + 0.0);
  return buf;
}

std::string dmis_units(LengthUnit unit) { return "UNITS/" + upper(unit.name) + ",ANGDEC\n"; }

}  // namespace probecomp::io
