#include "probecomp/studies/approach_angle_study.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <tuple>

#include "probecomp/cad/locator.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/fitting/elements.hpp"
#include "probecomp/geometry/stopwatch.hpp"
#include "probecomp/simulation/reference_sphere.hpp"
#include "probecomp/studies/analytic_cylinder.hpp"
#include "probecomp/studies/cylinder_study.hpp"

namespace probecomp::studies {

namespace {

constexpr double kRadiansPerDegree = std::numbers::pi / 180.0;
// The arc reaches 30° beyond the planned angles on either side: a 2 mm shift along z moves the contact of a
// horizontal touch about 10.5° round the actual circle (asin(dy / (R + r))), and the tip must not reach an edge.
constexpr double kArcBeyondDeg = 30.0;
// Where the qualification sphere and the probing test's stand in the machine (mm).
const Point3 kQualificationSphere(400.0, 250.0, 80.0);
const Point3 kProbingTestSphere(-150.0, 320.0, 45.0);

// ISO 10360-5: the sphere fitted (least squares) to the contact points; P_FTU is the range of their radial
// distances from its centre, P_STU its diameter minus the sphere's.
std::pair<double, double> form_and_size(const std::vector<Point3>& contacts, double diameter) {
  const fitting::SphereFit f = fitting::fit_sphere(contacts);
  if (f.status != fitting::ElementFitStatus::OK) {
    return {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Point3& p : contacts) {
    const double d = (p - f.center).norm();
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  return {hi - lo, 2.0 * f.radius - diameter};
}

ProbingTest probing_test(const ApproachAngleStudyOptions& o, const probe::StylusQualification& q) {
  const simulation::SphereTouches t =
      simulation::touch_reference_sphere(kProbingTestSphere, o.sphere_diameter / 2.0, o.probe_radius,
                                         simulation::iso10360_5_normals(), o.probe, o.sphere_noise, o.seed + 2);
  std::vector<Point3> plain, model;
  for (std::size_t k = 0; k < t.centres.size(); ++k) {
    const Vector3& n = t.normals[k];
    plain.push_back(t.centres[k] - q.effective_radius * n);
    model.push_back(t.centres[k] - probe::effective_radius(q, -n).radius * n);
  }
  ProbingTest p;
  p.touches = static_cast<int>(t.centres.size());
  std::tie(p.form_plain, p.size_plain) = form_and_size(plain, o.sphere_diameter);
  std::tie(p.form_model, p.size_model) = form_and_size(model, o.sphere_diameter);
  return p;
}

double deviation(const compensation::CompensationResult& r, std::size_t k) {
  const compensation::CompensatedPoint& p = r.points.at(k);
  return p.status == compensation::PointStatus::Ok ? p.deviation : std::numeric_limits<double>::quiet_NaN();
}

template <class Value>
void over_bins(const std::vector<ApproachAngleBin>& bins, ErrorSummary ApproachAngleBin::*method, Value&& value) {
  for (const ApproachAngleBin& b : bins) {
    if ((b.*method).points > 0) value(b.*method);
  }
}

}  // namespace

double ApproachAngleStudyResult::worst_bin_mean(ErrorSummary ApproachAngleBin::*method) const {
  double worst = 0.0;
  over_bins(bins, method, [&](const ErrorSummary& s) { worst = std::max(worst, std::abs(s.mean)); });
  return worst;
}

double ApproachAngleStudyResult::worst_bin_std(ErrorSummary ApproachAngleBin::*method) const {
  double worst = 0.0;
  over_bins(bins, method, [&](const ErrorSummary& s) { worst = std::max(worst, s.std); });
  return worst;
}

double ApproachAngleStudyResult::bin_mean_spread(ErrorSummary ApproachAngleBin::*method) const {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  over_bins(bins, method, [&](const ErrorSummary& s) {
    lo = std::min(lo, s.mean);
    hi = std::max(hi, s.mean);
  });
  return hi >= lo ? hi - lo : 0.0;
}

ApproachAngleStudyResult run_approach_angle_study(const ApproachAngleStudyOptions& o) {
  const geometry::Stopwatch clock;
  ApproachAngleStudyResult out;

  // 1. The stylus qualified on the reference sphere, with the probe it will measure with.
  const simulation::SphereTouches sphere = simulation::touch_reference_sphere(
      kQualificationSphere, o.sphere_diameter / 2.0, o.probe_radius,
      simulation::sphere_cap_normals(o.sphere_touches, o.sphere_lowest_deg), o.probe, o.sphere_noise, o.seed + 1);
  out.qualification = probe::qualify_stylus("T1", sphere.centres, sphere.normals, o.sphere_diameter);
  probe::Qualification qualification;
  qualification.styli.push_back(out.qualification);

  // 2. The section touched at each approach angle, section by section.
  SimulatedMeasurement m;
  m.nominal = cylinder_part({.radius = o.cylinder_radius,
                             .arc_start = -kArcBeyondDeg,
                             .arc_end = 180.0 + kArcBeyondDeg,
                             .length = o.length});
  m.placement = geometry::from_pose({.t = Vector3(0.0, 0.0, o.misalignment)});
  m.probe_radius = o.probe_radius;
  m.noise_sigma = o.part_noise;
  m.seed = o.seed;
  m.pretravel = o.probe;
  std::vector<double> thetas;
  for (int s = 0; s < o.sections; ++s) {
    const double x = o.length * 0.8 * (o.sections > 1 ? static_cast<double>(s) / (o.sections - 1) - 0.5 : 0.0);
    for (int k = 0; k < o.angles; ++k) {
      const double theta = o.angles > 1 ? 180.0 * k / (o.angles - 1) : 90.0;
      const Vector3 n(0.0, std::cos(theta * kRadiansPerDegree), std::sin(theta * kRadiansPerDegree));
      m.plan.push_back({Point3(x, 0.0, 0.0) + o.cylinder_radius * n, n, 0});
      thetas.push_back(theta);
    }
  }
  const MethodComparison c = compare_methods(m);

  // 3. The same touches by the CAD method with the qualification.
  std::vector<Point3> raw;
  std::vector<Vector3> normals;
  for (std::size_t k = 0; k < c.touches.size(); ++k) {
    raw.push_back(c.touches[k].measured);
    normals.push_back(m.plan[k].normal);
  }
  compensation::CompensateOptions q;
  q.method = compensation::Method::Cad;
  q.probe_radius = o.probe_radius;
  q.qualification = &qualification;
  q.accept_doubtful_registration = true;  // as compare_methods: scored against the truth, not refused
  const compensation::CompensationResult qualified =
      compensation::compensate(m.nominal, raw, std::span<const Vector3>(normals), q);
  const cad::Model actual = simulation::actual_model(m.nominal, m.deformation, m.placement);
  const std::vector<double> qualified_error = errors_against(cad::ModelLocator(actual), qualified);
  out.cad_untrusted = static_cast<int>(c.touches.size()) - c.cad.count(compensation::PointStatus::Ok);
  out.qualified_untrusted = static_cast<int>(c.touches.size()) - qualified.count(compensation::PointStatus::Ok);

  // 4. Each touch and the bins.
  const CircleCase circle{.R = o.cylinder_radius, .r = o.probe_radius, .dy = o.misalignment};
  for (std::size_t k = 0; k < thetas.size(); ++k) {
    out.touches.push_back({.theta_deg = thetas[k],
                           .pretravel = o.probe(-m.plan[k].normal),
                           .analytic = conventional_touch(circle, thetas[k]).error,
                           .conventional = c.conventional_error[k],
                           .cad = c.cad_error[k],
                           .qualified = qualified_error[k],
                           .cad_deviation = deviation(c.cad, k),
                           .qualified_deviation = deviation(qualified, k)});
  }
  const double width = 180.0 / o.bins;
  for (int b = 0; b < o.bins; ++b) {
    ApproachAngleBin bin;
    bin.theta_from = b * width;
    bin.theta_to = (b + 1) * width;
    std::vector<double> conventional, cad, with_model, cad_deviation, qualified_deviation;
    double analytic = 0.0, pretravel = 0.0;
    for (const ApproachAngleTouch& t : out.touches) {
      if (std::min(o.bins - 1, static_cast<int>(t.theta_deg / width)) != b) continue;
      conventional.push_back(t.conventional);
      cad.push_back(t.cad);
      with_model.push_back(t.qualified);
      cad_deviation.push_back(t.cad_deviation);
      qualified_deviation.push_back(t.qualified_deviation);
      analytic += t.analytic;
      pretravel += t.pretravel;
    }
    if (conventional.empty()) continue;
    bin.conventional = summarise(conventional);
    bin.cad = summarise(cad);
    bin.qualified = summarise(with_model);
    bin.cad_deviation = summarise(cad_deviation);
    bin.qualified_deviation = summarise(qualified_deviation);
    bin.analytic = analytic / static_cast<double>(conventional.size());
    bin.pretravel = pretravel / static_cast<double>(conventional.size());
    out.bins.push_back(bin);
  }

  // 5. ISO 10360-5 on a second sphere.
  out.probing = probing_test(o, out.qualification);
  out.seconds = clock.seconds();
  return out;
}

}  // namespace probecomp::studies
