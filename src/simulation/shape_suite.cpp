#include "probecomp/simulation/shape_suite.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "probecomp/nurbs/constructors.hpp"
#include "probecomp/simulation/freeform_case.hpp"
#include "probecomp/simulation/random.hpp"

namespace probecomp::simulation {

namespace {

// 8 × 7 control points over 80 × 70 mm on non-uniform knots, weights 1: a crown of 8 mm, a cross wave of 1.5 mm and
// a twist, curvature radii above 50 mm; a different parametrisation, size and shape from the paper's panel.
nurbs::Surface hood_surface() {
  nurbs::KnotVector U({0, 0, 0, 0, 0.18, 0.4, 0.58, 0.8, 1, 1, 1, 1}, 3);
  nurbs::KnotVector V({0, 0, 0, 0, 0.3, 0.55, 0.8, 1, 1, 1, 1}, 3);
  std::vector<Point3> P;
  for (int i = 0; i < U.num_basis(); ++i) {
    for (int j = 0; j < V.num_basis(); ++j) {
      const double x = -40.0 + 80.0 * U.greville(i);
      const double y = -35.0 + 70.0 * V.greville(j);
      const double z = 8.0 * std::cos(std::numbers::pi * x / 110.0) * std::cos(std::numbers::pi * y / 90.0) +
                       1.5 * std::sin(2.0 * std::numbers::pi * x / 60.0) * std::sin(2.0 * std::numbers::pi * y / 70.0) +
                       0.002 * x * y;
      P.emplace_back(x, y, z);
    }
  }
  return nurbs::Surface(std::move(U), std::move(V), P, {});
}

// The unit tangent at (u, v) (fractions of the domain) at `angle` degrees from S_u towards S_v.
Vector3 tangent_at(const nurbs::Surface& s, double u, double v, double angle) {
  const nurbs::Domain d = s.domain();
  const double pu = d.u0 + u * (d.u1 - d.u0), pv = d.v0 + v * (d.v1 - d.v0);
  const nurbs::SurfaceD1 D = nurbs::derivatives_d1(s, pu, pv);
  const Vector3 eu = D.Su.normalized();
  const Vector3 ev = D.Su.cross(D.Sv).normalized().cross(eu);
  return std::cos(angle * kDegree) * eu + std::sin(angle * kDegree) * ev;
}

Point3 point_at(const nurbs::Surface& s, double u, double v) {
  const nurbs::Domain d = s.domain();
  return nurbs::evaluate(s, d.u0 + u * (d.u1 - d.u0), d.v0 + v * (d.v1 - d.v0));
}

FeatureSpec bump(double u, double v, double amplitude, double width) {
  return {.kind = FeatureSpec::Kind::Bump, .u = u, .v = v, .amplitude = amplitude, .size = width};
}
FeatureSpec wave(double u, double v, double angle, double amplitude, double wavelength, double window = 0.0,
                 bool band = false, double band_angle = 0.0) {
  return {.kind = FeatureSpec::Kind::Wave, .u = u, .v = v, .angle = angle, .amplitude = amplitude,
          .size = wavelength, .window = window, .band = band, .band_angle = band_angle};
}
FeatureSpec crease(double u, double v, double angle, double height, double width) {
  return {.kind = FeatureSpec::Kind::Crease, .u = u, .v = v, .angle = angle, .amplitude = height, .size = width};
}
FeatureSpec twist(double u, double v, double angle, double amplitude, double length) {
  return {.kind = FeatureSpec::Kind::Twist, .u = u, .v = v, .angle = angle, .amplitude = amplitude, .size = length};
}

ShapeCase make_case(BaseSurface base, Sampling sampling, double sigma_um, std::vector<FeatureSpec> features,
                    std::uint64_t seed) {
  ShapeCase c;
  c.base = base;
  c.sampling = sampling;
  c.noise_sigma = sigma_um * 1e-3;
  c.features = std::move(features);
  c.seed = seed;
  // A misalignment of up to 1.5° and 0.5 mm that differs from case to case (the registration's coarse stage and
  // ICP take it; it is not what the suite judges).
  std::mt19937_64 rng(seed * 7919 + 17);
  std::uniform_real_distribution<double> angle(-1.5, 1.5), shift(-0.5, 0.5);
  c.rx = angle(rng);
  c.ry = angle(rng);
  c.rz = 0.3 * angle(rng);
  c.t = draw_vector(shift, rng);
  return c;
}

}  // namespace

const char* to_string(BaseSurface b) {
  switch (b) {
    case BaseSurface::Panel: return "panel";
    case BaseSurface::Hood: return "hood";
    case BaseSurface::Cylinder: return "cylinder";
  }
  return "?";
}

const char* to_string(Sampling s) {
  switch (s) {
    case Sampling::Grid: return "grid";
    case Sampling::Random: return "random";
    case Sampling::ScanLines: return "scan";
  }
  return "?";
}

cad::Model base_model(BaseSurface b) {
  cad::Model m;
  m.file_units = "mm";
  nurbs::Surface s = b == BaseSurface::Panel ? paper_panel()
                     : b == BaseSurface::Hood ? hood_surface()
                                              : nurbs::make_cylinder_section(Point3::Zero(), Vector3::UnitX(),
                                                                             Vector3::UnitZ(), 40.0, 40.0 * kDegree,
                                                                             140.0 * kDegree, 60.0);
  m.path = std::string("built-in ") + to_string(b);
  m.faces.push_back(cad::Face{.index = 0, .name = to_string(b), .source_type = "bspline", .surface = std::move(s),
                              .trim = nullptr, .outward = 1, .material_known = false, .exact = true});
  return m;
}

std::string describe(const FeatureSpec& f) {
  char text[160];
  switch (f.kind) {
    case FeatureSpec::Kind::Bump:
      std::snprintf(text, sizeof text, "%s %.0f um sd %.1f mm", f.amplitude < 0 ? "dent" : "bulge",
                    std::abs(f.amplitude) * 1e3, f.size);
      break;
    case FeatureSpec::Kind::Wave:
      if (f.window > 0.0) {
        std::snprintf(text, sizeof text, "wave %.0f um L %.0f mm at %.0f deg, %s %.0f mm", f.amplitude * 1e3, f.size,
                      f.angle, f.band ? "band" : "window", f.window);
      } else {
        std::snprintf(text, sizeof text, "wave %.0f um L %.0f mm at %.0f deg, whole face", f.amplitude * 1e3, f.size,
                      f.angle);
      }
      break;
    case FeatureSpec::Kind::Crease:
      std::snprintf(text, sizeof text, "crease %.0f um over %.1f mm at %.0f deg", f.amplitude * 1e3, f.size, f.angle);
      break;
    case FeatureSpec::Kind::Twist:
      std::snprintf(text, sizeof text, "%s %.0f um at %.0f mm", std::fmod(std::abs(f.angle), 90.0) == 45.0 ? "saddle" : "twist",
                    f.amplitude * 1e3, f.size);
      break;
  }
  return text;
}

double length_along(const nurbs::Surface& s, bool along_u) {
  const nurbs::Domain d = s.domain();
  constexpr int kSteps = 200;
  double length = 0.0;
  Point3 previous = Point3::Zero();
  for (int k = 0; k <= kSteps; ++k) {
    const double f = static_cast<double>(k) / kSteps;
    const Point3 x = along_u ? nurbs::evaluate(s, d.u0 + f * (d.u1 - d.u0), 0.5 * (d.v0 + d.v1))
                             : nurbs::evaluate(s, 0.5 * (d.u0 + d.u1), d.v0 + f * (d.v1 - d.v0));
    if (k > 0) length += (x - previous).norm();
    previous = x;
  }
  return length;
}

geometry::RigidTransform ShapeCase::placement() const {
  return geometry::from_pose({.rx = rx, .ry = ry, .rz = rz, .t = t});
}

Deformation deformation_of(const ShapeCase& c, const cad::Model& nominal) {
  const nurbs::Surface& s = nominal.faces.at(0).surface;
  Deformation d;
  for (const FeatureSpec& f : c.features) {
    const Point3 o = point_at(s, f.u, f.v);
    const Vector3 a = tangent_at(s, f.u, f.v, f.angle);
    const Vector3 b = tangent_at(s, f.u, f.v, f.angle + 90.0);
    switch (f.kind) {
      case FeatureSpec::Kind::Bump: d.bumps.push_back({.centre = o, .amplitude = f.amplitude, .width = f.size}); break;
      case FeatureSpec::Kind::Wave:
        d.sinusoids.push_back({.amplitude = f.amplitude, .wavelength = f.size, .direction = a, .origin = o,
                               .window = f.window, .phase = 90.0,
                               .band = f.band ? tangent_at(s, f.u, f.v, f.angle + f.band_angle) : Vector3::Zero()});
        break;
      case FeatureSpec::Kind::Crease:
        d.creases.push_back({.origin = o, .direction = a, .height = f.amplitude, .width = f.size});
        break;
      case FeatureSpec::Kind::Twist:
        d.twists.push_back({.origin = o, .first = a, .second = b, .amplitude = f.amplitude, .length = f.size});
        break;
    }
  }
  return d;
}

std::vector<ProgrammedPoint> plan_of(const ShapeCase& c, const cad::Model& nominal) {
  const cad::Face& face = nominal.faces.at(0);
  const double lu = length_along(face.surface, true), lv = length_along(face.surface, false);
  const PlanMargin margin{};
  switch (c.sampling) {
    case Sampling::Grid: {
      const int nu = std::max(2, static_cast<int>(std::lround(std::sqrt(c.points * lu / lv))));
      const int nv = std::max(2, static_cast<int>(std::lround(static_cast<double>(c.points) / nu)));
      return grid_plan(face, nu, nv, margin);
    }
    case Sampling::Random: {
      std::vector<ProgrammedPoint> plan = random_plan(face, c.points, c.seed + 1000, margin);
      std::mt19937_64 rng(c.seed + 2000);
      std::shuffle(plan.begin(), plan.end(), rng);
      return plan;
    }
    case Sampling::ScanLines: {
      // Lines across the longer direction would be few and long: they run along it, `line_spacing` apart across.
      const bool along_u = lu >= lv;
      const double across = (along_u ? lv * (1.0 - 2.0 * margin.v) : lu * (1.0 - 2.0 * margin.u));
      const int lines = std::max(2, static_cast<int>(std::lround(across / c.line_spacing)) + 1);
      const int per_line = std::max(2, c.points / lines);
      return scan_line_plan(face, lines, per_line, along_u, margin);
    }
  }
  return {};
}

std::vector<ShapeCase> shape_suite() {
  using B = BaseSurface;
  using S = Sampling;
  // The ridge-and-dent panel: a band of four ridges 0.12 mm high and a 3.5 mm dent.
  const std::vector<FeatureSpec> ridge_dent{wave(0.35, 0.5, 0.0, 0.12, 10.0, 6.0, true), bump(0.72, 0.3, -0.5, 1.5)};
  const std::vector<FeatureSpec> crease_ripple_saddle{crease(0.5, 0.5, 30.0, 0.15, 2.0), wave(0.5, 0.5, 60.0, 0.015, 12.0),
                                                      twist(0.5, 0.5, 45.0, 0.1, 40.0)};
  const std::vector<FeatureSpec> twisted_dents_eggcrate{twist(0.5, 0.5, 0.0, 0.2, 35.0), bump(0.3, 0.3, -0.3, 2.0),
                                                        bump(0.7, 0.65, -0.15, 1.0), wave(0.5, 0.5, 0.0, 0.02, 15.0),
                                                        wave(0.5, 0.5, 90.0, 0.02, 15.0)};
  std::vector<ShapeCase> out{
      make_case(B::Panel, S::Grid, 4.5, ridge_dent, 1),
      make_case(B::Panel, S::Random, 4.5, ridge_dent, 2),
      make_case(B::Panel, S::ScanLines, 4.5, ridge_dent, 3),
      make_case(B::Panel, S::Grid, 3.0, crease_ripple_saddle, 4),
      make_case(B::Panel, S::Random, 3.0, crease_ripple_saddle, 5),
      make_case(B::Panel, S::ScanLines, 3.0, crease_ripple_saddle, 6),
      make_case(B::Panel, S::Grid, 4.5, {bump(0.4, 0.6, -1.0, 1.25), bump(0.6, 0.4, 0.25, 12.0)}, 7),
      make_case(B::Hood, S::Grid, 4.5, twisted_dents_eggcrate, 8),
      make_case(B::Hood, S::Random, 4.5, twisted_dents_eggcrate, 9),
      make_case(B::Hood, S::ScanLines, 4.5, twisted_dents_eggcrate, 10),
      make_case(B::Hood, S::Grid, 1.5, {crease(0.3, 0.5, 100.0, 0.3, 1.0), bump(0.6, 0.5, 0.3, 14.0)}, 11),
      make_case(B::Hood, S::Random, 10.0, {crease(0.5, 0.4, 10.0, 0.05, 4.0), wave(0.5, 0.6, 0.0, 0.08, 20.0, 8.0, true, 90.0)}, 12),
      make_case(B::Hood, S::ScanLines, 0.0, {bump(0.4, 0.4, -0.5, 2.0), wave(0.65, 0.65, 30.0, 0.05, 8.0, 6.0)}, 13),
      make_case(B::Cylinder, S::Grid, 4.5, {wave(0.5, 0.5, 90.0, 0.1, 8.0, 5.0, true), bump(0.25, 0.3, -0.4, 1.8)}, 14),
      make_case(B::Cylinder, S::Random, 3.0, {crease(0.5, 0.5, 90.0, 0.1, 2.0), bump(0.3, 0.7, 0.2, 10.0)}, 15),
      make_case(B::Cylinder, S::ScanLines, 4.5, {twist(0.5, 0.5, 0.0, 0.15, 30.0), wave(0.5, 0.5, 20.0, 0.04, 25.0)}, 16),
      make_case(B::Cylinder, S::Grid, 0.0, {crease(0.4, 0.5, 20.0, 0.2, 1.5), bump(0.7, 0.5, -0.3, 2.5)}, 17),
      make_case(B::Panel, S::Grid, 0.0, ridge_dent, 18),
      make_case(B::Panel, S::Random, 1.5, {bump(0.3, 0.5, -1.0, 3.2), wave(0.65, 0.5, 45.0, 0.06, 16.0, 8.0, true)}, 19),
      make_case(B::Panel, S::ScanLines, 10.0, {bump(0.5, 0.5, 0.3, 15.0), crease(0.6, 0.5, 75.0, 0.2, 3.0)}, 20),
      make_case(B::Hood, S::Grid, 3.0, {wave(0.5, 0.5, 30.0, 0.03, 8.0), bump(0.6, 0.35, -0.4, 1.6)}, 21),
      make_case(B::Cylinder, S::Random, 4.5, {bump(0.3, 0.3, -0.3, 1.5), bump(0.7, 0.7, -0.6, 2.6), twist(0.5, 0.5, 45.0, 0.2, 30.0)}, 22),
      make_case(B::Panel, S::Grid, 4.5, {wave(0.5, 0.5, 15.0, 0.15, 30.0), crease(0.55, 0.45, 45.0, 0.1, 2.5)}, 23),
      make_case(B::Hood, S::Random, 4.5, {wave(0.5, 0.5, 0.0, 0.15, 8.0, 5.0, true, 90.0)}, 24),
      make_case(B::Cylinder, S::ScanLines, 3.0, {bump(0.5, 0.4, -0.2, 0.9), wave(0.5, 0.7, 0.0, 0.06, 12.0, 5.0, true)}, 25),
      make_case(B::Panel, S::Random, 3.0, {twist(0.5, 0.5, 0.0, 0.15, 40.0), crease(0.3, 0.5, 120.0, 0.1, 1.5), bump(0.75, 0.5, -0.5, 2.0)}, 26),
      make_case(B::Hood, S::Grid, 10.0, {bump(0.4, 0.6, 0.2, 10.0), wave(0.5, 0.5, 60.0, 0.05, 12.0), crease(0.7, 0.3, 0.0, 0.15, 2.0)}, 27),
      make_case(B::Cylinder, S::Grid, 1.5, {wave(0.5, 0.5, 45.0, 0.05, 10.0), crease(0.5, 0.3, 0.0, 0.1, 2.0)}, 28),
      make_case(B::Panel, S::ScanLines, 0.0, {crease(0.45, 0.5, 60.0, 0.3, 1.0), wave(0.5, 0.5, 0.0, 0.03, 20.0)}, 29),
      make_case(B::Hood, S::ScanLines, 3.0, {crease(0.5, 0.6, 150.0, 0.2, 2.0), bump(0.3, 0.3, -0.3, 1.2)}, 30),
  };
  // A random sampling runs half the time without i,j,k (what a scan's points have), half with.
  for (ShapeCase& c : out) {
    if (c.sampling == Sampling::Random) c.approach_normals = c.seed % 2 == 1;
    if (c.sampling == Sampling::Random) c.points = 6000;
    char name[48];
    std::snprintf(name, sizeof name, "S%02d-%s-%s", static_cast<int>(c.seed), to_string(c.base), to_string(c.sampling));
    c.name = name;
  }
  return out;
}

ShapeCase draw_shape_case(std::uint64_t seed, double noise_sigma) {
  std::mt19937_64 rng(seed * 104729 + 3);
  auto uniform = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  auto pick = [&](int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); };
  const auto base = static_cast<BaseSurface>(pick(3));
  const auto sampling = static_cast<Sampling>(pick(3));
  std::vector<FeatureSpec> features;
  const int count = 1 + pick(3);
  for (int k = 0; k < count; ++k) {
    const double u = uniform(0.2, 0.8), v = uniform(0.2, 0.8), angle = uniform(0.0, 180.0);
    switch (pick(6)) {
      case 0: features.push_back(bump(u, v, uniform(0.1, 0.4), uniform(8.0, 15.0))); break;
      case 1: {
        // 2–8 mm across (the Gaussian's σ a 2.4th of it), 0.05–1 mm deep, flanks no steeper than 26°.
        const double sd = uniform(2.0, 8.0) / 2.4;
        features.push_back(bump(u, v, -std::min(uniform(0.05, 1.0), 0.8 * sd), sd));
        break;
      }
      case 2: features.push_back(wave(u, v, angle, uniform(0.01, 0.06), uniform(8.0, 30.0))); break;
      case 3:
        features.push_back(wave(u, v, angle, uniform(0.01, 0.15), uniform(8.0, 30.0), uniform(4.0, 10.0), pick(3) > 0,
                                pick(2) == 0 ? 0.0 : 90.0));
        break;
      case 4: features.push_back(crease(u, v, angle, uniform(0.05, 0.3), uniform(1.0, 4.0))); break;
      default: features.push_back(twist(0.5, 0.5, pick(2) == 0 ? 0.0 : 45.0, uniform(0.05, 0.3), 35.0)); break;
    }
  }
  ShapeCase c = make_case(base, sampling, noise_sigma * 1e3, std::move(features), seed + 1000);
  if (sampling == Sampling::Random) c.approach_normals = pick(2) == 0;
  c.points = sampling == Sampling::Random ? 6000 : 7000;
  c.line_spacing = uniform(3.0, 5.0);
  char name[48];
  std::snprintf(name, sizeof name, "D%llu-%s-%s", static_cast<unsigned long long>(seed), to_string(c.base),
                to_string(c.sampling));
  c.name = name;
  return c;
}

}  // namespace probecomp::simulation
