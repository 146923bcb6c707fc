#include "probecomp/studies/freeform_study.hpp"

#include <algorithm>
#include <random>

namespace probecomp::studies {

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
  SimulatedMeasurement m{.nominal = c.nominal, .deformation = c.deformation, .placement = c.placement, .plan = out.plan,
                         .probe_radius = c.probe_radius, .noise_sigma = c.noise_sigma, .seed = options.seed};
  static_cast<MethodComparison&>(out) =
      compare_methods(m, {.approach_normals = options.approach_normals, .compensate = options.compensate});
  return out;
}

PaperTable2 paper_table2() {
  PaperTable2 t;
  t.conventional = {.points = 7200, .std = 0.045965, .mean = 0.018314, .min = -0.049, .max = 0.279};
  t.proposed = {.points = 7200, .std = 0.012947, .mean = 0.003014, .min = -0.055, .max = 0.094};
  return t;
}

}  // namespace probecomp::studies
