#include "probecomp/results/files.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "probecomp/io/dmis.hpp"
#include "probecomp/io/format.hpp"
#include "probecomp/io/qif.hpp"
#include "qif_characteristics.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::results {

using io::append_fixed;
using io::DmisTips;
using io::FileProgress;
using io::PointTable;

void write_compensated_csv(std::ostream& stream, const PointTable& t, const compensation::CompensationResult& r,
                           const FileProgress& progress) {
  // The tip radius of each row when the input gave any (the default filled in where a row's was empty), or when a
  // qualification gave each its effective radius.
  const bool radius_column = t.radii.has_value() || r.qualified_radii();
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
  out << io::dmis_units(t.unit);
  // The tips, when the input gave each point its own: as the input's sensors, with the radius each point was
  // compensated with; after a qualification, with their nominal radii (an effective radius is a point's, not a
  // sensor's: the CSV output has it).
  std::vector<double> radii;
  if (t.radii) {
    for (std::size_t k = 0; k < r.points.size(); ++k) {
      const double nominal = (*t.radii)[k];
      radii.push_back(scale * (r.qualified_radii() && std::isfinite(nominal) ? nominal : r.points[k].radius));
    }
  }
  DmisTips tips(t, radii);
  out << tips.definitions();
  for (std::size_t k = 0; k < r.points.size(); ++k) {
    const compensation::CompensatedPoint& p = r.points[k];
    const std::string label = io::dmis_label(t, k);
    if (p.computed()) {
      if (t.radii) out << tips.select(k);
      out << io::dmis_point(label, p.contact, p.normal, t.unit);
      out << "$$ deviation=" << io::mm(scale * p.deviation) << " u=" << io::mm(scale * p.uncertainty) << " face=" << p.face
          << " status=" << compensation::to_string(p.status) << '\n';
    } else {
      out << "$$ FA(" << label << ") not compensated: status=" << compensation::to_string(p.status) << '\n';
    }
  }
  return out.str();
}

std::string compensated_qif(const PointTable& t, const compensation::CompensationResult& r, const std::string& source,
                            const inspection::Inspection* inspection) {
  std::vector<io::QifContactPoint> points;
  points.reserve(r.points.size());
  for (const compensation::CompensatedPoint& p : r.points) {
    points.push_back({.computed = p.computed(), .contact = p.contact, .normal = p.normal, .deviation = p.deviation,
                      .uncertainty = p.uncertainty, .radius = p.radius, .face = p.face,
                      .status = compensation::to_string(p.status)});
  }
  std::string xml = io::contact_points_qif(t, points, compensation::to_string(r.method), source);
  if (inspection != nullptr) add_characteristics(xml, *inspection, 1.0 / t.unit.mm);
  return xml;
}

}  // namespace probecomp::results
