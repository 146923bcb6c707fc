#include "probecomp/io/dmis.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include "probecomp/io/format.hpp"
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

// A ball tip's definition, S(name)=SNSDEF/... (or SA(name), a calibrated one).
struct Sensor {
  std::string name;        // as written
  std::string definition;  // after the '=', blanks removed
  int line = 0;
  double diameter = 0.0;   // in `unit`, when `problem` is empty
  LengthUnit unit;
  std::string problem;     // why probecomp cannot read this definition, for a selection of it to report
};

struct DmisPoint {
  bool actual = false;
  std::string label;
  Point3 x;
  std::optional<Vector3> n;
  std::vector<std::string> fields;  // the numbers as written: x, y, z[, i, j, k]
  int line = 0;
  LengthUnit unit;  // of x
  const Sensor* tip = nullptr;  // the sensor selected when it was measured
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

// A labelled statement `L(label)=BODY` or its actual `LA(label)=BODY` (L the letter, F for features and S for
// sensors), spaces removed: the label as written, BODY upper-cased and as written, and where BODY starts.
struct Labelled {
  bool actual = false;
  std::string text, label, body;  // text: the statement without spaces; body: upper-cased
  std::size_t body_at = 0;        // index of BODY in text
};
std::optional<Labelled> labelled(const Statement& s, char letter) {
  Labelled l;
  l.text = without_spaces(s.text);
  const std::string head = upper(l.text);
  l.actual = head.starts_with(std::string{letter, 'A', '('});
  if (!l.actual && !head.starts_with(std::string{letter, '('})) return std::nullopt;
  const auto close = l.text.find(')');
  const auto eq = l.text.find('=', close == std::string::npos ? 0 : close);
  if (close == std::string::npos || eq == std::string::npos) return std::nullopt;
  const std::size_t open = l.actual ? 3 : 2;
  l.label = l.text.substr(open, close - open);
  l.body_at = eq + 1;
  l.body = head.substr(l.body_at);
  return l;
}

// A point definition, or nothing for any other statement.
std::optional<DmisPoint> parse_point(const Statement& s, const std::string& name) {
  const std::string where = name + ":" + std::to_string(s.line) + ": ";
  const std::optional<Labelled> l = labelled(s, 'F');
  if (!l) return std::nullopt;
  const std::string& text = l->text;
  const std::string& body = l->body;
  if (!body.starts_with("FEAT/POINT")) return std::nullopt;  // another feature type
  if (!body.starts_with("FEAT/POINT,CART,")) {
    throw InputError(where + "only FEAT/POINT,CART,x,y,z,i,j,k points are read (polar points are not)");
  }
  DmisPoint p;
  p.actual = l->actual;
  p.line = s.line;
  p.label = l->label;
  std::vector<double> v;
  std::istringstream in(text.substr(l->body_at + std::string("FEAT/POINT,CART,").size()));
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

// The fields of a statement's body after its major word ("SNSDEF/PROBE,INDEX,..." → PROBE, INDEX, ...).
std::vector<std::string> fields_after(const std::string& text, std::size_t start) {
  std::vector<std::string> out;
  std::istringstream in(text.substr(start));
  std::string field;
  while (std::getline(in, field, ',')) out.push_back(field);
  return out;
}

// A sensor definition, or nothing for any other statement. The forms read are DMIS's for a ball on a probe head:
//   SNSDEF/PROBE,INDEX|FIXED,POL,tilt,rotate,i,j,k,length,diameter
//   SNSDEF/PROBE,INDEX|FIXED,CART,x,y,z,i,j,k,diameter
// (a trailing SPHERE names the ball). Any other form (a DISC or CYLNDR tip, another sensor type) is kept with the
// reason it is not read: a file may define sensors it never measures with.
std::optional<Sensor> parse_sensor(const Statement& s, const std::string& name, LengthUnit unit) {
  const std::optional<Labelled> l = labelled(s, 'S');
  if (!l || !l->body.starts_with("SNSDEF/")) return std::nullopt;
  const std::string& text = l->text;
  Sensor x;
  x.name = l->label;
  x.definition = text.substr(l->body_at);
  x.line = s.line;
  x.unit = unit;
  const std::vector<std::string> f = fields_after(text, l->body_at + std::string("SNSDEF/").size());
  const auto is = [&](std::size_t k, const char* word) { return k < f.size() && upper(f[k]) == word; };
  if (!is(0, "PROBE") || !(is(1, "INDEX") || is(1, "FIXED")) || !(is(2, "POL") || is(2, "CART"))) {
    x.problem = "only ball tips defined as SNSDEF/PROBE,INDEX|FIXED,POL,tilt,rotate,i,j,k,length,diameter or "
                "SNSDEF/PROBE,INDEX|FIXED,CART,x,y,z,i,j,k,diameter are read";
    return x;
  }
  std::vector<std::string> numbers(f.begin() + 3, f.end());
  if (numbers.size() == 8 && upper(numbers[7]) == "SPHERE") numbers.pop_back();
  if (numbers.size() > 7 && !parse_number(numbers[7])) {
    x.problem = "its tip is a " + upper(numbers[7]) + ", and only ball tips are compensated";
    return x;
  }
  if (numbers.size() != 7) {
    x.problem = "it has " + std::to_string(numbers.size()) + " numbers after " + upper(f[2]) + "; expected 7 (" +
                (is(2, "POL") ? "tilt, rotate, i, j, k, length, diameter" : "x, y, z, i, j, k, diameter") + ")";
    return x;
  }
  const std::string where = name + ":" + std::to_string(s.line) + ": sensor S(" + x.name + "): ";
  for (std::size_t k = 0; k + 1 < numbers.size(); ++k) {
    if (!parse_number(numbers[k])) throw InputError(where + "'" + numbers[k] + "' is not a number");
  }
  const std::optional<double> d = parse_number(numbers.back());
  if (!d || !std::isfinite(*d) || !(*d > 0.0)) {
    throw InputError(where + "the ball diameter (the last number) must be a positive number, not '" + numbers.back() +
                     "'");
  }
  x.diameter = *d;
  return x;
}

// A sensor selection, SNSLCT/S(name) or SNSLCT/SA(name), as the name; "" for another form of SNSLCT; nothing for
// any other statement.
std::optional<std::string> parse_selection(const Statement& s) {
  const std::string text = without_spaces(s.text);
  const std::string head = upper(text);
  if (!head.starts_with("SNSLCT/")) return std::nullopt;
  const std::size_t open = head.starts_with("SNSLCT/S(") ? 9 : head.starts_with("SNSLCT/SA(") ? 10 : 0;
  const auto close = text.find(')', open);
  if (open == 0 || close == std::string::npos) return std::string();
  return text.substr(open, close - open);
}

// A number's text for a row in another unit than it was written in: the shortest text of its value there.
std::string in_unit(const std::string& field, LengthUnit from, LengthUnit to) {
  if (from == to) return field;
  return exact(parse_number(field).value_or(0.0) * from.mm / to.mm);
}

}  // namespace

bool is_dmis(const std::filesystem::path& path) {
  const std::string e = upper(path.extension().string());
  return e == ".DMO" || e == ".DMI" || e == ".DMS";
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
  // Every definition read, in order (a redefinition of a name applies to the selections after it), and the
  // latest of each name (upper case: DMIS names are not case-sensitive).
  std::vector<std::unique_ptr<Sensor>> definitions;
  std::map<std::string, const Sensor*> sensors;
  const Sensor* selected = nullptr;
  std::optional<Statement> unread_selection;  // an SNSLCT of another form, in force
  for (const Statement& s : statements) {
    const std::string where = name + ":" + std::to_string(s.line) + ": ";
    if (auto u = parse_units(s, name)) {
      if (declared && !(*u == *declared)) {
        throw InputError(where + "the file says its lengths are in " + u->name + ", not in " + declared->name,
                         Hint::DeclaredUnit);
      }
      unit = *u;
    } else if (auto x = parse_sensor(s, name, unit)) {
      definitions.push_back(std::make_unique<Sensor>(std::move(*x)));
      sensors[upper(definitions.back()->name)] = definitions.back().get();
    } else if (auto tip = parse_selection(s)) {
      unread_selection.reset();
      selected = nullptr;
      if (tip->empty()) {
        unread_selection = s;  // an error only if a point is measured under it
        continue;
      }
      const auto found = sensors.find(upper(*tip));
      if (found == sensors.end()) {
        throw InputError(where + "SNSLCT selects S(" + *tip + "), which no SNSDEF before it defines");
      }
      if (!found->second->problem.empty()) {
        throw InputError(where + "SNSLCT selects S(" + *tip + "), whose definition (line " +
                         std::to_string(found->second->line) + ") probecomp cannot read: " + found->second->problem);
      }
      selected = found->second;
    } else if (auto p = parse_point(s, name)) {
      if (unread_selection) {
        throw InputError(name + ":" + std::to_string(unread_selection->line) + ": point " + p->label +
                         " is measured with the sensor this SNSLCT selects, and only SNSLCT/S(name) is read");
      }
      p->unit = unit;
      p->tip = selected;
      points.push_back(std::move(*p));
    }
  }
  const bool any_actual = std::any_of(points.begin(), points.end(), [](const DmisPoint& p) { return p.actual; });
  std::erase_if(points, [&](const DmisPoint& p) { return p.actual != any_actual; });
  if (points.empty()) throw InputError(name + ": no points (no FA(...) or F(...) = FEAT/POINT,CART statements)");
  const bool with_normals = points.front().n.has_value();
  const bool with_tips = std::any_of(points.begin(), points.end(), [](const DmisPoint& p) { return p.tip != nullptr; });
  PointTable t;
  t.unit = points.front().unit;
  t.columns = with_normals ? std::vector<std::string>{"label", "x", "y", "z", "i", "j", "k"}
                           : std::vector<std::string>{"label", "x", "y", "z"};
  if (with_tips) t.columns.insert(t.columns.end(), {"r", "tip"});
  std::vector<Vector3> normals;
  std::vector<double> radii;
  for (const DmisPoint& p : points) {
    if (p.n.has_value() != with_normals) {
      throw InputError(name + ":" + std::to_string(p.line) + ": point " + p.label +
                       (with_normals ? " has no normal i,j,k" : " has a normal i,j,k") + " where the first point " +
                       (with_normals ? "has one" : "has none"));
    }
    t.points.push_back(p.unit.mm * p.x);
    t.line.push_back(p.line);
    std::vector<std::string> row{p.label};
    for (std::size_t c = 0; c < p.fields.size(); ++c) row.push_back(c < 3 ? in_unit(p.fields[c], p.unit, t.unit) : p.fields[c]);
    if (with_normals) normals.push_back(*p.n);
    if (with_tips && p.tip == nullptr) {
      row.insert(row.end(), {"", ""});
      radii.push_back(std::numeric_limits<double>::quiet_NaN());
    } else if (with_tips) {
      // Half the diameter is exact in binary, so the radius reads back as the same number.
      row.push_back(in_unit(exact(p.tip->diameter / 2), p.tip->unit, t.unit));
      row.push_back(p.tip->name);
      radii.push_back(p.tip->unit.mm * p.tip->diameter / 2);
      t.sensor_definitions.emplace(p.tip->name, p.tip->definition);
    }
    t.rows.push_back(row);
  }
  if (with_normals) t.normals = std::move(normals);
  if (with_tips) t.radii = std::move(radii);
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

std::string dmis_label(const PointTable& t, std::size_t k) {
  for (std::size_t c = 0; c < t.columns.size(); ++c) {
    const std::string n = lower(t.columns[c]);
    if ((n == "label" || n == "id") && k < t.rows.size()) return std::string(t.rows[k][c]);
  }
  std::string label = "P";
  label += std::to_string(k + 1);
  return label;
}

DmisTips::DmisTips(const PointTable& t, const std::vector<double>& radii) : tip_of_row_(radii.size(), -1) {
  const int tip_column = column_index(t, "tip");
  std::map<std::pair<std::string, double>, int> by_name_and_radius;  // the name given (or none) and the radius
  int generated = 0;
  for (std::size_t k = 0; k < radii.size(); ++k) {
    const double r = radii[k];
    if (std::isnan(r)) {
      if (k > 0 && tip_of_row_[k - 1] >= 0) {
        throw InputError("line " + std::to_string(k < t.line.size() ? t.line[k] : static_cast<int>(k) + 1) +
                         ": this point has no tip radius but an earlier one has, and DMIS cannot deselect a sensor");
      }
      continue;
    }
    const std::string given =
        tip_column >= 0 && k < t.rows.size() ? std::string(t.rows[k][static_cast<std::size_t>(tip_column)]) : std::string();
    const auto [at, added] = by_name_and_radius.emplace(std::pair(given, r), static_cast<int>(tips_.size()));
    tip_of_row_[k] = at->second;
    if (!added) continue;
    // A new tip: the name given (with a suffix when it already stands for another radius), else TIPn.
    const auto taken = [&](const std::string& name) {
      return std::any_of(tips_.begin(), tips_.end(), [&](const Tip& x) { return x.name == name; });
    };
    std::string name = given.empty() ? "TIP" + std::to_string(++generated) : given;
    for (int suffix = 2; taken(name); ++suffix) {
      name = given.empty() ? "TIP" + std::to_string(++generated) : given + "_" + std::to_string(suffix);
    }
    Tip tip{name, "", r};
    // The input's own definition of this tip, when its ball is this one.
    const auto found = t.sensor_definitions.find(given);
    if (found != t.sensor_definitions.end()) {
      const std::string& d = found->second;
      if (parse_number(d.substr(d.rfind(',') + 1)) == 2 * r) tip.definition = d;
    }
    tips_.push_back(tip);
  }
}

std::string DmisTips::definitions() const {
  std::string out;
  for (const Tip& tip : tips_) {
    if (!tip.definition.empty()) {
      out += "S(" + tip.name + ")=" + tip.definition + "\n";
      continue;
    }
    out += "$$ S(" + tip.name + "): the ball's diameter as measured with; the probe's orientation and length are not "
           "known here (neutral INDEX,POL,0,0,0,0,1,0)\n";
    out += "S(" + tip.name + ")=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,0," + exact(2 * tip.radius) + "\n";
  }
  return out;
}

std::string DmisTips::select(std::size_t k) {
  if (tip_of_row_[k] < 0 || tip_of_row_[k] == selected_) return {};
  selected_ = tip_of_row_[k];
  return "SNSLCT/S(" + tips_[static_cast<std::size_t>(selected_)].name + ")\n";
}

std::string points_dmis(const PointTable& t, const std::string& source) {
  const double scale = 1.0 / t.unit.mm;  // mm → the table's unit, for a table without the rows' text
  const int ix = column_index(t, "x"), iy = column_index(t, "y"), iz = column_index(t, "z");
  const int ii = column_index(t, "i"), ij = column_index(t, "j"), ik = column_index(t, "k"), ir = column_index(t, "r");
  std::vector<double> radii;
  if (t.radii) {
    for (std::size_t k = 0; k < t.points.size(); ++k) {
      const double r = (*t.radii)[k];
      radii.push_back(std::isnan(r) ? r : row_value(t, ir, k, scale * r));
    }
  }
  DmisTips tips(t, radii);
  std::ostringstream out;
  out << "$$ probecomp: the " << t.points.size() << " measured points (probe centres) of " << source << ", "
      << t.unit.name << "\n";
  out << dmis_units(t.unit) << tips.definitions();
  for (std::size_t k = 0; k < t.points.size(); ++k) {
    if (t.radii) out << tips.select(k);
    const Point3& x = t.points[k];
    out << "FA(" << dmis_label(t, k) << ")=FEAT/POINT,CART," << exact(row_value(t, ix, k, scale * x.x())) << ','
        << exact(row_value(t, iy, k, scale * x.y())) << ',' << exact(row_value(t, iz, k, scale * x.z()));
    if (t.normals) {
      const Vector3& n = (*t.normals)[k];
      out << ',' << exact(row_value(t, ii, k, n.x())) << ',' << exact(row_value(t, ij, k, n.y())) << ','
          << exact(row_value(t, ik, k, n.z()));
    }
    out << '\n';
  }
  return out.str();
}

}  // namespace probecomp::io
