// Fitting benchmarks: least-squares control points (assembly and solve), the penalised fit's smoothing search, and
// offset surfaces.

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <random>

#include "probecomp/fitting/least_squares.hpp"
#include "probecomp/fitting/offset.hpp"
#include "probecomp/fitting/penalized.hpp"
#include "probecomp/simulation/random.hpp"
#include "support/test_surfaces.hpp"

namespace {

using namespace probecomp;

// 1 000 000 points with 5 µm noise on a bicubic 40 × 40 free-form panel, fitted from a start 0.1 mm off; one
// thread.
void BM_FitControlPoints(benchmark::State& state) {
  static const nurbs::Surface truth = testing::freeform_panel(3, 40);
  static std::vector<Point3> points;
  static std::vector<fitting::SurfaceParameter> params;
  static nurbs::Surface start = truth;
  if (points.empty()) {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> t(0.0, 1.0), d(-0.1, 0.1);
    std::normal_distribution<double> noise(0.0, 0.005);
    for (int k = 0; k < 1'000'000; ++k) {
      const fitting::SurfaceParameter uv{t(rng), t(rng)};
      params.push_back(uv);
      points.push_back(nurbs::evaluate(truth, uv.u, uv.v) + noise(rng) * nurbs::unit_normal(truth, uv.u, uv.v).n);
    }
    std::vector<Point3> P;
    std::vector<double> w;
    for (int i = 0; i < truth.num_u(); ++i)
      for (int j = 0; j < truth.num_v(); ++j) {
        P.push_back(truth.control_point(i, j) + simulation::draw_vector(d, rng));
        w.push_back(truth.weight(i, j));
      }
    start = nurbs::Surface(truth.U(), truth.V(), P, w);
  }
  tbb::task_arena one(1);
  fitting::FitResult fit{.surface = start};
  for (auto _ : state) {
    one.execute([&] { fit = fitting::fit_control_points(start, points, params); });
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * points.size()));
  state.counters["rms_um"] = fit.rms * 1000.0;
  state.counters["iterations"] = fit.iterations;
  state.counters["control_points"] = truth.num_u() * truth.num_v();
}
BENCHMARK(BM_FitControlPoints)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// The penalised fit with its smoothing chosen by cross-validation (17 trials, each a band Cholesky factor, the band
// of the inverse and the leave-one-out score) on a net as fine as a refined face's: a 40 × 40 free-form panel (1 600
// control points, half-bandwidth 123), 50 000 points with 5 µm noise, from a start 0.1 mm off, one thread. The band
// algebra is most of its time here; on the pipeline's 10 000-point case (220 control points) the score is.
void BM_FitPenalized40x40(benchmark::State& state) {
  static const nurbs::Surface truth = testing::freeform_panel(3, 40);
  static const testing::SurfaceSamples data = testing::sample_surface(truth, 50'000, 0.005, 2, testing::Noise::Isotropic);
  static const nurbs::Surface start = testing::perturbed(truth, 0.1, 4);
  tbb::task_arena one(1);
  fitting::PenalizedFitResult fit{.surface = start};
  for (auto _ : state) {
    one.execute([&] { fit = fitting::fit_penalized(start, data.points, data.params); });
  }
  state.counters["trials"] = fit.evaluations;
  state.counters["log10_smoothing"] = fit.log10_smoothing;
  state.counters["effective_dof"] = fit.effective_dof;
}
BENCHMARK(BM_FitPenalized40x40)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// A 20 × 20 rational bicubic panel (uniform knots, weights 0.8–1.25, curvature radius down to 17 mm) offset
// by a 1 mm probe radius to 1e-4 mm; default threads.
void BM_OffsetSurface(benchmark::State& state) {
  const nurbs::Surface panel = testing::freeform_panel(3, 20, true);
  fitting::OffsetResult r{.surface = panel};
  for (auto _ : state) r = fitting::offset_surface(panel, 1.0);
  state.counters["ok"] = r.ok();
  state.counters["deviation_um"] = r.deviation * 1000.0;
  state.counters["rounds"] = r.rounds;
  state.counters["control_points"] = r.surface.num_u() * r.surface.num_v();
}
BENCHMARK(BM_OffsetSurface)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

}  // namespace
