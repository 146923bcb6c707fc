#include "studies/freeform_study.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "cad/locator.hpp"

namespace probecomp::studies {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Signed distance of each computed, trusted point from the actual part.
std::vector<double> errors_against(const cad::ModelLocator& actual, const compensation::CompensationResult& r) {
  std::vector<Point3> pts;
  std::vector<std::size_t> index;
  for (std::size_t k = 0; k < r.points.size(); ++k) {
    if (r.points[k].status == compensation::PointStatus::Ok) {
      pts.push_back(r.points[k].contact);
      index.push_back(k);
    }
  }
  std::vector<double> e(r.points.size(), std::numeric_limits<double>::quiet_NaN());
  const std::vector<cad::ModelPoint> feet = actual.closest_points(pts);
  for (std::size_t i = 0; i < feet.size(); ++i) {
    if (feet[i].ok()) e[index[i]] = feet[i].distance;
  }
  return e;
}

}  // namespace

ErrorSummary summarise(const std::vector<double>& errors) {
  ErrorSummary s;
  double sum = 0.0;
  s.min = std::numeric_limits<double>::infinity();
  s.max = -s.min;
  for (double e : errors) {
    if (std::isnan(e)) continue;
    ++s.points;
    sum += e;
    s.min = std::min(s.min, e);
    s.max = std::max(s.max, e);
  }
  if (s.points == 0) return {};
  s.mean = sum / s.points;
  double ss = 0.0;
  for (double e : errors) {
    if (!std::isnan(e)) ss += (e - s.mean) * (e - s.mean);
  }
  s.std = s.points > 1 ? std::sqrt(ss / (s.points - 1)) : 0.0;
  return s;
}

FreeformStudyResult run_freeform_study(const FreeformStudyOptions& options) {
  FreeformStudyResult out;
  out.freeform = simulation::paper_freeform_case(options.reversed);
  if (options.noise_sigma >= 0.0) out.freeform.noise_sigma = options.noise_sigma;
  const simulation::FreeformCase& c = out.freeform;
  auto t0 = Clock::now();
  if (options.random_points > 0) {
    out.plan = simulation::random_plan(c.nominal, options.random_points, options.seed + 1000);
  } else {
    // The grid runs 120 along the panel's 100 mm and 60 along its 50 mm whichever way the surface is parametrised.
    out.plan = options.reversed ? simulation::grid_plan(c.nominal, c.grid_v, c.grid_u)
                                : simulation::grid_plan(c.nominal, c.grid_u, c.grid_v);
  }
  if (options.shuffle) {
    std::mt19937_64 rng(options.seed + 2000);
    std::shuffle(out.plan.begin(), out.plan.end(), rng);
  }
  const cad::Model actual = simulation::actual_model(c.nominal, c.deformation, c.placement);
  const cad::ModelLocator actual_locator(actual);
  out.touches = simulation::simulate_touches(
      actual_locator, out.plan, {.probe_radius = c.probe_radius, .noise_sigma = c.noise_sigma, .seed = options.seed});
  out.simulate_seconds = since(t0);

  std::vector<Point3> raw;
  std::vector<Vector3> normals;
  for (std::size_t k = 0; k < out.touches.size(); ++k) {
    raw.push_back(out.touches[k].measured);
    normals.push_back(out.plan[k].normal);
  }
  compensation::CompensateOptions o = options.compensate;
  o.method = compensation::Method::Cad;
  o.probe_radius = c.probe_radius;
  t0 = Clock::now();
  out.cad = compensation::compensate(c.nominal, raw,
                                     options.approach_normals ? std::optional<std::span<const Vector3>>(normals)
                                                              : std::nullopt,
                                     o);
  out.cad_seconds = since(t0);
  o.method = compensation::Method::Conventional;
  t0 = Clock::now();
  out.conventional = compensation::compensate(c.nominal, raw, std::span<const Vector3>(normals), o);
  out.conventional_seconds = since(t0);

  out.cad_error = errors_against(actual_locator, out.cad);
  out.conventional_error = errors_against(actual_locator, out.conventional);
  out.cad_summary = summarise(out.cad_error);
  out.conventional_summary = summarise(out.conventional_error);
  return out;
}

PaperTable2 paper_table2() {
  PaperTable2 t;
  t.conventional = {.points = 7200, .std = 0.045965, .mean = 0.018314, .min = -0.049, .max = 0.279};
  t.proposed = {.points = 7200, .std = 0.012947, .mean = 0.003014, .min = -0.055, .max = 0.094};
  return t;
}

}  // namespace probecomp::studies
