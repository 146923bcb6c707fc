#include "probecomp/inspection/characteristics.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "probecomp/cad/locator.hpp"
#include "probecomp/error.hpp"
#include "restricted_fit.hpp"

namespace probecomp::inspection {

namespace {

// The coverage factor of a decision over n points: their intervals d ± k·u cover their true deviations all together
// with 95 % probability (Šidák 1967, normal errors): each with 0.95^(1/n), so k = Φ⁻¹(1 − (1 − 0.95^(1/n))/2), and
// never below ISO 14253-1's k = 2 (one point: 1.96). With k = 2 on each of many points, a face exactly at its limit
// would have some point's whole interval past it by chance (20 points: 37 % of the time) and be rejected.
double coverage_factor(int n) {
  const double tail = 0.5 * (1.0 - std::pow(0.95, 1.0 / std::max(1, n)));  // one side's probability per point
  // Φ⁻¹(1 − tail) by Newton on the upper tail Q(x) = erfc(x/√2)/2, from x = 2 (Q is convex for x > 0: monotone).
  double x = 2.0;
  for (int i = 0; i < 50; ++i) {
    const double q = 0.5 * std::erfc(x / std::sqrt(2.0));
    const double density = std::exp(-0.5 * x * x) / std::sqrt(2.0 * M_PI);
    const double step = (q - tail) / density;
    x += step;
    if (std::abs(step) < 1e-12) break;
  }
  return std::max(2.0, x);
}

[[noreturn]] void bad(const std::filesystem::path& path, const std::string& why) {
  throw InputError(path.string() + ": " + why);
}

}  // namespace

const char* to_string(Decision d) {
  switch (d) {
    case Decision::Conforms: return "conforms";
    case Decision::DoesNotConform: return "does-not-conform";
    case Decision::Indeterminate: return "indeterminate";
    case Decision::NotEvaluated: return "not-evaluated";
  }
  return "not-evaluated";
}

Specification read_specification(const std::filesystem::path& path, const cad::Model& model) {
  std::ifstream in(path);
  if (!in) bad(path, "cannot be opened");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    bad(path, std::string("not JSON: ") + e.what());
  }
  if (!j.is_object() || !j.contains("characteristics") || !j["characteristics"].is_array()) {
    bad(path, "expected an object with a \"characteristics\" array");
  }
  auto read_faces = [&](const nlohmann::json& faces, const std::string& where) {
    if (!faces.is_array() || faces.empty()) bad(path, where + ": no \"faces\"");
    std::vector<int> out;
    for (const nlohmann::json& f : faces) {
      const int face = f.get<int>();
      if (face < 0 || face >= model.face_count()) {
        bad(path, where + ": face " + std::to_string(face) + " is not in the model (" + std::to_string(model.face_count()) + " faces)");
      }
      out.push_back(face);
    }
    return out;
  };
  Specification spec;
  std::set<std::string> datums;
  if (j.contains("datums")) {
    if (!j["datums"].is_object()) bad(path, "\"datums\" must be an object of named datums");
    for (const auto& [name, d] : j["datums"].items()) {
      const std::string where = "datum " + name;
      try {
        if (!d.is_object() || !d.contains("faces")) bad(path, where + ": no \"faces\"");
        DatumSpec datum{.name = name, .faces = read_faces(d["faces"], where)};
        const std::string fit = d.value("fit", std::string("least-squares"));
        if (fit == "tangent") {
          datum.fit = DatumFit::Tangent;
        } else if (fit != "least-squares") {
          bad(path, where + ": unknown fit \"" + fit + "\" (expected least-squares or tangent)");
        }
        if (d.contains("targets")) {
          // Point targets, [x, y, z] in the model's mm, and line targets, {"point", "direction", "length"}: NAME1,
          // NAME2, ... in their order.
          if (!d["targets"].is_array() || d["targets"].empty()) {
            bad(path, where + ": \"targets\" must be a list of points [x, y, z] or lines {\"point\", \"direction\", \"length\"}");
          }
          const auto triple = [&](const nlohmann::json& v, const char* what) {
            if (!v.is_array() || v.size() != 3) bad(path, where + ": a target's " + what + " must be [x, y, z]");
            const Vector3 x(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
            if (!x.allFinite()) bad(path, where + ": a target's " + what + " must be finite");
            return x;
          };
          for (const nlohmann::json& t : d["targets"]) {
            Target target{.label = name + std::to_string(datum.targets.size() + 1)};
            if (t.is_object()) {
              if (!t.contains("point") || !t.contains("direction") || !t.contains("length")) {
                bad(path, where + ": a line target needs \"point\", \"direction\" and \"length\" (mm)");
              }
              target.point = triple(t["point"], "point");
              target.direction = triple(t["direction"], "direction");
              target.length = t["length"].get<double>();
              if (!(target.direction.norm() > 0.0)) bad(path, where + ": a line target's direction must not be zero");
              if (!(target.length > 0.0) || !std::isfinite(target.length)) {
                bad(path, where + ": a line target's length must be positive (mm)");
              }
              target.direction.normalize();
            } else {
              target.point = triple(t, "point");
            }
            datum.targets.push_back(std::move(target));
          }
        }
        spec.datums.push_back(std::move(datum));
      } catch (const nlohmann::json::exception& e) {
        bad(path, where + ": " + e.what());
      }
      datums.insert(name);
    }
  }
  if (j.contains("alignment")) {
    try {
      for (const nlohmann::json& d : j["alignment"]) {
        const std::string name = d.get<std::string>();
        if (!datums.contains(name)) bad(path, "alignment: datum " + name + " is not defined under \"datums\"");
        spec.alignment.push_back(name);
      }
    } catch (const nlohmann::json::exception& e) {
      bad(path, std::string("alignment: ") + e.what());
    }
    if (spec.alignment.empty()) bad(path, "alignment: no datums (leave it out for the best fit of all points)");
  }
  int k = 0;
  for (const nlohmann::json& c : j["characteristics"]) {
    ++k;
    CharacteristicSpec s;
    const std::string where = "characteristic " + std::to_string(k);
    try {
      s.name = c.value("name", std::string("C").append(std::to_string(k)));
      s.type = c.value("type", std::string("surface-profile"));
      if (s.type != "surface-profile") bad(path, where + ": unknown type \"" + s.type + "\" (expected surface-profile)");
      if (!c.contains("faces")) bad(path, where + ": no \"faces\"");
      s.faces = read_faces(c["faces"], where);
      if (!c.contains("tolerance")) bad(path, where + ": no \"tolerance\"");
      s.tolerance = c["tolerance"].get<double>();
      if (!(s.tolerance > 0.0) || !std::isfinite(s.tolerance)) bad(path, where + ": the tolerance must be positive (mm)");
      if (c.contains("outside")) {
        s.outside = c["outside"].get<double>();
        if (!(*s.outside >= 0.0 && *s.outside <= s.tolerance)) bad(path, where + ": \"outside\" must lie in [0, tolerance]");
      }
      if (c.contains("datums")) {
        for (const nlohmann::json& d : c["datums"]) {
          const std::string name = d.get<std::string>();
          if (!datums.contains(name)) bad(path, where + ": datum " + name + " is not defined under \"datums\"");
          s.datums.push_back(name);
        }
      }
    } catch (const nlohmann::json::exception& e) {
      bad(path, where + ": " + e.what());
    }
    spec.characteristics.push_back(std::move(s));
  }
  return spec;
}

std::vector<int> datum_faces(const Specification& spec) {
  std::set<int> faces;
  for (const DatumSpec& d : spec.datums) faces.insert(d.faces.begin(), d.faces.end());
  return {faces.begin(), faces.end()};
}

Specification from_pmi(const cad::Pmi& pmi, int& skipped) {
  Specification spec;
  for (const cad::DatumFeature& d : pmi.datum_features) {
    if (d.point_or_line_targets > 0) {
      spec.unusable_datums[d.name] = "datum " + d.name + " is set by " + std::to_string(d.point_or_line_targets) +
                                     " datum targets (points or lines) the file does not place on a face";
    } else if (d.faces.empty()) {
      spec.unusable_datums[d.name] = "datum " + d.name + ": its datum feature could not be read from the file";
    } else {
      DatumSpec datum{.name = d.name, .faces = d.faces};
      for (const cad::DatumTarget& t : d.targets) {
        datum.targets.push_back({d.name + std::to_string(t.number), t.point, t.direction, t.length});
      }
      spec.datums.push_back(std::move(datum));
    }
  }
  skipped = 0;
  int k = 0;
  for (const cad::GeometricTolerance& t : pmi.tolerances) {
    ++k;
    if (t.type != cad::ToleranceType::ProfileOfSurface && t.type != cad::ToleranceType::Flatness) {
      ++skipped;
      continue;
    }
    CharacteristicSpec s;
    s.name = std::string(t.type == cad::ToleranceType::Flatness ? "flatness " : "profile ") + std::to_string(k);
    s.faces = t.faces;
    s.tolerance = t.value.value_or(0.0);
    if (t.type == cad::ToleranceType::ProfileOfSurface) {
      s.datums = t.datums;
      s.outside = t.outside;  // within [0, value]: read_pmi refuses a displacement beyond it, with its value
    }
    spec.characteristics.push_back(std::move(s));
  }
  return spec;
}

LoadedSpecification load_specification(const std::string& source, const cad::Model& model) {
  LoadedSpecification out;
  if (source != "pmi") {
    out.spec = read_specification(source, model);
    return out;
  }
  const cad::Pmi pmi = cad::read_pmi(model.path, model);
  for (const std::string& w : pmi.warnings) out.warnings.push_back(model.path.string() + ": " + w);
  int skipped = 0;
  out.spec = from_pmi(pmi, skipped);
  if (out.spec.characteristics.empty()) {
    throw std::invalid_argument(model.path.string() + " states no surface profile or flatness" +
                                (pmi.tolerances.empty() ? " (no semantic PMI: STEP AP242 carries it)" : ""));
  }
  if (skipped > 0) {
    out.warnings.push_back(std::to_string(skipped) + " of the file's tolerances are not surface profiles or flatness and "
                           "are not evaluated");
  }
  return out;
}

Inspection evaluate(const Specification& spec, const cad::Model& nominal, const compensation::CompensationResult& result) {
  Inspection out;
  std::map<std::string, DatumFrame>& frames = out.frames;
  for (const CharacteristicSpec& s : spec.characteristics) {
    CharacteristicResult c;
    c.spec = s;
    c.outside = s.outside.value_or(0.5 * s.tolerance);
    auto not_evaluated = [&](const std::string& why) {
      c.reason = why;
      out.characteristics.push_back(std::move(c));
    };
    if (!(s.tolerance > 0.0)) {
      not_evaluated("no tolerance magnitude (the file's could not be read)");
      continue;
    }
    std::string key;
    std::vector<DatumSpec> order;
    std::string missing;
    for (const std::string& name : s.datums) {
      if (!key.empty()) key += '|';
      key += name;
      const auto d = std::find_if(spec.datums.begin(), spec.datums.end(), [&](const DatumSpec& x) { return x.name == name; });
      if (d == spec.datums.end()) {
        missing = name;
        break;
      }
      order.push_back(*d);
    }
    if (!missing.empty()) {
      const auto why = spec.unusable_datums.find(missing);
      not_evaluated(why != spec.unusable_datums.end() ? why->second : "datum " + missing + " is not defined");
      continue;
    }
    auto [it, added] = frames.try_emplace(key);
    if (added) {
      it->second = establish_frame(order, nominal, result);
      for (const DatumResult& d : it->second.datums) out.datums.push_back({key, d});
    }
    const DatumFrame& frame = it->second;
    if (!frame.ok()) {
      not_evaluated("datum reference frame " + key + ": " + frame.reason);
      continue;
    }
    // The trusted points on the characteristic's faces, in the CAD frame as its datums locate the part, and those
    // faces alone as a model to fit them to.
    const std::set<int> faces(s.faces.begin(), s.faces.end());
    const geometry::RigidTransform to_cad = frame.transform.inverse();
    std::vector<Point3> points;
    std::vector<double> u;
    std::vector<std::size_t> row;
    for (std::size_t k = 0; k < result.points.size(); ++k) {
      const compensation::CompensatedPoint& p = result.points[k];
      if (p.status == compensation::PointStatus::Ok && faces.contains(p.face)) {
        points.push_back(to_cad * p.contact);
        u.push_back(p.uncertainty);
        row.push_back(k);
      }
    }
    const int needed = std::max(1, static_cast<int>(frame.free_basis.cols()) + 1);
    if (static_cast<int>(points.size()) < needed) {
      c.points = static_cast<int>(points.size());
      c.too_few_points = true;
      not_evaluated(std::to_string(c.points) + " trusted points on its faces (" + std::to_string(needed) +
                    " needed for the motions its datums leave free)");
      continue;
    }
    const cad::Model own = faces_of(nominal, s.faces);
    const cad::ModelLocator locator(own);
    // Least squares (not the registration's robust weights: every trusted point counts).
    const RestrictedFit fit = fit_in_motions(locator, points, frame.free_basis, frame.centre, frame.length, false);
    if (!fit.converged) {
      not_evaluated("the best fit of its points to its faces did not converge");
      continue;
    }
    const double centre = c.outside - 0.5 * s.tolerance;
    c.min = std::numeric_limits<double>::infinity();
    c.max = -std::numeric_limits<double>::infinity();
    // A point whose foot fell on its faces' edge after the fit is past them (its distance is not along a normal):
    // fit_in_motions leaves it out, and it is not counted.
    c.points = static_cast<int>(fit.used.size());
    c.coverage = coverage_factor(c.points);
    bool inside = true, outside_surely = false;
    std::optional<JudgedPoint> held_back;  // of the points whose d ± U crosses a limit, the one of largest U
    for (Eigen::Index r = 0; r < fit.d.size(); ++r) {
      const double d = fit.d(r);
      const Eigen::Matrix<double, 6, 1> J = fit.J.row(r).transpose();
      const double uk = u[static_cast<std::size_t>(fit.used[static_cast<std::size_t>(r)])];
      const double ud = std::sqrt(uk * uk + J.dot(frame.covariance * J));  // the point's own and its datums' share
      const double U = c.coverage * ud;
      c.min = std::min(c.min, d);
      c.max = std::max(c.max, d);
      const double width = 2.0 * std::abs(d - centre);
      if (width > c.value) {
        c.value = width;
        c.u = 2.0 * ud;
      }
      inside = inside && d - U >= c.outside - s.tolerance && d + U <= c.outside;
      outside_surely = outside_surely || d - U > c.outside || d + U < c.outside - s.tolerance;
      const bool straddles = (d - U < c.outside && d + U > c.outside) ||
                             (d - U < c.outside - s.tolerance && d + U > c.outside - s.tolerance);
      const std::size_t at = row[static_cast<std::size_t>(fit.used[static_cast<std::size_t>(r)])];
      if (straddles) c.undecided.push_back(at);
      c.judged.push_back({.row = at, .deviation = d, .U = U});
      if (straddles && (!held_back || U > held_back->U)) held_back = c.judged.back();
    }
    if (c.points < needed) {
      c.too_few_points = true;
      not_evaluated("after the best fit only " + std::to_string(c.points) + " of its points lie inside its faces");
      continue;
    }
    c.decision = outside_surely ? Decision::DoesNotConform : inside ? Decision::Conforms : Decision::Indeterminate;
    if (c.decision == Decision::Indeterminate) {
      // What holds it back, in one line: the value and its 2u describe the widest point, which may be well inside
      // while a point of large u (a contact whose normal could not be confirmed: u up to r) crosses a limit.
      char line[200];
      if (held_back) {
        std::snprintf(line, sizeof line, "%zu of its points' d +- U cross a limit of the zone; the largest U %.4f mm, row %zu",
                      c.undecided.size(), held_back->U, held_back->row + 1);
      } else {
        std::snprintf(line, sizeof line, "a point's U is not finite");
      }
      c.reason = line;
    }
    out.characteristics.push_back(std::move(c));
  }
  if (!spec.alignment.empty()) {
    std::vector<DatumSpec> order;
    for (const std::string& name : spec.alignment) {
      if (!out.alignment.empty()) out.alignment += '|';
      out.alignment += name;
      const auto d = std::find_if(spec.datums.begin(), spec.datums.end(), [&](const DatumSpec& x) { return x.name == name; });
      if (d != spec.datums.end()) order.push_back(*d);
    }
    out.alignment_frame = establish_frame(order, nominal, result);
    if (frames.try_emplace(out.alignment, *out.alignment_frame).second && out.alignment_frame->ok()) {
      for (const DatumResult& d : out.alignment_frame->datums) out.datums.push_back({out.alignment, d});
    }
  }
  return out;
}

}  // namespace probecomp::inspection
