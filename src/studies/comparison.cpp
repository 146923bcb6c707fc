#include "probecomp/studies/comparison.hpp"

#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include "probecomp/error.hpp"
#include "probecomp/geometry/stopwatch.hpp"

namespace probecomp::studies {

namespace {


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

std::vector<double> errors_against(const cad::ModelLocator& part, const compensation::CompensationResult& r) {
  std::vector<Point3> pts;
  std::vector<std::size_t> index;
  for (std::size_t k = 0; k < r.points.size(); ++k) {
    if (r.points[k].status == compensation::PointStatus::Ok) {
      pts.push_back(r.points[k].contact);
      index.push_back(k);
    }
  }
  std::vector<double> e(r.points.size(), std::numeric_limits<double>::quiet_NaN());
  const std::vector<cad::ModelPoint> feet = part.closest_points(pts);
  for (std::size_t i = 0; i < feet.size(); ++i) {
    if (feet[i].ok()) e[index[i]] = feet[i].distance;
  }
  return e;
}

namespace {

std::vector<simulation::Touch> touches_on(const cad::ModelLocator& actual, const SimulatedMeasurement& m) {
  std::vector<simulation::Touch> touches = simulation::simulate_touches(
      actual, m.plan,
      {.probe_radius = m.probe_radius, .probe_radii = m.probe_radii, .noise_sigma = m.noise_sigma, .seed = m.seed,
       .pretravel = m.pretravel});
  if (m.repeats_are_copies) {
    for (std::size_t k = 1; k < touches.size(); ++k) {
      if (m.plan[k].point == m.plan[k - 1].point && m.plan[k].normal == m.plan[k - 1].normal) {
        touches[k] = touches[k - 1];
      }
    }
  }
  for (std::size_t k = 0; k < touches.size(); ++k) {
    if (touches[k].status == simulation::Touch::Status::Missed) {
      throw InputError("simulated measurement: programmed point " + std::to_string(k + 1) +
                                  " misses the actual part");
    }
  }
  return touches;
}

}  // namespace

std::vector<simulation::Touch> simulate_measurement(const SimulatedMeasurement& m) {
  const cad::Model actual = simulation::actual_model(m.nominal, m.deformation, m.placement);
  return touches_on(cad::ModelLocator(actual), m);
}

MethodComparison compare_methods(const SimulatedMeasurement& m, const ComparisonOptions& options) {
  MethodComparison out;
  geometry::Stopwatch clock;
  const cad::Model actual = simulation::actual_model(m.nominal, m.deformation, m.placement);
  const cad::ModelLocator actual_locator(actual);
  out.touches = touches_on(actual_locator, m);
  out.simulate_seconds = clock.restart();

  std::vector<Point3> raw;
  std::vector<Vector3> normals;
  for (std::size_t k = 0; k < out.touches.size(); ++k) {
    raw.push_back(out.touches[k].measured);
    normals.push_back(m.plan[k].normal);
  }
  compensation::CompensateOptions o = options.compensate;
  o.method = compensation::Method::Cad;
  o.probe_radius = m.probe_radius;
  o.probe_radii = m.probe_radii;
  // A study's deformations are deliberate (the cylinder's 1.5 mm sine against r = 1 mm): a registration they
  // leave doubtful is scored against the truth, not refused.
  o.accept_doubtful_registration = true;
  clock.restart();
  out.cad = compensation::compensate(m.nominal, raw,
                                     options.approach_normals ? std::optional<std::span<const Vector3>>(normals)
                                                              : std::nullopt,
                                     o);
  out.cad_seconds = clock.restart();
  o.method = compensation::Method::Conventional;
  out.conventional = compensation::compensate(m.nominal, raw, std::span<const Vector3>(normals), o);
  out.conventional_seconds = clock.restart();

  out.cad_error = errors_against(actual_locator, out.cad);
  out.conventional_error = errors_against(actual_locator, out.conventional);
  out.cad_summary = summarise(out.cad_error);
  out.conventional_summary = summarise(out.conventional_error);
  return out;
}

}  // namespace probecomp::studies
