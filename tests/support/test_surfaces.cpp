#include "support/test_surfaces.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "probecomp/simulation/random.hpp"

namespace probecomp::testing {

namespace {
nurbs::KnotVector random_knots(std::mt19937_64& rng, int p, int n_ctrl, bool repeated) {
  const int interior = n_ctrl - p - 1;
  std::uniform_real_distribution<double> unit(0.05, 0.95);
  std::vector<double> inner;
  for (int k = 0; k < interior; ++k) inner.push_back(unit(rng));
  std::sort(inner.begin(), inner.end());
  if (repeated && interior >= 2 && p >= 2) inner[interior / 2] = inner[interior / 2 - 1];
  std::vector<double> U(static_cast<std::size_t>(p + 1), 0.0);
  U.insert(U.end(), inner.begin(), inner.end());
  U.insert(U.end(), static_cast<std::size_t>(p + 1), 1.0);
  return nurbs::KnotVector(std::move(U), p);
}
}  // namespace

nurbs::Surface random_rational_surface(std::uint64_t seed, const RandomSurfaceSpec& spec) {
  std::mt19937_64 rng(seed);
  nurbs::KnotVector U = random_knots(rng, spec.p, spec.nu, spec.repeated_knots);
  nurbs::KnotVector V = random_knots(rng, spec.q, spec.nv, spec.repeated_knots);
  std::uniform_real_distribution<double> z(-spec.height, spec.height);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  std::uniform_real_distribution<double> w(spec.weight_min, spec.weight_max);
  std::vector<Point3> P;
  std::vector<double> W;
  for (int i = 0; i < spec.nu; ++i) {
    for (int j = 0; j < spec.nv; ++j) {
      const double x = spec.size * (i + jitter(rng)) / (spec.nu - 1);
      const double y = spec.size * (j + jitter(rng)) / (spec.nv - 1);
      P.emplace_back(x, y, z(rng));
      W.push_back(w(rng));
    }
  }
  return nurbs::Surface(std::move(U), std::move(V), P, W);
}

nurbs::Surface freeform_panel(std::uint64_t seed, int n, bool uniform_knots) {
  std::mt19937_64 rng(seed);
  constexpr int p = 3;
  nurbs::KnotVector U = random_knots(rng, p, n, false);
  nurbs::KnotVector V = random_knots(rng, p, n, false);
  if (uniform_knots) {
    U = nurbs::KnotVector::uniform(p, n - p);
    V = nurbs::KnotVector::uniform(p, n - p);
  }
  std::uniform_real_distribution<double> w(0.8, 1.25);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  const double a = phase(rng), b = phase(rng);
  std::vector<Point3> P;
  std::vector<double> W;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double x = 200.0 * i / (n - 1);
      const double y = 200.0 * j / (n - 1);
      const double z = 18.0 * std::sin(2.0 * std::numbers::pi * x / 180.0 + a) * std::cos(std::numbers::pi * y / 200.0) +
                       7.0 * std::sin(2.0 * std::numbers::pi * (x + y) / 110.0 + b);
      P.emplace_back(x, y, z);
      W.push_back(w(rng));
    }
  }
  return nurbs::Surface(std::move(U), std::move(V), P, W);
}

nurbs::Surface spiral_sheet() {
  constexpr int p = 3;
  constexpr int spans = 64;
  constexpr double r0 = 10.0;
  constexpr double growth_per_turn = 6.0;
  constexpr double turns = 2.0;
  constexpr double height = 30.0;
  const nurbs::KnotVector U = nurbs::KnotVector::uniform(p, spans);
  // Control points on the spiral at the Greville abscissae: a smooth curve close to the spiral.
  std::vector<Point3> P;
  for (int i = 0; i < U.num_basis(); ++i) {
    double g = 0.0;
    for (int k = 1; k <= p; ++k) g += U[i + k];
    g /= p;
    const double theta = 2.0 * std::numbers::pi * turns * g;
    const double r = r0 + growth_per_turn * theta / (2.0 * std::numbers::pi);
    for (int j = 0; j < 2; ++j) P.emplace_back(r * std::cos(theta), r * std::sin(theta), j * height);
  }
  return nurbs::Surface(U, nurbs::KnotVector::uniform(1, 1), P);
}

std::vector<Point3> random_points_near(const nurbs::Surface& s, std::size_t n, double max_offset, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const nurbs::Domain d = s.domain();
  std::uniform_real_distribution<double> u(d.u0, d.u1), v(d.v0, d.v1), t(-max_offset, max_offset);
  std::vector<Point3> out;
  out.reserve(n);
  while (out.size() < n) {
    const double uu = u(rng);
    const double vv = v(rng);
    const auto nrm = nurbs::unit_normal(s, uu, vv);
    const double tt = t(rng);
    if (nrm.status == nurbs::UnitNormal::Status::Degenerate) continue;
    out.push_back(nurbs::evaluate(s, uu, vv) + tt * nrm.n);
  }
  return out;
}

nurbs::Surface perturbed(const nurbs::Surface& s, double amount, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> d(-amount, amount);
  std::vector<Point3> P;
  std::vector<double> w;
  for (int i = 0; i < s.num_u(); ++i) {
    for (int j = 0; j < s.num_v(); ++j) {
      P.push_back(s.control_point(i, j) + simulation::draw_vector(d, rng));
      w.push_back(s.weight(i, j));
    }
  }
  return nurbs::Surface(s.U(), s.V(), P, w);
}

SurfaceSamples sample_surface(const nurbs::Surface& s, std::size_t n, double sigma, std::uint64_t seed, Noise noise,
                              double u_fraction) {
  std::mt19937_64 rng(seed);
  const nurbs::Domain d = s.domain();
  std::uniform_real_distribution<double> u(d.u0, d.u0 + u_fraction * (d.u1 - d.u0)), v(d.v0, d.v1);
  std::normal_distribution<double> gauss(0.0, sigma);
  SurfaceSamples out;
  for (std::size_t k = 0; k < n; ++k) {
    const fitting::SurfaceParameter t{u(rng), v(rng)};
    Point3 x = nurbs::evaluate(s, t.u, t.v);
    if (sigma > 0.0) {
      if (noise == Noise::AlongNormal) {
        x += gauss(rng) * nurbs::unit_normal(s, t.u, t.v).n;
      } else {
        x += simulation::draw_vector(gauss, rng);
      }
    }
    out.points.push_back(x);
    out.params.push_back(t);
  }
  return out;
}

SurfaceDeviation surface_deviation(const nurbs::Surface& fit, const nurbs::Surface& truth, int grid,
                                   double u_fraction) {
  const nurbs::Domain d = truth.domain();
  SurfaceDeviation out;
  for (int a = 0; a < grid; ++a) {
    for (int b = 0; b < grid; ++b) {
      const double u = d.u0 + u_fraction * (d.u1 - d.u0) * a / (grid - 1);
      const double v = d.v0 + (d.v1 - d.v0) * b / (grid - 1);
      const double e = (nurbs::evaluate(fit, u, v) - nurbs::evaluate(truth, u, v)).norm();
      out.max = std::max(out.max, e);
      out.rms += e * e;
    }
  }
  out.rms = std::sqrt(out.rms / (static_cast<double>(grid) * grid));
  return out;
}

}  // namespace probecomp::testing
