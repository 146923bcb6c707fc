// Point files in and out at scanning sizes (issue 24), one thread:
//   BM_WriteCompensatedCsv1M   results::compensated_csv of 1 000 000 computed rows (x,y,z,nx,ny,nz,deviation,u,face,status)
//   BM_ReadPointCsv1M          io::read_point_csv of a 1 000 000-row x,y,z,i,j,k file (about 90 MB), from the page cache
// The text is built in memory; writing it to disk is the file system's (io::OutputFiles).

#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/results/files.hpp"
#include "probecomp/results/statistics.hpp"
#include "probecomp/simulation/random.hpp"

namespace {

using namespace probecomp;

constexpr int kRows = 1'000'000;

compensation::CompensationResult rows() {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> x(-60.0, 60.0), d(-0.05, 0.05);
  compensation::CompensationResult r;
  r.points.resize(kRows);
  for (compensation::CompensatedPoint& p : r.points) {
    p.status = compensation::PointStatus::Ok;
    p.contact = simulation::draw_vector(x, rng).cwiseProduct(Vector3(1.0, 1.0, 0.1));
    const double ny = d(rng), nx = d(rng);  // as gcc drew them as the constructor's arguments
    p.normal = Vector3(nx, ny, 1.0).normalized();
    p.deviation = d(rng);
    p.uncertainty = 0.001 + 0.01 * std::abs(d(rng));
    p.face = 0;
    p.radius = 1.0;
  }
  return r;
}

void BM_WriteCompensatedCsv1M(benchmark::State& state) {
  const compensation::CompensationResult r = rows();
  io::PointTable table;
  table.columns = {"x", "y", "z", "i", "j", "k"};
  std::size_t bytes = 0;
  for (auto _ : state) {
    const std::string text = results::compensated_csv(table, r);
    bytes = text.size();
    benchmark::DoNotOptimize(text.data());
  }
  state.counters["MB"] = static_cast<double>(bytes) / 1e6;
  state.counters["rows_per_s"] = benchmark::Counter(kRows, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_ReadPointCsv1M(benchmark::State& state) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "probecomp_bench_1m.csv";
  {
    const compensation::CompensationResult r = rows();
    std::ofstream out(path);
    out << "x,y,z,i,j,k\n";
    char line[200];
    for (const compensation::CompensatedPoint& p : r.points) {
      std::snprintf(line, sizeof line, "%.9f,%.9f,%.9f,%.12f,%.12f,%.12f\n", p.contact.x(), p.contact.y(), p.contact.z(),
                    p.normal.x(), p.normal.y(), p.normal.z());
      out << line;
    }
  }
  std::size_t n = 0;
  for (auto _ : state) {
    const io::PointTable t = io::read_point_csv(path);
    n = t.points.size();
    benchmark::DoNotOptimize(t.points.data());
  }
  std::filesystem::remove(path);
  state.counters["rows"] = static_cast<double>(n);
  state.counters["rows_per_s"] = benchmark::Counter(kRows, benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

BENCHMARK(BM_WriteCompensatedCsv1M)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(BM_ReadPointCsv1M)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
