// probecomp qualify: each stylus qualified on a reference sphere (DESIGN.md §8; probe/qualification.hpp), written
// as QUAL.json for compensate --qualification, and a table of the figures on standard output.

#include <cstdio>
#include <iostream>
#include <map>
#include <stdexcept>

#include "cli/commands.hpp"
#include "probecomp/error.hpp"
#include "probecomp/io/json.hpp"
#include "probecomp/io/output_files.hpp"
#include "probecomp/io/point_files.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/io/units.hpp"
#include "probecomp/probe/qualification_file.hpp"

namespace probecomp::cli {

std::vector<std::string> point_styli(const io::PointTable& t) {
  int column = io::column_index(t, "stylus");
  if (column < 0) column = io::column_index(t, "tip");
  if (column < 0) return {};
  std::vector<std::string> out;
  out.reserve(t.rows.size());
  for (const auto& row : t.rows) out.emplace_back(row[static_cast<std::size_t>(column)]);
  return out;
}

int run_qualify(const QualifyArgs& a) {
  if (!(a.sphere_diameter > 0.0)) throw std::invalid_argument("--sphere-diameter must be a positive length");
  if (a.max_degree < 0 || a.max_degree > 12) throw std::invalid_argument("--max-degree must be 0 to 12");
  io::check_outputs_spare_inputs({{"--output", a.output}}, {{"--points", a.points}});
  std::optional<io::LengthUnit> declared;
  if (!a.units.empty()) declared = io::length_unit(a.units);
  const io::PointTable t = io::read_points(a.points, declared);
  const double diameter = a.sphere_diameter * t.unit.mm;
  // Rows by stylus, in the order each first appears.
  std::vector<std::string> styli = point_styli(t);
  if (styli.empty()) styli.assign(t.points.size(), kDefaultStylus);
  std::vector<std::string> order;
  std::map<std::string, std::vector<std::size_t>> rows;
  for (std::size_t k = 0; k < styli.size(); ++k) {
    if (styli[k].empty()) {
      throw InputError(a.points + ":" + std::to_string(t.line[k]) + ": this touch names no stylus");
    }
    if (!rows.contains(styli[k])) order.push_back(styli[k]);
    rows[styli[k]].push_back(k);
  }
  probe::Qualification q;
  probe::QualificationOptions options;
  options.max_degree = a.max_degree;
  for (const std::string& name : order) {
    std::vector<Point3> centres;
    std::vector<Vector3> normals;
    for (std::size_t k : rows[name]) {
      centres.push_back(t.points[k]);
      if (t.normals) normals.push_back((*t.normals)[k]);
    }
    probe::StylusQualification s = probe::qualify_stylus(name, centres, normals, diameter, options);
    // A sphere the touches do not fit with a positive tip smaller than it: the diameter, or its unit, is not the
    // sphere's (or the touches are not of one sphere).
    if (s.status == probe::QualificationStatus::OK && !(s.effective_radius > 0.0 && s.effective_radius < diameter / 2)) {
      char text[240];
      std::snprintf(text, sizeof text,
                    "stylus %s: the touches' centres lie on a sphere of diameter %.6g mm, which with --sphere-diameter "
                    "%.6g mm leaves a tip radius of %.6g mm: check the diameter and the unit",
                    name.c_str(), diameter + 2 * s.effective_radius, diameter, s.effective_radius);
      throw InputError(a.points + ": " + text);
    }
    q.styli.push_back(std::move(s));
  }
  int usable = 0;
  for (const probe::StylusQualification& s : q.styli) {
    if (s.status == probe::QualificationStatus::OK) {
      ++usable;
    } else {
      std::cerr << "probecomp: warning: stylus " << s.stylus << " is not qualified: " << s.reason << '\n';
    }
  }
  if (usable == 0) throw InputError(a.points + ": no stylus could be qualified");
  io::OutputFiles files;
  files.add(a.output, io::json_text(probe::to_json(q)));
  files.commit();
  std::printf("%-10s %7s %14s %9s %9s %9s %6s %9s %8s\n", "stylus", "touches", "radius mm", "u um", "form um",
              "resid um", "degree", "varies um", "support");
  for (const probe::StylusQualification& s : q.styli) {
    if (s.status != probe::QualificationStatus::OK) {
      std::printf("%-10s %7d  %s\n", s.stylus.c_str(), s.touches, to_string(s.status));
      continue;
    }
    std::printf("%-10s %7d %14.6f %9.3f %9.3f %9.3f %6d %9.3f %7.0f°\n", s.stylus.c_str(), s.touches,
                s.effective_radius, 1e3 * s.effective_radius_u, 1e3 * s.form_error, 1e3 * s.residual,
                s.model.degree(), 1e3 * s.model.variation(), s.support_angle_deg);
  }
  return 0;
}

}  // namespace probecomp::cli
