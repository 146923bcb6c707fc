#include "probecomp/results/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "probecomp/io/format.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::results {

using io::json_number;
using io::json_string;
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
                            const FileTimings& files, const std::optional<Tolerance>& tolerance) {
  const DeviationSummaries dev = summarise_deviations(r, tolerance);
  std::ostringstream j;
  const Eigen::Matrix4d M = r.registration.transform.matrix();
  j << "{\"method\": \"" << compensation::to_string(r.method) << "\", \"units\": \"mm\",\n \"inputs\": {\"cad\": "
    << json_string(inputs.cad) << ", \"points\": " << json_string(inputs.points) << ", \"points_unit\": \""
    << inputs.points_unit.name << "\", \"probe_radius\": "
    << (inputs.probe_radius ? json_number("%.9g", *inputs.probe_radius) : std::string("null")) << ", \"tip_radii\": [";
  for (std::size_t k = 0; k < inputs.tip_radii.size(); ++k) j << (k ? ", " : "") << json_number("%.9g", inputs.tip_radii[k]);
  j << "]},\n \"transform\": [";
  for (int a = 0; a < 4; ++a) {
    j << (a ? ",\n               [" : "[");
    for (int b = 0; b < 4; ++b) j << (b ? ", " : "") << json_number("%.15g", M(a, b));
    j << "]";
  }
  j << "],\n \"registration\": {\"converged\": " << (r.registration.converged() ? "true" : "false") << ", \"status\": \""
    << registration::to_string(r.registration.status) << "\", \"stop_reason\": " << json_string(r.registration.stop_reason)
    << ", \"rms\": " << json_number("%.9g", r.registration.rms)
    << ", \"iterations\": " << r.registration.iterations + r.registration.coarse_iterations
    << ", \"searches\": " << r.registration.searches
    << ", \"scale\": " << json_number("%.9g", r.registration.scale) << ", \"inliers\": " << r.registration.inliers
    << ", \"starts\": " << r.registration.starts << ", \"left_out\": " << r.registration.left_out
    << ", \"free_motions\": [";
  // Machine frame, as the transform maps to: the motions the data do not fix, held at the start.
  // Appended piecewise: GCC 12 flags `"[" + std::string` with a false -Wrestrict.
  const auto vec = [](const Vector3& v) {
    std::string s = "[";
    s += json_number("%.9g", v.x()) + ", " + json_number("%.9g", v.y()) + ", " + json_number("%.9g", v.z()) + "]";
    return s;
  };
  for (std::size_t k = 0; k < r.registration.constraints.free.size(); ++k) {
    const registration::FreeMotion& f = r.registration.constraints.free[k];
    const bool rotation = f.kind == registration::FreeMotion::Kind::Rotation;
    j << (k ? ", " : "") << "{\"kind\": \"" << (rotation ? "rotation" : "translation") << "\", \""
      << (rotation ? "axis" : "direction") << "\": " << vec(r.registration.transform.linear() * f.direction);
    if (rotation) j << ", \"through\": " << vec(r.registration.transform * f.through);
    j << "}";
  }
  j << "]},\n \"faces\": [";
  for (std::size_t f = 0; f < r.faces.size(); ++f) {
    const compensation::FaceReport& x = r.faces[f];
    j << (f ? ",\n   " : "\n   ") << "{\"face\": " << x.face << ", \"points\": " << x.points
      << ", \"fitted\": " << (x.fitted ? "true" : "false") << ", \"material_side\": \"" << cad::to_string(x.material)
      << "\", \"mean_u\": " << json_number("%.9g", x.mean_uncertainty);
    if (x.fitted) {
      j << ", \"control_points\": " << x.control_points << ", \"fits\": " << x.fits
        << ", \"refinement_rounds\": " << x.rounds << ", \"rms_residual\": " << json_number("%.9g", x.rms)
        << ", \"max_residual\": " << json_number("%.9g", x.max_residual) << ", \"noise_estimate\": " << json_number("%.9g", x.noise_sigma)
        << ", \"effective_dof\": " << json_number("%.6g", x.effective_dof)
        << ", \"log10_smoothing\": " << json_number("%.4g", x.log10_smoothing)
        << ", \"outliers\": " << x.count(compensation::PointStatus::Outlier) << ", \"repeated_points\": " << x.repeated
        << ", \"noise_reached\": " << (x.fit_status == fitting::AdaptiveFitResult::Status::OK ? "true" : "false");
    }
    j << ", \"counts\": {";
    for (std::size_t k = 0; k < std::size(compensation::kPointStatuses); ++k) {
      j << (k ? ", " : "") << "\"" << compensation::to_string(compensation::kPointStatuses[k]) << "\": " << x.counts[k];
    }
    const DeviationSummary& d = dev.faces[f];
    j << "}, \"deviation\": {\"points\": " << d.points << ", \"mean\": " << json_number("%.9g", d.mean) << ", \"std\": "
      << json_number("%.9g", d.std) << ", \"min\": " << json_number("%.9g", d.min) << ", \"max\": " << json_number("%.9g", d.max);
    if (tolerance) j << ", \"out_of_tolerance\": " << d.out_of_tolerance;
    j << "}, \"stop_reason\": " << json_string(x.stop_reason) << "}";
  }
  j << "],\n \"counts\": {";
  const compensation::Statistics& st = r.statistics;
  for (std::size_t s = 0; s < std::size(compensation::kPointStatuses); ++s) {
    j << (s ? ", " : "") << "\"" << compensation::to_string(compensation::kPointStatuses[s]) << "\": " << st.counts[s];
  }
  j << ", \"total\": " << st.total << "},\n \"deviation\": {\"points\": " << st.count(compensation::PointStatus::Ok)
    << ", \"mean\": " << json_number("%.9g", st.deviation_mean) << ", \"std\": " << json_number("%.9g", st.deviation_std)
    << ", \"min\": " << json_number("%.9g", st.deviation_min) << ", \"max\": " << json_number("%.9g", st.deviation_max);
  if (tolerance) {
    j << ", \"tolerance\": [" << json_number("%.9g", tolerance->lower) << ", " << json_number("%.9g", tolerance->upper)
      << "], \"out_of_tolerance\": " << dev.all.out_of_tolerance;
  }
  j << "}";
  j << ",\n \"warnings\": [";
  for (std::size_t w = 0; w < r.warnings.size(); ++w) j << (w ? ", " : "") << json_string(r.warnings[w]);
  j << "]";
  const compensation::Timings& t = r.seconds;
  j << ",\n \"timings\": {\"read\": " << json_number("%.4f", files.read) << ", \"prepare\": " << json_number("%.4f", t.prepare)
    << ", \"register\": " << json_number("%.4f", t.registration) << ", \"fit\": " << json_number("%.4f", t.fitting)
    << ", \"compensate\": " << json_number("%.4f", t.compensation) << ", \"write\": " << json_number("%.4f", files.write)
    << ", \"total\": " << json_number("%.4f", files.total) << "}}\n";
  return j.str();
}

}  // namespace probecomp::results
