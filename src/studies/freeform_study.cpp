#include "probecomp/studies/freeform_study.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

namespace probecomp::studies {

FreeformStudyOptions scattered_points(int n) {
  FreeformStudyOptions o;
  o.random_points = n;
  o.shuffle = true;
  o.approach_normals = false;
  return o;
}

FreeformStudyResult run_freeform_study(const FreeformStudyOptions& options) {
  FreeformStudyResult out;
  out.freeform = simulation::paper_freeform_case(options.reversed);
  if (options.noise_sigma >= 0.0) out.freeform.noise_sigma = options.noise_sigma;
  // 1 mm deep over a width of 1.75 mm: slopes up to e^(-1/2) / 1.75 = 0.35, i.e. 19°.
  if (options.steep_dent) out.freeform.deformation.bumps.at(1).width = 1.75;
  const simulation::FreeformCase& c = out.freeform;
  const cad::Face& face = c.nominal.faces.at(0);
  if (options.random_points > 0) {
    out.plan = simulation::random_plan(face, options.random_points, options.seed + 1000);
  } else {
    // The grid runs 120 along the panel's 100 mm and 60 along its 50 mm whichever way the surface is parametrised.
    out.plan = options.reversed ? simulation::grid_plan(face, c.grid_v, c.grid_u)
                                : simulation::grid_plan(face, c.grid_u, c.grid_v);
  }
  if (options.shuffle) {
    std::mt19937_64 rng(options.seed + 2000);
    std::shuffle(out.plan.begin(), out.plan.end(), rng);
  }
  if (options.repeated_fraction > 0.0) {
    std::mt19937_64 rng(options.seed + 3000);
    std::bernoulli_distribution repeat(std::min(options.repeated_fraction, 1.0));
    std::vector<simulation::ProgrammedPoint> with_repeats;
    with_repeats.reserve(out.plan.size() * 2);
    for (const simulation::ProgrammedPoint& p : out.plan) {
      with_repeats.push_back(p);
      if (repeat(rng)) with_repeats.push_back(p);
    }
    out.plan = std::move(with_repeats);
  }
  std::vector<double> radii;
  if (options.second_probe_radius > 0.0) {
    double x0 = std::numeric_limits<double>::infinity(), x1 = -x0;
    for (const simulation::ProgrammedPoint& p : out.plan) {
      x0 = std::min(x0, p.point.x());
      x1 = std::max(x1, p.point.x());
    }
    for (const simulation::ProgrammedPoint& p : out.plan) {
      radii.push_back(p.point.x() > 0.5 * (x0 + x1) ? options.second_probe_radius : c.probe_radius);
    }
  }
  SimulatedMeasurement m{.nominal = c.nominal, .deformation = c.deformation, .placement = c.placement, .plan = out.plan,
                         .probe_radius = c.probe_radius, .probe_radii = radii, .noise_sigma = c.noise_sigma,
                         .seed = options.seed, .repeats_are_copies = options.exact_repeats};
  static_cast<MethodComparison&>(out) =
      compare_methods(m, {.approach_normals = options.approach_normals, .compensate = options.compensate});

  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const simulation::ProgrammedPoint& p : out.plan) {
    x0 = std::min(x0, p.point.x());
    x1 = std::max(x1, p.point.x());
    y0 = std::min(y0, p.point.y());
    y1 = std::max(y1, p.point.y());
  }
  constexpr int kRegions = 4;
  std::array<int, kRegions * kRegions>& inside = out.region_covered;
  std::array<int, kRegions * kRegions>& counted = out.region_ok;
  double u_sum = 0.0;
  for (std::size_t k = 0; k < out.plan.size(); ++k) {
    const compensation::CompensatedPoint& p = out.cad.points[k];
    if (p.status != compensation::PointStatus::Ok) {
      ++out.flagged;
      continue;
    }
    if (!std::isfinite(out.cad_error[k])) continue;
    const Point3& x = out.plan[k].point;
    const int a = std::clamp(static_cast<int>(kRegions * (x.x() - x0) / std::max(x1 - x0, 1e-12)), 0, kRegions - 1);
    const int b = std::clamp(static_cast<int>(kRegions * (x.y() - y0) / std::max(y1 - y0, 1e-12)), 0, kRegions - 1);
    const bool in = std::abs(out.cad_error[k]) <= 2.0 * p.uncertainty;
    inside[static_cast<std::size_t>(a * kRegions + b)] += in;
    ++counted[static_cast<std::size_t>(a * kRegions + b)];
    u_sum += p.uncertainty;
  }
  const int all_inside = std::accumulate(inside.begin(), inside.end(), 0);
  const int all_counted = std::accumulate(counted.begin(), counted.end(), 0);
  if (all_counted > 0) {
    out.mean_uncertainty = u_sum / all_counted;
    out.coverage_2u = static_cast<double>(all_inside) / all_counted;
    out.worst_region_coverage_2u = 1.0;
    for (std::size_t g = 0; g < inside.size(); ++g) {
      if (counted[g] > 0) {
        out.worst_region_coverage_2u = std::min(out.worst_region_coverage_2u, static_cast<double>(inside[g]) / counted[g]);
      }
    }
  }
  return out;
}

PaperTable2 paper_table2() {
  PaperTable2 t;
  t.conventional = {.points = 7200, .std = 0.045965, .mean = 0.018314, .min = -0.049, .max = 0.279};
  t.proposed = {.points = 7200, .std = 0.012947, .mean = 0.003014, .min = -0.055, .max = 0.094};
  return t;
}

}  // namespace probecomp::studies
