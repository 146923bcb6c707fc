#include "probecomp/io/results.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "probecomp/io/dmis.hpp"
#include "probecomp/io/format.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::io {

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
    throw std::invalid_argument("--tolerance must be LOWER,UPPER in mm (e.g. -0.05,0.05), not '" + text + "'");
  }
  if (!(*lower < *upper)) {
    throw std::invalid_argument("--tolerance: the lower limit must be below the upper, not '" + text + "'");
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

void write_compensated_csv(std::ostream& stream, const PointTable& t, const compensation::CompensationResult& r,
                           const FileProgress& progress) {
  // The tip radius of each row when the input gave any (the default filled in where a row's was empty).
  const bool radius_column = t.radii.has_value();
  std::vector<std::string> ours{"x", "y", "z", "nx", "ny", "nz", "deviation", "u", "face", "status"};
  if (radius_column) ours.push_back("r");
  // Rows go out in blocks, each built in its own reused string with std::to_chars: a million rows are 115 MB of
  // text that never has to be held whole (bench/io_bench.cpp). The blocks of a window are formatted in parallel and
  // written in order: the same bytes whatever the thread count.
  constexpr std::size_t kBlockRows = 8192;
  // Blocks of about 1.3 MB, a window formatted at a time: 4 keep 2 cores busy, and the text held is 5 MB on top of
  // the command's peak, which the write is (16 blocks: 21 MB; 1 M points' peak 338 → 320 MiB).
  constexpr std::size_t kWindowBlocks = 4;
  std::string header;
  for (std::size_t c = 0; c < ours.size(); ++c) header.append(c ? "," : "").append(ours[c]);
  header.append(t.carried_header(ours)).push_back('\n');
  stream.write(header.data(), static_cast<std::streamsize>(header.size()));
  const std::vector<int> carried = t.carried_columns();
  const double scale = 1.0 / t.unit.mm;  // mm → the input's unit
  auto append_row = [&](std::string& out, std::size_t k) {
    const compensation::CompensatedPoint& p = r.points[k];
    if (p.computed()) {
      const Point3 x = scale * p.contact;
      for (double v : {x.x(), x.y(), x.z()}) append_fixed(out, v, 9).push_back(',');
      for (double v : {p.normal.x(), p.normal.y(), p.normal.z()}) append_fixed(out, v, 12).push_back(',');
      append_fixed(out, scale * p.deviation, 9).push_back(',');
      append_fixed(out, scale * p.uncertainty, 9).push_back(',');
      out.append(std::to_string(p.face)).push_back(',');
    } else {
      // Never dropped: the row is there, empty, with the reason.
      out.append(",,,,,,,,").append(p.face >= 0 ? std::to_string(p.face) : "").push_back(',');
    }
    out.append(compensation::to_string(p.status));
    if (radius_column) append_fixed(out.append(","), scale * p.radius, 9);
    if (!carried.empty()) t.append_carried_fields(out, k, carried);
    out.push_back('\n');
  };
  const std::size_t rows = r.points.size();
  const std::size_t blocks = (rows + kBlockRows - 1) / kBlockRows;
  std::vector<std::string> text(std::min(blocks, kWindowBlocks));
  for (std::size_t first = 0; first < blocks; first += kWindowBlocks) {
    const std::size_t last = std::min(blocks, first + kWindowBlocks);
    tbb::parallel_for(first, last, [&](std::size_t b) {
      std::string& out = text[b - first];
      out.clear();
      out.reserve(160 * kBlockRows);
      for (std::size_t k = b * kBlockRows; k < std::min(rows, (b + 1) * kBlockRows); ++k) append_row(out, k);
    });
    for (std::size_t b = first; b < last; ++b) {
      stream.write(text[b - first].data(), static_cast<std::streamsize>(text[b - first].size()));
    }
    if (progress) progress(static_cast<double>(std::min(rows, last * kBlockRows)) / static_cast<double>(rows));
  }
}

std::string compensated_csv(const PointTable& t, const compensation::CompensationResult& r) {
  std::ostringstream out;
  write_compensated_csv(out, t, r);
  return out.str();
}

std::string compensated_dmis(const PointTable& t, const compensation::CompensationResult& r, const std::string& source) {
  std::ostringstream out;
  const std::string u = t.unit.name;
  const double scale = 1.0 / t.unit.mm;  // mm → the input's unit
  out << "$$ probecomp " << compensation::to_string(r.method) << " compensation of " << source
      << ": contact points and the normals used, machine frame, " << u << "\n";
  out << "$$ after each point: its deviation from the registered nominal (" << u
      << ", + outside), its standard uncertainty u\n"
      << "$$ along the normal (k = 1, " << u << "), face and status\n";
  out << dmis_units(t.unit);
  // The tips, when the input gave each point its own: as the input's sensors, with the radius each point was
  // compensated with.
  std::vector<double> radii;
  if (t.radii) {
    for (const compensation::CompensatedPoint& p : r.points) radii.push_back(scale * p.radius);
  }
  DmisTips tips(t, radii);
  out << tips.definitions();
  for (std::size_t k = 0; k < r.points.size(); ++k) {
    const compensation::CompensatedPoint& p = r.points[k];
    const std::string label = dmis_label(t, k);
    if (p.computed()) {
      if (t.radii) out << tips.select(k);
      out << dmis_point(label, p.contact, p.normal, t.unit);
      out << "$$ deviation=" << mm(scale * p.deviation) << " u=" << mm(scale * p.uncertainty) << " face=" << p.face << " status=" << compensation::to_string(p.status) << '\n';
    } else {
      out << "$$ FA(" << label << ") not compensated: status=" << compensation::to_string(p.status) << '\n';
    }
  }
  return out.str();
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

}  // namespace probecomp::io
