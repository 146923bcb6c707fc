#include "probecomp/results/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <vector>

#include "probecomp/io/json.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::results {

using io::Json;
using io::json_fixed;
using io::json_number;
using io::json_text;
using io::parse_number;
using io::trim;

DeviationSummary summarise(const std::vector<double>& d, const std::optional<Tolerance>& tolerance) {
  DeviationSummary s;
  s.points = static_cast<int>(d.size());
  if (d.empty()) return s;
  double sum = 0.0;
  s.min = std::numeric_limits<double>::infinity();
  s.max = -s.min;
  for (double x : d) {
    sum += x;
    s.min = std::min(s.min, x);
    s.max = std::max(s.max, x);
    if (tolerance && !tolerance->passes(x)) ++s.out_of_tolerance;
  }
  s.mean = sum / static_cast<double>(d.size());
  double sq = 0.0;
  for (double x : d) sq += (x - s.mean) * (x - s.mean);
  s.std = std::sqrt(sq / static_cast<double>(d.size()));
  return s;
}

std::vector<double> distinct_radii(std::vector<double> radii) {
  std::sort(radii.begin(), radii.end());
  radii.erase(std::unique(radii.begin(), radii.end()), radii.end());
  return radii;
}

Tolerance parse_tolerance(const std::string& text) {
  const auto comma = text.find(',');
  std::optional<double> lower, upper;
  if (comma != std::string::npos) {
    lower = parse_number(trim(text.substr(0, comma)));
    upper = parse_number(trim(text.substr(comma + 1)));
  }
  if (!lower || !upper || !std::isfinite(*lower) || !std::isfinite(*upper)) {
    throw std::invalid_argument("must be LOWER,UPPER in mm (e.g. -0.05,0.05), not '" + text + "'");
  }
  if (!(*lower < *upper)) {
    throw std::invalid_argument("the lower limit must be below the upper, not '" + text + "'");
  }
  return {*lower, *upper};
}

DeviationSummaries summarise_deviations(const compensation::CompensationResult& r, const std::optional<Tolerance>& tolerance) {
  std::map<int, std::vector<double>> by_face;
  std::vector<double> all;
  for (const compensation::CompensatedPoint& p : r.points) {
    if (p.status != compensation::PointStatus::Ok) continue;
    by_face[p.face].push_back(p.deviation);
    all.push_back(p.deviation);
  }
  DeviationSummaries out;
  for (const compensation::FaceReport& f : r.faces) {
    const auto found = by_face.find(f.face);
    out.faces.push_back(summarise(found == by_face.end() ? std::vector<double>{} : found->second, tolerance));
  }
  out.all = summarise(all, tolerance);
  return out;
}

