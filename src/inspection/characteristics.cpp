#include "probecomp/inspection/characteristics.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "probecomp/cad/locator.hpp"
#include "probecomp/error.hpp"
#include "probecomp/registration/icp.hpp"

namespace probecomp::inspection {

namespace {

// Form only: at least this many points past the 6 motions a rigid fit may take.
constexpr int kMinPointsForForm = 7;

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
  std::set<std::string> datums;
  if (j.contains("datums")) {
    if (!j["datums"].is_object()) bad(path, "\"datums\" must be an object of named datums");
    for (const auto& [name, d] : j["datums"].items()) datums.insert(name);
  }
  Specification spec;
  int k = 0;
  for (const nlohmann::json& c : j["characteristics"]) {
    ++k;
    CharacteristicSpec s;
    const std::string where = "characteristic " + std::to_string(k);
    try {
      s.name = c.value("name", "C" + std::to_string(k));
      s.type = c.value("type", std::string("surface-profile"));
      if (s.type != "surface-profile") bad(path, where + ": unknown type \"" + s.type + "\" (expected surface-profile)");
      if (!c.contains("faces") || !c["faces"].is_array() || c["faces"].empty()) bad(path, where + ": no \"faces\"");
      for (const nlohmann::json& f : c["faces"]) {
        const int face = f.get<int>();
        if (face < 0 || face >= model.face_count()) {
          bad(path, where + ": face " + std::to_string(face) + " is not in the model (" + std::to_string(model.face_count()) + " faces)");
        }
        s.faces.push_back(face);
      }
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

Specification from_pmi(const cad::Pmi& pmi, int& skipped) {
  Specification spec;
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
    if (t.type == cad::ToleranceType::ProfileOfSurface) s.datums = t.datums;
    spec.characteristics.push_back(std::move(s));
  }
  return spec;
}

std::vector<CharacteristicResult> evaluate(const Specification& spec, const cad::Model& nominal,
                                           const compensation::CompensationResult& result) {
  std::vector<CharacteristicResult> out;
  for (const CharacteristicSpec& s : spec.characteristics) {
    CharacteristicResult c;
    c.spec = s;
    c.outside = s.outside.value_or(0.5 * s.tolerance);
    if (!(s.tolerance > 0.0)) {
      c.reason = "no tolerance magnitude (the file's could not be read)";
      out.push_back(std::move(c));
      continue;
    }
    if (!s.datums.empty()) {
      c.reason = "datum reference frames are not evaluated yet";
      out.push_back(std::move(c));
      continue;
    }
    // The trusted points on the characteristic's faces, and those faces alone as a model to fit them to.
    const std::set<int> faces(s.faces.begin(), s.faces.end());
    std::vector<Point3> points;
    std::vector<double> u;
    for (const compensation::CompensatedPoint& p : result.points) {
      if (p.status == compensation::PointStatus::Ok && faces.contains(p.face)) {
        points.push_back(p.contact);
        u.push_back(p.uncertainty);
      }
    }
    c.points = static_cast<int>(points.size());
    if (c.points < kMinPointsForForm) {
      c.reason = std::to_string(c.points) + " trusted points on its faces (" + std::to_string(kMinPointsForForm) +
                 " needed for its form)";
      out.push_back(std::move(c));
      continue;
    }
    cad::Model own;
    own.file_units = nominal.file_units;
    for (int f : s.faces) own.faces.push_back(nominal.faces[static_cast<std::size_t>(f)]);
    const cad::ModelLocator locator(own);
    // Least squares (not the registration's robust weights: every trusted point counts), from where the whole
    // part was registered.
    registration::RegistrationOptions options;
    options.initial = result.registration.transform;
    options.robust.loss = registration::RobustLoss::None;
    const registration::RegistrationResult fit = registration::register_points(locator, points, options);
    if (!fit.converged()) {
      c.reason = "the best fit of its points to its faces did not converge: " + fit.stop_reason;
      out.push_back(std::move(c));
      continue;
    }
    const double centre = c.outside - 0.5 * s.tolerance;
    c.min = std::numeric_limits<double>::infinity();
    c.max = -std::numeric_limits<double>::infinity();
    bool inside = true, outside_surely = false;
    // A point whose foot fell on its faces' edge after the fit is past them (its distance is not along a normal):
    // left out, and not counted.
    c.points = 0;
    for (std::size_t k = 0; k < points.size(); ++k) {
      const registration::PointMatch& m = fit.matches[k];
      if (!m.ok() || m.on_edge) continue;
      ++c.points;
      const double d = m.distance, U = 2.0 * u[k];
      c.min = std::min(c.min, d);
      c.max = std::max(c.max, d);
      const double width = 2.0 * std::abs(d - centre);
      if (width > c.value) {
        c.value = width;
        c.u = 2.0 * u[k];
      }
      inside = inside && d - U >= c.outside - s.tolerance && d + U <= c.outside;
      outside_surely = outside_surely || d - U > c.outside || d + U < c.outside - s.tolerance;
    }
    if (c.points < kMinPointsForForm) {
      c.reason = "after the best fit only " + std::to_string(c.points) + " of its points lie inside its faces";
      c.decision = Decision::NotEvaluated;
      out.push_back(std::move(c));
      continue;
    }
    c.decision = outside_surely ? Decision::DoesNotConform : inside ? Decision::Conforms : Decision::Indeterminate;
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace probecomp::inspection
