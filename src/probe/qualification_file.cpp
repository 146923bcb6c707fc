#include "probecomp/probe/qualification_file.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "probecomp/error.hpp"

namespace probecomp::probe {

namespace {

constexpr const char* kFormat = "probecomp qualification 1";
// A coefficient or covariance to 12 significant digits: 1e-12 mm on a radius of 1 mm, far below what a
// qualification resolves; positions (the sphere's centre, hundreds of mm from the origin) to 12 as well.
constexpr int kDigits = 12;

io::Json vector_json(const Vector3& v, int digits = kDigits) {
  return io::Json::array({io::json_number(v.x(), digits), io::json_number(v.y(), digits), io::json_number(v.z(), digits)});
}

io::Json stylus_json(const StylusQualification& s) {
  io::Json j;
  j["stylus"] = s.stylus;
  j["status"] = to_string(s.status);
  j["touches"] = s.touches;
  if (s.status != QualificationStatus::OK) {
    j["reason"] = s.reason;
    return j;
  }
  j["effective_radius"] = io::json_number(s.effective_radius, kDigits);
  j["effective_radius_u"] = io::json_number(s.effective_radius_u, 6);
  j["sphere_centre"] = vector_json(s.sphere_centre);
  j["form_error"] = io::json_number(s.form_error, 6);
  j["sphere_rms"] = io::json_number(s.sphere_rms, 6);
  j["residual"] = io::json_number(s.residual, 6);
  j["loo_residual"] = io::json_number(s.loo_residual, 6);
  io::Json m;
  m["basis"] = "real spherical harmonics of the travel direction (machine frame, theta from +z, phi from +x), "
               "fully normalised (mean square 1); degree 1 is in sphere_centre";
  m["degree"] = s.model.degree();
  m["variation"] = io::json_number(s.model.variation(), 6);
  m["log10_smoothing"] = io::json_number(s.model.log10_smoothing, 6);
  io::Json terms = io::Json::array();
  for (std::size_t k = 0; k < s.model.terms.size(); ++k) {
    terms.push_back({{"l", s.model.terms[k].l}, {"m", s.model.terms[k].m},
                     {"coefficient", io::json_number(s.model.coefficients[k], kDigits)}});
  }
  m["terms"] = terms;
  io::Json covariance = io::Json::array();
  for (const std::vector<double>& row : s.model.covariance) {
    io::Json r = io::Json::array();
    for (double v : row) r.push_back(io::json_number(v, kDigits));
    covariance.push_back(r);
  }
  m["covariance"] = covariance;
  j["model"] = m;
  j["support_angle_deg"] = io::json_number(s.support_angle_deg, 6);
  io::Json directions = io::Json::array();
  for (const Vector3& d : s.directions) directions.push_back(vector_json(d, 9));
  j["directions"] = directions;
  return j;
}

// Reading: every field checked, the error naming the file, the stylus and the field.
struct Reader {
  const std::string& path;

  [[noreturn]] void fail(const std::string& what) const { throw InputError(path + ": " + what); }

  const io::Json& field(const io::Json& j, const char* name, const std::string& where) const {
    if (!j.is_object() || !j.contains(name)) fail(where + "has no \"" + name + "\"");
    return j.at(name);
  }
  double number(const io::Json& j, const char* name, const std::string& where) const {
    const io::Json& v = field(j, name, where);
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail(where + "\"" + name + "\" is not a number");
    return v.get<double>();
  }
  Vector3 vector(const io::Json& v, const std::string& what) const {
    if (!v.is_array() || v.size() != 3) fail(what + " is not three numbers");
    Vector3 out;
    for (int i = 0; i < 3; ++i) {
      if (!v[static_cast<std::size_t>(i)].is_number()) fail(what + " is not three numbers");
      out(i) = v[static_cast<std::size_t>(i)].get<double>();
    }
    if (!out.allFinite()) fail(what + " is not finite");
    return out;
  }

