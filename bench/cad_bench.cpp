// CAD model benchmarks on the 4 MB impeller (277 trimmed faces): reading and indexing, and projecting
// 100 000 points around it on 2 threads ("find nominals"). On the repatch-hpdc part's elementary faces: closest
// points in closed form against the NURBS solver and OpenCASCADE on the same face, one core; and the whole model's
// locator with and without the closed forms.

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <Geom_Plane.hxx>
#include <gp_Ax3.hxx>

#include <map>
#include <mutex>
#include <random>

#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/plan.hpp"
#include "probecomp/simulation/random.hpp"

namespace {

using namespace probecomp;

const std::filesystem::path kImpeller = std::filesystem::path(PROBECOMP_BENCH_CAD_DIR) / "pyiges_impeller.igs";

// 100 000 points within ±2 mm of planned points, scattered sideways by up to 1 mm: every face gets its share.
std::vector<Point3> points_around(const cad::Model& model) {
  const std::vector<cad::PlannedPoint> plan = cad::plan_points(model, 2.0, {});
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<std::size_t> pick(0, plan.size() - 1);
  std::uniform_real_distribution<double> off(-2.0, 2.0), side(-1.0, 1.0);
  std::vector<Point3> out;
  for (int k = 0; k < 100'000; ++k) {
    const cad::PlannedPoint& p = plan[pick(rng)];
    const Vector3 aside = simulation::draw_vector(side, rng);  // before `off`: the order gcc drew them in one expression
    out.push_back(p.point + off(rng) * p.normal + aside);
  }
  return out;
}

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
  static const std::vector<Point3> points = points_around(model);
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

const std::filesystem::path kRepatch = std::filesystem::path(PROBECOMP_BENCH_CAD_DIR) / "asitus_repatch-hpdc.stp";

const cad::Model& repatch() {
  static const cad::Model model = cad::read_model(kRepatch);
  return model;
}

// The part's largest face of the kind, and 100 000 points within 5 mm of its control-net box.
struct ElementaryCase {
  const cad::Face* face = nullptr;
  std::vector<Point3> points;
};

const ElementaryCase& elementary_case(cad::ElementaryKind kind) {
  static std::map<cad::ElementaryKind, ElementaryCase> cases;
  static std::mutex m;
  std::lock_guard lock(m);
  ElementaryCase& c = cases[kind];
  if (c.face) return c;
  double largest = -1.0;
  for (const cad::Face& f : repatch().faces) {
    if (!f.analytic || f.analytic->surface().kind != kind) continue;
    const double size = nurbs::bounding_box(f.surface).diagonal();
    if (size > largest) largest = size, c.face = &f;
  }
  const BoundingBox box = nurbs::bounding_box(c.face->surface);
  std::mt19937_64 rng(5);
  for (int k = 0; k < 100'000; ++k) {
    Point3 p;
    for (int i = 0; i < 3; ++i) p[i] = std::uniform_real_distribution<double>(box.min[i] - 5.0, box.max[i] + 5.0)(rng);
    c.points.push_back(p);
  }
  return c;
}

void BM_ClosedFormClosestPoint(benchmark::State& state) {
  const ElementaryCase& c = elementary_case(static_cast<cad::ElementaryKind>(state.range(0)));
  std::size_t next = 0;
  for (auto _ : state) {
    for (int k = 0; k < 1000; ++k, next = next + 1 == c.points.size() ? 0 : next + 1) {
      benchmark::DoNotOptimize(c.face->analytic->closest_point(c.points[next]));
    }
  }
  state.SetItemsProcessed(state.iterations() * 1000);
  state.SetLabel(cad::to_string(c.face->analytic->surface().kind));
}
BENCHMARK(BM_ClosedFormClosestPoint)->Arg(static_cast<int>(cad::ElementaryKind::Plane))
    ->Arg(static_cast<int>(cad::ElementaryKind::Cylinder))->Arg(static_cast<int>(cad::ElementaryKind::Cone))
    ->Arg(static_cast<int>(cad::ElementaryKind::Sphere))->Arg(static_cast<int>(cad::ElementaryKind::Torus))
    ->MinTime(1.0);

// The same faces' NURBS through the global solver: what every elementary face cost before.
void BM_ClosedFormClosestPoint_NurbsSolver(benchmark::State& state) {
  const ElementaryCase& c = elementary_case(static_cast<cad::ElementaryKind>(state.range(0)));
  const nurbs::ClosestPointSolver solver(c.face->surface);
  std::size_t next = 0;
  for (auto _ : state) {
    for (int k = 0; k < 100; ++k, next = next + 1 == c.points.size() ? 0 : next + 1) {
      benchmark::DoNotOptimize(solver.closest_point(c.points[next]));
    }
  }
  state.SetItemsProcessed(state.iterations() * 100);
  state.SetLabel(cad::to_string(c.face->analytic->surface().kind));
}
BENCHMARK(BM_ClosedFormClosestPoint_NurbsSolver)->Arg(static_cast<int>(cad::ElementaryKind::Plane))
    ->Arg(static_cast<int>(cad::ElementaryKind::Cylinder))->MinTime(1.0);

// OpenCASCADE's projection onto the same plane and cylinder as elementary surfaces (its analytic extrema),
// bounded to the face's range.
void BM_ClosedFormClosestPoint_OCCT(benchmark::State& state) {
  const ElementaryCase& c = elementary_case(static_cast<cad::ElementaryKind>(state.range(0)));
  const cad::ElementarySurface& e = c.face->analytic->surface();
  const gp_Ax3 frame(gp_Pnt(e.origin.x(), e.origin.y(), e.origin.z()), gp_Dir(e.z.x(), e.z.y(), e.z.z()),
                     gp_Dir(e.x.x(), e.x.y(), e.x.z()));
  Handle(Geom_Surface) surface;
  if (e.kind == cad::ElementaryKind::Plane) surface = new Geom_Plane(frame);
  else surface = new Geom_CylindricalSurface(frame, e.radius);
  // The face's range in the elementary parameters: those of its NURBS's corners.
  const nurbs::Domain d = c.face->surface.domain();
  const auto [a0, b0] = e.parameters(nurbs::evaluate(c.face->surface, d.u0, d.v0));
  const auto [a1, b1] = e.parameters(nurbs::evaluate(c.face->surface, d.u1, d.v1));
  GeomAPI_ProjectPointOnSurf projector;
  projector.Init(surface, std::min(a0, a1), std::max(a0, a1), std::min(b0, b1), std::max(b0, b1));
  std::size_t next = 0;
  for (auto _ : state) {
    for (int k = 0; k < 100; ++k, next = next + 1 == c.points.size() ? 0 : next + 1) {
      const Point3& q = c.points[next];
      projector.Perform(gp_Pnt(q.x(), q.y(), q.z()));
      if (projector.NbPoints() > 0) benchmark::DoNotOptimize(projector.LowerDistance());
    }
  }
  state.SetItemsProcessed(state.iterations() * 100);
  state.SetLabel(cad::to_string(e.kind));
}
BENCHMARK(BM_ClosedFormClosestPoint_OCCT)->Arg(static_cast<int>(cad::ElementaryKind::Plane))
    ->Arg(static_cast<int>(cad::ElementaryKind::Cylinder))->MinTime(1.0);

// The whole part (232 faces, 107 elementary), 100 000 points around it, one thread: with the closed forms (1) and
// with every face searched as NURBS (0).
void BM_ProjectRepatch100k(benchmark::State& state) {
  static const cad::Model plain = [] {
    cad::Model m = repatch();
    for (cad::Face& f : m.faces) f.analytic = nullptr;
    return m;
  }();
  const cad::Model& model = state.range(0) ? repatch() : plain;
  const cad::ModelLocator locator(model);
  static const std::vector<Point3> points = points_around(repatch());
  tbb::task_arena arena(1);
  for (auto _ : state) {
    std::vector<cad::ModelPoint> r;
    arena.execute([&] { r = locator.closest_points(points); });
    benchmark::DoNotOptimize(r.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * points.size()));
  state.SetLabel(state.range(0) ? "closed forms" : "NURBS only");
}
BENCHMARK(BM_ProjectRepatch100k)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

}  // namespace
