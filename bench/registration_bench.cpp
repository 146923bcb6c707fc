// Registration benchmark (issue 5): 100 000 raw probe centres on a 20 × 20 rational bicubic face, misaligned by
// about 1 mm and 1°, registered to the face's radius-offset model on 2 cores. The offset model is built once
// outside the timing (BM_OffsetSurface times that); the timed part is ICP with its closest points, plus, in
// the second benchmark, indexing the offset face.

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <random>

#include "probecomp/cad/offset_model.hpp"
#include "probecomp/registration/routes.hpp"
#include "support/test_surfaces.hpp"

namespace {

using namespace probecomp;

struct Case {
  cad::Model nominal;
  cad::OffsetModel offset;
  std::vector<Point3> raw;
  geometry::RigidTransform truth;
};

const Case& registration_case() {
  static const Case c = [] {
    cad::Model nominal;
    nominal.faces.push_back(cad::Face{.index = 0, .name = "", .source_type = "bspline",
                                      .surface = testing::freeform_panel(7, 20, true), .trim = nullptr, .outward = 1,
                                      .material_known = true, .exact = true});
    const double r = 1.0;
    cad::OffsetModel offset = cad::offset_model(nominal, r);
    // 1° about each axis through the panel's centre, then 1 mm along each axis: the corner of the study's range.
    const nurbs::Domain d = nominal.faces[0].surface.domain();
    const Point3 centre = nurbs::evaluate(nominal.faces[0].surface, 0.5 * (d.u0 + d.u1), 0.5 * (d.v0 + d.v1));
    const geometry::RigidTransform truth =
        Eigen::Translation3d(centre + Vector3(1.0, -1.0, 1.0)) *
        geometry::from_pose({.rx = 1.0, .ry = -1.0, .rz = 1.0, .t = Vector3::Zero()}) * Eigen::Translation3d(-centre);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> t(0.02, 0.98);
    std::vector<Point3> raw;
    const nurbs::Surface& s = nominal.faces[0].surface;
    for (int k = 0; k < 100'000; ++k) {
      const double u = t(rng), v = t(rng);
      raw.push_back(truth * (nurbs::evaluate(s, u, v) + r * nurbs::unit_normal(s, u, v).n));
    }
    return Case{std::move(nominal), std::move(offset), std::move(raw), truth};
  }();
  return c;
}

void report(benchmark::State& state, const registration::RegistrationResult& r, const Case& c) {
  double worst = 0.0;
  for (std::size_t k = 0; k < c.raw.size(); k += 97) {
    const Point3 p = c.truth.inverse() * c.raw[k];
    worst = std::max(worst, (r.transform * p - c.raw[k]).norm());
  }
  state.counters["iterations"] = r.iterations;
  state.counters["converged"] = r.converged();
  state.counters["error_um"] = worst * 1e3;  // largest point error against the true motion, µm
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(c.raw.size()));
}

void BM_Register100k2Threads(benchmark::State& state) {
  const Case& c = registration_case();
  const cad::ModelLocator locator(c.offset.model);
  tbb::task_arena arena(2);
  registration::RegistrationResult r;
  for (auto _ : state) {
    arena.execute([&] { r = registration::register_to_offset_model(c.offset, locator, c.raw); });
  }
  report(state, r, c);
}
BENCHMARK(BM_Register100k2Threads)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

void BM_Register100kWithIndexing2Threads(benchmark::State& state) {
  const Case& c = registration_case();
  tbb::task_arena arena(2);
  registration::RegistrationResult r;
  for (auto _ : state) {
    arena.execute([&] {
      r = registration::register_to_offset_model(c.offset, c.raw);
    });
  }
  report(state, r, c);
}
BENCHMARK(BM_Register100kWithIndexing2Threads)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

}  // namespace