  StylusQualification stylus(const io::Json& j, double diameter) const {
    StylusQualification s;
    const io::Json& name = field(j, "stylus", "a stylus ");
    if (!name.is_string() || name.get<std::string>().empty()) fail("a stylus's \"stylus\" is not a name");
    s.stylus = name.get<std::string>();
    const std::string where = "stylus " + s.stylus + ": ";
    s.sphere_diameter = diameter;
    const io::Json& status = field(j, "status", where);
    if (!status.is_string()) fail(where + "\"status\" is not a word");
    s.touches = static_cast<int>(number(j, "touches", where));
    if (status.get<std::string>() != "ok") {
      s.status = status.get<std::string>() == to_string(QualificationStatus::TooFewTouches)
                     ? QualificationStatus::TooFewTouches
                     : QualificationStatus::NumericalError;
      s.reason = j.contains("reason") && j.at("reason").is_string() ? j.at("reason").get<std::string>()
                                                                    : status.get<std::string>();
      return s;
    }
    s.status = QualificationStatus::OK;
    s.effective_radius = number(j, "effective_radius", where);
    if (!(s.effective_radius > 0.0)) fail(where + "the effective radius must be positive");
    s.effective_radius_u = number(j, "effective_radius_u", where);
    s.sphere_centre = vector(field(j, "sphere_centre", where), where + "\"sphere_centre\"");
    s.form_error = number(j, "form_error", where);
    s.sphere_rms = number(j, "sphere_rms", where);
    s.residual = number(j, "residual", where);
    s.loo_residual = number(j, "loo_residual", where);
    s.support_angle_deg = number(j, "support_angle_deg", where);
    const io::Json& m = field(j, "model", where);
    const io::Json& terms = field(m, "terms", where + "the model ");
    if (!terms.is_array() || terms.empty()) fail(where + "the model has no terms");
    for (const io::Json& t : terms) {
      const int l = static_cast<int>(number(t, "l", where + "a term ")), mm = static_cast<int>(number(t, "m", where + "a term "));
      if (l < 0 || l == 1 || std::abs(mm) > l) fail(where + "a term of degree " + std::to_string(l) + " and order " + std::to_string(mm) + " is not one of the model's");
      s.model.terms.push_back({l, mm});
      s.model.coefficients.push_back(number(t, "coefficient", where + "a term "));
    }
    s.model.log10_smoothing = number(m, "log10_smoothing", where + "the model ");
    const io::Json& covariance = field(m, "covariance", where + "the model ");
    if (!covariance.is_array() || covariance.size() != terms.size()) fail(where + "the model's covariance is not " + std::to_string(terms.size()) + " rows");
    for (const io::Json& row : covariance) {
      if (!row.is_array() || row.size() != terms.size()) fail(where + "the model's covariance is not square");
      std::vector<double> r;
      for (const io::Json& v : row) {
        if (!v.is_number()) fail(where + "the model's covariance holds a value that is not a number");
        r.push_back(v.get<double>());
      }
      s.model.covariance.push_back(std::move(r));
    }
    const io::Json& directions = field(j, "directions", where);
    if (!directions.is_array() || directions.empty()) fail(where + "no touch directions");
    for (const io::Json& d : directions) {
      const Vector3 v = vector(d, where + "a direction");
      if (!(v.norm() > 0.5)) fail(where + "a direction is not a unit vector");
      s.directions.push_back(v.normalized());
    }
    return s;
  }
};

}  // namespace

io::Json to_json(const Qualification& q) {
  io::Json j;
  j["format"] = kFormat;
  j["units"] = "mm";
  j["sphere_diameter"] = q.styli.empty() ? io::Json(nullptr) : io::json_number(q.styli.front().sphere_diameter, kDigits);
  io::Json styli = io::Json::array();
  for (const StylusQualification& s : q.styli) styli.push_back(stylus_json(s));
  j["styli"] = styli;
  return j;
}

Qualification qualification_from_json(const std::string& text, const std::string& path) {
  const Reader r{path};
  io::Json j;
  try {
    j = io::Json::parse(text);
  } catch (const io::Json::parse_error& e) {
    r.fail(std::string("not JSON (") + e.what() + ")");
  }
  if (!j.is_object() || !j.contains("format") || j.at("format") != kFormat) {
    r.fail(std::string("not a qualification (no \"format\": \"") + kFormat + "\"; write one with probecomp qualify)");
  }
  const io::Json& units = r.field(j, "units", "");
  if (units != "mm") r.fail("\"units\" must be \"mm\"");
  const double diameter = r.number(j, "sphere_diameter", "");
  const io::Json& styli = r.field(j, "styli", "");
  if (!styli.is_array() || styli.empty()) r.fail("no styli");
  Qualification q;
  for (const io::Json& s : styli) {
    q.styli.push_back(r.stylus(s, diameter));
    for (std::size_t k = 0; k + 1 < q.styli.size(); ++k) {
      if (q.styli[k].stylus == q.styli.back().stylus) r.fail("stylus " + q.styli.back().stylus + " is qualified twice");
    }
  }
  return q;
}

Qualification read_qualification(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot be read");
  std::ostringstream text;
  text << in.rdbuf();
  return qualification_from_json(text.str(), path);
}

}  // namespace probecomp::probe
