#include "probecomp/studies/shape_suite_study.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>
#include <vector>

#include "probecomp/nurbs/closest_point.hpp"

namespace probecomp::studies {

namespace {

// Far beyond every case's seed (the suite's 1–30, draws 1 000 + N), so that no noise draw repeats another case's.
constexpr std::uint64_t kNoiseDrawStride = 1'000'003;

}  // namespace

RegionShares region_coverage_2u(std::span<const double> error, std::span<const double> u, std::span<const int> region) {
  std::array<int, std::tuple_size_v<RegionShares>> rows{}, covered{};
  for (std::size_t k = 0; k < error.size(); ++k) {
    if (!std::isfinite(error[k])) continue;
    const auto g = static_cast<std::size_t>(region[k]);
    ++rows[g];
    covered[g] += std::abs(error[k]) <= 2.0 * u[k];
  }
  RegionShares share;
  for (std::size_t g = 0; g < share.size(); ++g) {
    share[g] = rows[g] < kSuiteMinRegionRows ? std::numeric_limits<double>::quiet_NaN()
                                             : static_cast<double>(covered[g]) / rows[g];
  }
  return share;
}

SimulatedMeasurement shape_case_measurement(const simulation::ShapeCase& c) {
  cad::Model nominal = simulation::base_model(c.base);
  std::vector<simulation::ProgrammedPoint> plan = simulation::plan_of(c, nominal);
  simulation::Deformation deformation = simulation::deformation_of(c, nominal);
  return {.nominal = std::move(nominal),
          .deformation = std::move(deformation),
          .placement = c.placement(),
          .plan = std::move(plan),
          .probe_radius = c.probe_radius,
          .noise_sigma = c.noise_sigma,
          .seed = c.seed + c.noise_draw * kNoiseDrawStride};
}

ShapeCaseResult run_shape_case(const simulation::ShapeCase& c, const compensation::CompensateOptions& options) {
  ShapeCaseResult out;
  out.shape = c;
  const SimulatedMeasurement m = shape_case_measurement(c);
  out.nominal = m.nominal;
  out.plan = m.plan;
  const bool normals = c.sampling != simulation::Sampling::ScanLines && c.approach_normals;
  static_cast<MethodComparison&>(out) = compare_methods(m, {.approach_normals = normals, .compensate = options});

  const nurbs::Surface& s = out.nominal.faces.at(0).surface;
  const nurbs::Domain d = s.domain();
  out.region.resize(out.plan.size());
  const nurbs::ClosestPointSolver nominal_solver(s);
  int all_rows = 0, all_covered = 0;
  double u_sum = 0.0;
  std::vector<double> u(out.plan.size(), std::numeric_limits<double>::quiet_NaN());
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
    u[k] = p.uncertainty;
    ++all_rows;
    all_covered += std::abs(out.cad_error[k]) <= 2.0 * p.uncertainty;
    u_sum += p.uncertainty;
  }
  // (cad_error is NaN for every row not ok: errors_against.)
  out.region_coverage = region_coverage_2u(out.cad_error, u, out.region);
  if (all_rows > 0) {
    out.coverage_2u = static_cast<double>(all_covered) / all_rows;
    out.mean_uncertainty = u_sum / all_rows;
    out.worst_region_coverage_2u = 1.0;
    for (std::size_t g = 0; g < out.region_coverage.size(); ++g) {
      if (out.region_coverage[g] < out.worst_region_coverage_2u) {
        out.worst_region_coverage_2u = out.region_coverage[g];
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

ReplicatedShapeCase replicate_shape_case(simulation::ShapeCase c, int draws, const compensation::CompensateOptions& options) {
  ReplicatedShapeCase out;
  std::vector<std::vector<double>> error;  // per draw, per row (NaN where not ok)
  std::vector<std::vector<double>> u;      // per draw, per row
  std::vector<int> region;
  RegionShares sum{};
  std::array<int, std::tuple_size_v<RegionShares>> scored{};
  for (int d = 0; d < draws; ++d) {
    c.noise_draw = static_cast<std::uint64_t>(d);
    ShapeCaseResult s = run_shape_case(c, options);
    out.stds.push_back(s.cad_summary.std);
    out.coverages.push_back(s.coverage_2u);
    out.worst_regions.push_back(s.worst_region_coverage_2u);
    for (std::size_t g = 0; g < sum.size(); ++g) {
      if (!std::isfinite(s.region_coverage[g])) continue;
      sum[g] += s.region_coverage[g];
      ++scored[g];
    }
    region = std::move(s.region);
    error.push_back(std::move(s.cad_error));
    std::vector<double>& ud = u.emplace_back();
    for (const compensation::CompensatedPoint& p : s.cad.points) ud.push_back(p.uncertainty);
  }
  {
    double bias2 = 0.0, scatter2 = 0.0, u2 = 0.0;
    std::size_t rows = 0;
    for (std::size_t k = 0; k < region.size(); ++k) {
      double sum_e = 0.0, sum_e2 = 0.0, sum_u2 = 0.0;
      bool every = draws > 1;
      for (std::size_t d = 0; d < error.size() && every; ++d) {
        every = std::isfinite(error[d][k]);
        sum_e += error[d][k];
        sum_e2 += error[d][k] * error[d][k];
        sum_u2 += u[d][k] * u[d][k];
      }
      if (!every) continue;
      const double mean = sum_e / draws;
      const double variance = std::max(0.0, (sum_e2 - draws * mean * mean) / (draws - 1));
      bias2 += std::max(0.0, mean * mean - variance / draws);
      scatter2 += variance;
      u2 += sum_u2 / draws;
      ++rows;
    }
    if (rows > 0) {
      out.bias_rms = std::sqrt(bias2 / rows);
      out.scatter_rms = std::sqrt(scatter2 / rows);
      out.u_rms = std::sqrt(u2 / rows);
    }
  }
  std::vector<double> oracle(region.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < oracle.size(); ++k) {
    double squares = 0.0;
    int n = 0;
    for (const std::vector<double>& e : error) {
      if (!std::isfinite(e[k])) continue;
      squares += e[k] * e[k];
      ++n;
    }
    if (n > 0) oracle[k] = std::sqrt(squares / n);
  }
  for (const std::vector<double>& e : error) {
    const RegionShares share = region_coverage_2u(e, oracle, region);
    double lowest = std::numeric_limits<double>::quiet_NaN();
    for (const double x : share) lowest = std::fmin(lowest, x);  // fmin passes over the NaN of unscored regions
    out.oracle_worst_regions.push_back(lowest);
  }
  for (std::size_t g = 0; g < sum.size(); ++g) {
    // Only regions scored in every draw, so that each mean is over the same draws.
    if (scored[g] == draws) out.lowest_region_mean = std::fmin(out.lowest_region_mean, sum[g] / draws);
  }
  return out;
}

}  // namespace probecomp::studies
