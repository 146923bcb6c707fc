// End-to-end benchmarks (issue 6), on 2 cores:
//   BM_Compensate10k             the paper's size: 10 000 simulated touches of the built-in free-form case
//                                (deformed, misaligned, σ = 4.5 µm), CAD-based compensation. Target ≤ 0.2 s.
//   BM_NormalCheck1M             compensation::normal_disagreement alone on 1 000 000 centres of a 20 × 20 rational
//                                bicubic face (the fit: the exact surface), 1 % left out at random: the cost the
//                                check adds to a face with gross errors (items: points checked).
//   BM_Compensate1M20x20         1 000 000 raw centres on a 20 × 20 rational bicubic face (moved ~1 mm / 1°,
//                                σ = 2 µm). Target ≤ 10 s and ≤ 2 GB peak memory (counter peak_rss_MB: the
//                                process's peak resident set, which includes the input).
// Inputs are made once, outside the timing; the timed part is compensation::compensate (offset model,
// registration, fitting, contact points, deviations). Counters give each stage's seconds.

#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <random>

#include "probecomp/cad/locator.hpp"
#include "probecomp/compensation/normal_support.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/simulation/freeform_case.hpp"
#include "probecomp/simulation/random.hpp"
#include "support/test_surfaces.hpp"

namespace {

using namespace probecomp;

struct Input {
  cad::Model nominal;
  std::vector<Point3> raw;
  std::vector<Vector3> normals;
};

const Input& freeform_10k() {
  static const Input in = [] {
    const simulation::FreeformCase c = simulation::paper_freeform_case();
    const auto plan = simulation::random_plan(c.nominal.faces.at(0), 10'000, 11);
    const cad::Model actual = simulation::actual_model(c.nominal, c.deformation, c.placement);
    const cad::ModelLocator locator(actual);
    const auto touches = simulation::simulate_touches(locator, plan, {.probe_radius = 1.0, .noise_sigma = 0.0045, .seed = 1});
    Input i{c.nominal, {}, {}};
    for (std::size_t k = 0; k < touches.size(); ++k) {
      i.raw.push_back(touches[k].measured);
      i.normals.push_back(plan[k].normal);
    }
    return i;
  }();
  return in;
}

const Input& panel_1m() {
  static const Input in = [] {
    Input i;
    i.nominal.faces.push_back(cad::Face{.index = 0, .name = "", .source_type = "bspline",
                                        .surface = testing::freeform_panel(7, 20, true), .trim = nullptr, .outward = 1,
                                        .material_known = true, .exact = true});
    const nurbs::Surface& s = i.nominal.faces[0].surface;
    const geometry::RigidTransform T = geometry::from_pose({.rx = 1.0, .ry = -1.0, .rz = 0.5, .t = Vector3(1, -1, 1)});
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> t(0.02, 0.98);
    std::normal_distribution<double> noise(0.0, 0.002);
    for (int k = 0; k < 1'000'000; ++k) {
      const double u = t(rng), v = t(rng);
      i.raw.push_back(T * (nurbs::evaluate(s, u, v) + 1.0 * nurbs::unit_normal(s, u, v).n) +
                      simulation::draw_vector(noise, rng));
    }
    return i;
  }();
  return in;
}

void run(benchmark::State& state, const Input& in) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  compensation::CompensateOptions o;
  o.probe_radius = 1.0;
  compensation::CompensationResult r;
  for (auto _ : state) {
    r = compensation::compensate(in.nominal, in.raw, std::nullopt, o);
    benchmark::DoNotOptimize(r.points.data());
  }
  state.counters["points"] = static_cast<double>(in.raw.size());
  state.counters["ok"] = r.count(compensation::PointStatus::Ok);
  state.counters["s_prepare"] = r.seconds.prepare;
  state.counters["s_register"] = r.seconds.registration;
  state.counters["s_fit"] = r.seconds.fitting;
  state.counters["s_compensate"] = r.seconds.compensation;
  state.counters["control_points"] = r.faces.empty() ? 0 : r.faces[0].control_points;
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["peak_rss_MB"] = static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in kB on Linux
}

void BM_Compensate10k(benchmark::State& state) { run(state, freeform_10k()); }

void BM_NormalCheck1M(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  const nurbs::Surface s = testing::freeform_panel(7, 20, true);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> t(0.02, 0.98), chance(0.0, 1.0);
  std::vector<Point3> centres;
  std::vector<fitting::SurfaceParameter> params;
  std::vector<double> weights;
  for (int k = 0; k < 1'000'000; ++k) {
    const double u = t(rng), v = t(rng);
    centres.push_back(nurbs::evaluate(s, u, v));
    params.push_back({u, v});
    weights.push_back(chance(rng) < 0.01 ? 0.0 : 1.0);
  }
  std::size_t checked = 0;
  for (auto _ : state) {
    const std::vector<double> angle = compensation::normal_disagreement(s, centres, params, weights).angle;
    checked = 0;
    for (const double a : angle) checked += a != 0.0;
    benchmark::DoNotOptimize(angle.data());
  }
  state.counters["checked"] = static_cast<double>(checked);
}
void BM_Compensate1M20x20(benchmark::State& state) { run(state, panel_1m()); }

}  // namespace

BENCHMARK(BM_Compensate10k)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_NormalCheck1M)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_Compensate1M20x20)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
