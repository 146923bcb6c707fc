#include "probecomp/simulation/measure.hpp"

#include <tbb/parallel_for.h>

#include <cmath>
#include <random>

namespace probecomp::simulation {

namespace {

// Newton on the travel stops when a step is below this (mm); the touch is then accepted if the tip is within
// kTouchTolerance of the part. Far below any CMM's resolution.
constexpr double kTravelTolerance = 1e-11;
constexpr double kTouchTolerance = 1e-9;
constexpr int kMaxNewtonSteps = 60;
// Lines meeting the offset part at a grazing angle (cosine below this) are reported as missed, not solved.
constexpr double kGrazingCosine = 1e-3;

Touch touch(const cad::ModelLocator& actual, const ProgrammedPoint& programmed, double r) {
  Touch out;
  const Vector3 n0 = programmed.normal.normalized();
  double t = r;  // start where the tip would touch the nominal part
  cad::ModelPoint foot;
  for (int step = 0; step < kMaxNewtonSteps; ++step) {
    const Point3 c = programmed.point + t * n0;
    foot = step == 0 ? actual.closest_point(c) : actual.closest_point(c, foot);
    if (!foot.ok()) return out;
    // The gradient of the signed distance: the unit vector from the foot point, or the face normal when the
    // centre is on the part.
    const Vector3 g = std::abs(foot.distance) > 1e-12 ? Vector3((c - foot.point) / foot.distance) : foot.normal;
    const double slope = g.dot(n0);
    if (slope < kGrazingCosine) return out;
    const double dt = -(foot.distance - r) / slope;
    t += dt;
    if (std::abs(dt) < kTravelTolerance) {
      const Point3 centre = programmed.point + t * n0;
      const cad::ModelPoint last = actual.closest_point(centre, foot);
      if (!last.ok() || std::abs(last.distance - r) > kTouchTolerance) return out;
      const bool edge = last.on_trim_edge || last.status == nurbs::ClosestPointStatus::OnBoundary;
      out.status = edge ? Touch::Status::Edge : Touch::Status::OK;
      out.centre = centre;
      out.measured = centre;
      out.contact = last.point;
      out.normal = edge ? Vector3((centre - last.point).normalized()) : last.normal;
      out.face = last.face;
      out.u = last.u;
      out.v = last.v;
      out.travel = t;
      return out;
    }
  }
  return out;
}

// Programmed points at fractions (a, b) of the face's (u, v) domain.
std::vector<ProgrammedPoint> plan_at(const cad::Face& face, const std::vector<std::pair<double, double>>& ab) {
  const nurbs::Domain d = face.surface.domain();
  std::vector<ProgrammedPoint> out;
  out.reserve(ab.size());
  for (const auto& [a, b] : ab) {
    const double u = d.u0 + a * (d.u1 - d.u0), v = d.v0 + b * (d.v1 - d.v0);
    const nurbs::UnitNormal n = nurbs::unit_normal(face.surface, u, v);
    out.push_back({nurbs::evaluate(face.surface, u, v), static_cast<double>(face.outward) * n.n, face.index});
  }
  return out;
}

}  // namespace

std::vector<ProgrammedPoint> grid_plan(const cad::Face& face, int nu, int nv, PlanMargin margin) {
  std::vector<std::pair<double, double>> ab;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      ab.emplace_back(margin.u + (1.0 - 2.0 * margin.u) * (nu > 1 ? static_cast<double>(i) / (nu - 1) : 0.5),
                      margin.v + (1.0 - 2.0 * margin.v) * (nv > 1 ? static_cast<double>(j) / (nv - 1) : 0.5));
    }
  }
  return plan_at(face, ab);
}

std::vector<ProgrammedPoint> random_plan(const cad::Face& face, int n, std::uint64_t seed, PlanMargin margin) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> a(margin.u, 1.0 - margin.u), b(margin.v, 1.0 - margin.v);
  std::vector<std::pair<double, double>> ab;
  for (int k = 0; k < n; ++k) {
    const double x = a(rng), y = b(rng);  // in this order: the same draws as before margins per direction
    ab.emplace_back(x, y);
  }
  return plan_at(face, ab);
}

std::vector<ProgrammedPoint> scan_line_plan(const cad::Face& face, int lines, int per_line, bool along_u,
                                            PlanMargin margin) {
  const double ma = along_u ? margin.u : margin.v, mb = along_u ? margin.v : margin.u;
  std::vector<std::pair<double, double>> ab;
  ab.reserve(static_cast<std::size_t>(std::max(lines, 0)) * static_cast<std::size_t>(std::max(per_line, 0)));
  for (int l = 0; l < lines; ++l) {
    const double b = mb + (1.0 - 2.0 * mb) * (lines > 1 ? static_cast<double>(l) / (lines - 1) : 0.5);
    for (int k = 0; k < per_line; ++k) {
      const int along = l % 2 == 0 ? k : per_line - 1 - k;
      const double a = ma + (1.0 - 2.0 * ma) * (per_line > 1 ? static_cast<double>(along) / (per_line - 1) : 0.5);
      if (along_u) {
        ab.emplace_back(a, b);
      } else {
        ab.emplace_back(b, a);
      }
    }
  }
  return plan_at(face, ab);
}

const char* to_string(Touch::Status s) {
  switch (s) {
    case Touch::Status::OK: return "ok";
    case Touch::Status::Edge: return "edge";
    case Touch::Status::Missed: return "missed";
  }
  return "?";
}

std::vector<Touch> simulate_touches(const cad::ModelLocator& actual, std::span<const ProgrammedPoint> plan,
                                    const MeasurementOptions& options) {
  std::vector<Touch> out(plan.size());
  tbb::parallel_for(std::size_t{0}, plan.size(),
                    [&](std::size_t k) {
                      out[k] = touch(actual, plan[k], options.probe_radii.empty() ? options.probe_radius : options.probe_radii.at(k));
                    });
  if (!options.pretravel.none()) {
    for (std::size_t k = 0; k < out.size(); ++k) {
      if (out[k].status == Touch::Status::Missed) continue;
      const Vector3 d = -plan[k].normal.normalized();
      out[k].measured = out[k].centre + options.pretravel(d) * d;
    }
  }
  if (options.noise_sigma > 0.0) {
    std::mt19937_64 rng(options.seed);
    std::normal_distribution<double> noise(0.0, options.noise_sigma);
    for (Touch& t : out) {
      // Drawn for every point, touched or not, so that one point's noise does not depend on another's touch.
      const Vector3 e(noise(rng), noise(rng), noise(rng));
      if (t.status != Touch::Status::Missed) t.measured += e;
    }
  }
  return out;
}

cad::Model actual_model(const cad::Model& nominal, const Deformation& deformation,
                        const geometry::RigidTransform& placement) {
  cad::Model out = nominal;
  for (cad::Face& face : out.faces) {
    face.surface = nurbs::transformed(deformed_surface(face.surface, face.outward, deformation), placement);
    face.analytic = nullptr;  // deformed, the face is no longer the file's plane or cylinder
  }
  return out;
}

}  // namespace probecomp::simulation
