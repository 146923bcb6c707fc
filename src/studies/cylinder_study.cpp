#include "probecomp/studies/cylinder_study.hpp"

#include <cmath>
#include <numbers>

#include "probecomp/nurbs/constructors.hpp"
#include "probecomp/geometry/stopwatch.hpp"

namespace probecomp::studies {

namespace {

// "Smoothing removes noise" is claimed where the noise dominates the fit's own error: from σ = 10 µm.
constexpr double kSmoothingClaimFromSigma = 0.010;

CylinderStudyRow run_row(const cad::Model& nominal, const CylinderStudyOptions& o, const simulation::Deformation& d,
                         const geometry::RigidTransform& placement, double sigma, std::uint64_t seed) {
  const geometry::Stopwatch clock;
  SimulatedMeasurement m{.nominal = nominal, .deformation = d, .placement = placement,
                         .plan = simulation::grid_plan(nominal.faces.at(0), o.grid, o.grid, o.margin),
                         .probe_radius = o.probe_radius, .noise_sigma = sigma, .seed = seed};
  const MethodComparison c = compare_methods(m);
  CylinderStudyRow row;
  row.sigma = sigma;
  row.points = static_cast<int>(m.plan.size());
  row.cad = c.cad_summary;
  row.conventional = c.conventional_summary;
  row.cad_untrusted = row.points - c.cad.count(compensation::PointStatus::Ok);
  row.seconds = clock.seconds();
  return row;
}

}  // namespace

cad::Model cylinder_part(const CylinderPart& part) {
  cad::Model m;
  m.path = "built-in cylinder section";
  m.file_units = "mm";
  m.faces.push_back({.index = 0, .name = "cylinder section", .source_type = "cylinder",
                     .surface = nurbs::make_cylinder_section(Point3(-part.length / 2.0, 0.0, 0.0), Vector3::UnitY(),
                                                             Vector3::UnitZ(), part.radius, part.arc_start * kDegree,
                                                             part.arc_end * kDegree, part.length),
                     .trim = nullptr, .outward = 1, .material_known = false, .exact = true});
  return m;
}

simulation::Deformation cylinder_deformation(const CylinderStudyOptions& o, double peak) {
  simulation::Deformation d;
  const double middle = (o.part.arc_start + o.part.arc_end) / 2.0 * kDegree;
  d.sinusoids.push_back({.amplitude = peak, .wavelength = o.wavelength, .direction = Vector3::UnitX(),
                         .origin = Point3(0.0, o.part.radius * std::cos(middle), o.part.radius * std::sin(middle)),
                         .window = o.window, .phase = 90.0});
  return d;
}

bool CylinderStudyResult::cad_better_everywhere() const {
  for (const CylinderStudyRow& r : rows) {
    if (!(std::abs(r.cad.mean) < std::abs(r.conventional.mean) && r.cad.std < r.conventional.std)) return false;
  }
  return !rows.empty();
}

bool CylinderStudyResult::cad_smooths_noise() const {
  for (const CylinderStudyRow& r : rows) {
    if (r.sigma >= kSmoothingClaimFromSigma - 1e-12 && !(r.cad.std < r.sigma)) return false;
  }
  return !rows.empty();
}

CylinderStudyResult run_cylinder_misalignment_study(const CylinderStudyOptions& o) {
  const cad::Model nominal = cylinder_part(o.part);
  const geometry::RigidTransform placement = geometry::from_pose({.t = Vector3(0.0, 0.0, o.misalignment)});
  CylinderStudyResult out;
  for (std::size_t k = 0; k < o.sigmas.size(); ++k) {
    out.rows.push_back(run_row(nominal, o, {}, placement, o.sigmas[k], o.seed + k));
    out.rows.back().misalignment = o.misalignment;
  }
  return out;
}

CylinderStudyResult run_cylinder_deformation_study(const CylinderStudyOptions& o) {
  const cad::Model nominal = cylinder_part(o.part);
  CylinderStudyResult out;
  std::uint64_t k = 0;
  for (double peak : o.peaks) {
    for (double sigma : o.sigmas) {
      out.rows.push_back(run_row(nominal, o, cylinder_deformation(o, peak), geometry::RigidTransform::Identity(),
                                 sigma, o.seed + k++));
      out.rows.back().peak = peak;
    }
  }
  return out;
}

}  // namespace probecomp::studies
