#include "probecomp/studies/shape_suite_study.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "probecomp/nurbs/closest_point.hpp"

namespace probecomp::studies {

namespace {

// Far beyond every case's seed (the suite's 1–30, draws 1 000 + N), so that no noise draw repeats another case's.
constexpr std::uint64_t kNoiseDrawStride = 1'000'003;

}  // namespace

ShapeCaseResult run_shape_case(const simulation::ShapeCase& c, const compensation::CompensateOptions& options) {
  ShapeCaseResult out;
  out.shape = c;
  out.nominal = simulation::base_model(c.base);
  out.plan = simulation::plan_of(c, out.nominal);
  const SimulatedMeasurement m{.nominal = out.nominal,
                               .deformation = simulation::deformation_of(c, out.nominal),
                               .placement = c.placement(),
                               .plan = out.plan,
                               .probe_radius = c.probe_radius,
                               .noise_sigma = c.noise_sigma,
                               .seed = c.seed + c.noise_draw * kNoiseDrawStride};
  const bool normals = c.sampling != simulation::Sampling::ScanLines && c.approach_normals;
  static_cast<MethodComparison&>(out) = compare_methods(m, {.approach_normals = normals, .compensate = options});

  const nurbs::Surface& s = out.nominal.faces.at(0).surface;
  const nurbs::Domain d = s.domain();
  out.region.resize(out.plan.size());
  const nurbs::ClosestPointSolver nominal_solver(s);
  std::array<int, kSuiteRegions * kSuiteRegions> rows{}, covered{};
  int all_rows = 0, all_covered = 0;
  double u_sum = 0.0;
  for (std::size_t k = 0; k < out.plan.size(); ++k) {
    // The programmed point's parameters on the nominal: where on the face it was planned.
    const nurbs::ClosestPointResult foot = nominal_solver.closest_point(out.plan[k].point);
    const int a = std::clamp(static_cast<int>(kSuiteRegions * (foot.u - d.u0) / (d.u1 - d.u0)), 0, kSuiteRegions - 1);
    const int b = std::clamp(static_cast<int>(kSuiteRegions * (foot.v - d.v0) / (d.v1 - d.v0)), 0, kSuiteRegions - 1);
    out.region[k] = a * kSuiteRegions + b;
    const compensation::CompensatedPoint& p = out.cad.points[k];
    if (p.status != compensation::PointStatus::Ok) {
      ++out.flagged;
      continue;
    }
    if (!std::isfinite(out.cad_error[k])) continue;
    const bool in = std::abs(out.cad_error[k]) <= 2.0 * p.uncertainty;
    ++rows[static_cast<std::size_t>(out.region[k])];
    covered[static_cast<std::size_t>(out.region[k])] += in;
    ++all_rows;
    all_covered += in;
    u_sum += p.uncertainty;
  }
  if (all_rows > 0) {
    out.coverage_2u = static_cast<double>(all_covered) / all_rows;
    out.mean_uncertainty = u_sum / all_rows;
    out.worst_region_coverage_2u = 1.0;
    for (std::size_t g = 0; g < rows.size(); ++g) {
      if (rows[g] < kSuiteMinRegionRows) continue;
      const double share = static_cast<double>(covered[g]) / rows[g];
      if (share < out.worst_region_coverage_2u) {
        out.worst_region_coverage_2u = share;
        out.worst_region = static_cast<int>(g);
      }
    }
  }

  out.fit_rms = std::numeric_limits<double>::quiet_NaN();
  if (!out.cad.faces.empty() && out.cad.faces[0].centre_surface) {
    const nurbs::ClosestPointSolver solver(*out.cad.faces[0].centre_surface);
    double sum = 0.0;
    for (const simulation::Touch& t : out.touches) {
      const double e = solver.closest_point(t.centre).distance;
      sum += e * e;
    }
    out.fit_rms = std::sqrt(sum / static_cast<double>(out.touches.size()));
  }
  return out;
}

}  // namespace probecomp::studies
