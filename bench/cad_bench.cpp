// CAD model benchmarks on the 4 MB impeller (277 trimmed faces): reading and indexing, and projecting
// 100 000 points around it on 2 threads ("find nominals").

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <random>

#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/plan.hpp"

namespace {

using namespace probecomp;

const std::filesystem::path kImpeller = std::filesystem::path(PROBECOMP_BENCH_CAD_DIR) / "pyiges_impeller.igs";

void BM_ReadAndIndexImpeller(benchmark::State& state) {
  std::size_t faces = 0;
  for (auto _ : state) {
    const cad::Model model = cad::read_model(kImpeller);
    const cad::ModelLocator locator(model);
    faces = model.faces.size();
  }
  state.counters["faces"] = static_cast<double>(faces);
}
BENCHMARK(BM_ReadAndIndexImpeller)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

void BM_ProjectImpeller100k2Threads(benchmark::State& state) {
  static const cad::Model model = cad::read_model(kImpeller);
  static const cad::ModelLocator locator(model);
  // Points within ±2 mm of planned points, scattered sideways by up to 1 mm: every face gets its share.
  static const std::vector<Point3> points = [] {
    const std::vector<cad::PlannedPoint> plan = cad::plan_points(model, 2.0, {});
    std::mt19937_64 rng(1);
    std::uniform_int_distribution<std::size_t> pick(0, plan.size() - 1);
    std::uniform_real_distribution<double> off(-2.0, 2.0), side(-1.0, 1.0);
    std::vector<Point3> out;
    for (int k = 0; k < 100'000; ++k) {
      const cad::PlannedPoint& p = plan[pick(rng)];
      out.push_back(p.point + off(rng) * p.normal + Vector3(side(rng), side(rng), side(rng)));
    }
    return out;
  }();
  tbb::task_arena arena(2);
  std::size_t not_ok = 0;
  for (auto _ : state) {
    std::vector<cad::ModelPoint> r;
    arena.execute([&] { r = locator.closest_points(points); });
    not_ok = static_cast<std::size_t>(std::count_if(r.begin(), r.end(), [](const auto& m) { return !m.ok(); }));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * points.size()));
  state.counters["not_ok"] = static_cast<double>(not_ok);
}
BENCHMARK(BM_ProjectImpeller100k2Threads)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

}  // namespace