std::string statistics_json(const compensation::CompensationResult& r, const RunInputs& inputs,
                            const FileTimings& files, const std::optional<Tolerance>& tolerance,
                            const inspection::Inspection* inspection) {
  const DeviationSummaries dev = summarise_deviations(r, tolerance);
  const auto number = [](double v) { return json_number(v, 9); };
  const auto vec = [&](const Vector3& v) { return Json::array({number(v.x()), number(v.y()), number(v.z())}); };
  const auto counts = [](const auto& by_status) {
    Json c = Json::object();
    for (std::size_t k = 0; k < std::size(compensation::kPointStatuses); ++k) {
      c[compensation::to_string(compensation::kPointStatuses[k])] = by_status[k];
    }
    return c;
  };
  const auto deviation = [&](const DeviationSummary& d) {
    Json j = {{"points", d.points}, {"mean", number(d.mean)}, {"std", number(d.std)}, {"min", number(d.min)},
              {"max", number(d.max)}};
    if (tolerance) j["out_of_tolerance"] = d.out_of_tolerance;
    return j;
  };

  Json j;
  j["method"] = compensation::to_string(r.method);
  j["units"] = "mm";
  Json radii = Json::array();
  for (double t : inputs.tip_radii) radii.push_back(number(t));
  j["inputs"] = {{"cad", inputs.cad},
                 {"points", inputs.points},
                 {"points_unit", inputs.points_unit.name},
                 {"probe_radius", inputs.probe_radius ? number(*inputs.probe_radius) : Json(nullptr)},
                 {"tip_radii", radii}};
  if (r.qualified_radii()) {
    // Each stylus's radii by direction (compensate --qualification), and how many points it could not model.
    Json styli = Json::array();
    for (const compensation::StylusRadii& s : r.styli) {
      Json one = {{"stylus", s.stylus}, {"qualified", s.qualified}, {"points", s.points}};
      if (s.qualified) {
        one["effective_radius"] = number(s.effective_radius);
        one["variation"] = number(s.variation);
        one["degree"] = s.degree;
        one["unsupported_points"] = s.unsupported;
      }
      styli.push_back(one);
    }
    j["qualification"] = {{"styli", styli}};
  }
  const Eigen::Matrix4d M = r.registration.transform.matrix();
  Json transform = Json::array();
  for (int a = 0; a < 4; ++a) {
    transform.push_back(Json::array());
    for (int b = 0; b < 4; ++b) transform.back().push_back(json_number(M(a, b), 15));
  }
  j["transform"] = transform;

  const registration::RegistrationResult& reg = r.registration;
  // Machine frame, as the transform maps to: the motions the data do not fix, held at the start.
  Json free = Json::array();
  for (const registration::FreeMotion& f : reg.constraints.free) {
    const bool rotation = f.kind == registration::FreeMotion::Kind::Rotation;
    Json m = {{"kind", rotation ? "rotation" : "translation"},
              {rotation ? "axis" : "direction", vec(reg.transform.linear() * f.direction)}};
    if (rotation) m["through"] = vec(reg.transform * f.through);
    free.push_back(m);
  }
  j["registration"] = {{"converged", reg.converged()},
                       {"status", registration::to_string(reg.status)},
                       {"stop_reason", reg.stop_reason},
                       {"rms", number(reg.rms)},
                       {"iterations", reg.iterations + reg.coarse_iterations},
                       {"searches", reg.searches},
                       {"scale", number(reg.scale)},
                       {"inliers", reg.inliers},
                       {"starts", reg.starts},
                       {"left_out", reg.left_out},
                       {"located_by", reg.located_by.empty() ? "all-points" : "datum-features"},
                       {"locating_points", reg.locating_points()},
                       {"free_motions", free}};

  Json faces = Json::array();
  for (std::size_t f = 0; f < r.faces.size(); ++f) {
    const compensation::FaceReport& x = r.faces[f];
    Json face = {{"face", x.face},
                 {"points", x.points},
                 {"fitted", x.fitted},
                 {"material_side", cad::to_string(x.material)},
                 {"mean_u", number(x.mean_uncertainty)}};
    if (x.fitted) {
      face["control_points"] = x.control_points;
      face["fits"] = x.fits;
      face["refinement_rounds"] = x.rounds;
      face["rms_residual"] = number(x.rms);
      face["max_residual"] = number(x.max_residual);
      face["noise_estimate"] = number(x.noise_sigma);
      face["effective_dof"] = json_number(x.effective_dof, 6);
      face["log10_smoothing"] = json_number(x.log10_smoothing, 4);
      face["outliers"] = x.count(compensation::PointStatus::Outlier);
      face["repeated_points"] = x.repeated;
      face["noise_reached"] = x.fit_status == fitting::AdaptiveFitResult::Status::OK;
    } else if (x.fitted_as) {
      face["fitted_as"] = cad::to_string(*x.fitted_as);
      face["rms_residual"] = number(x.rms);
      face["noise_estimate"] = number(x.noise_sigma);
      face["outliers"] = x.count(compensation::PointStatus::Outlier);
    }
    face["counts"] = counts(x.counts);
    face["deviation"] = deviation(dev.faces[f]);
    face["stop_reason"] = x.stop_reason;
    faces.push_back(face);
  }
  j["faces"] = faces;

  const compensation::Statistics& st = r.statistics;
  j["counts"] = counts(st.counts);
  j["counts"]["total"] = st.total;
  Json all = {{"points", st.count(compensation::PointStatus::Ok)},
              {"mean", number(st.deviation_mean)},
              {"std", number(st.deviation_std)},
              {"min", number(st.deviation_min)},
              {"max", number(st.deviation_max)}};
  if (tolerance) {
    all["tolerance"] = {number(tolerance->lower), number(tolerance->upper)};
    all["out_of_tolerance"] = dev.all.out_of_tolerance;
  }
  j["deviation"] = all;
  if (inspection != nullptr && !inspection->datums.empty()) {
    Json list = Json::array();
    for (const inspection::FrameDatum& f : inspection->datums) {
      const inspection::DatumResult& d = f.datum;
      Json x = {{"name", d.name},     {"frame", f.frame}, {"faces", d.faces}, {"fit", inspection::to_string(d.fit)},
                {"points", d.points}, {"fixes", d.fixes}, {"rms", number(d.rms)}};
      if (d.size_change) x["size_change"] = number(*d.size_change);
      list.push_back(x);
    }
    j["datums"] = list;
  }
  if (inspection != nullptr && inspection->alignment_frame && inspection->alignment_frame->ok()) {
    j["alignment"] = {{"frame", inspection->alignment}, {"fixed", inspection->alignment_frame->fixed()}};
  }
  if (inspection != nullptr && !inspection->characteristics.empty()) {
    Json list = Json::array();
    for (const inspection::CharacteristicResult& c : inspection->characteristics) {
      Json x = {{"name", c.spec.name},
                {"type", c.spec.type},
                {"faces", c.spec.faces},
                {"datums", c.spec.datums},
                {"tolerance", number(c.spec.tolerance)},
                {"outside", number(c.outside)},
                {"points", c.points},
                {"decision", inspection::to_string(c.decision)}};
      if (c.decision == inspection::Decision::NotEvaluated) {
        x["reason"] = c.reason;
      } else {
        x["min"] = number(c.min);
        x["max"] = number(c.max);
        x["value"] = number(c.value);
        x["u"] = number(c.u);
        x["k"] = json_fixed(c.coverage, 3);
        if (c.decision == inspection::Decision::Indeterminate) x["reason"] = c.reason;
      }
      list.push_back(x);
    }
    j["characteristics"] = list;
  }
  j["warnings"] = r.warnings;
  const compensation::Timings& t = r.seconds;
  const auto seconds = [](double v) { return json_fixed(v, 4); };
  j["timings"] = {{"read", seconds(files.read)},
                  {"prepare", seconds(t.prepare)},
                  {"register", seconds(t.registration)},
                  {"fit", seconds(t.fitting)},
                  {"compensate", seconds(t.compensation)},
                  {"write", seconds(files.write)},
                  {"total", seconds(files.total)}};
  return json_text(j);
}

}  // namespace probecomp::results
