#include "probecomp/cad/outline.hpp"

#include <algorithm>
#include <cmath>

namespace probecomp::cad {

namespace {

// Evenly spaced picks of a boundary curve's sample parameters, its first and last kept, at most `most` of them.
std::vector<double> thinned(const std::vector<double>& t, int most) {
  const auto n = static_cast<int>(t.size());
  if (n <= most || most < 2) return t;
  std::vector<double> out;
  for (int k = 0; k < most; ++k) out.push_back(t[static_cast<std::size_t>(std::lround(double(k) * (n - 1) / (most - 1)))]);
  return out;
}

}  // namespace

std::vector<Polyline> face_outline(const Face& face, const OutlineOptions& options) {
  const nurbs::Surface& S = face.surface;
  std::vector<Polyline> lines;
  const nurbs::Domain whole = S.domain();
  const nurbs::Domain box = face.trimmed() ? face.trim->parameter_bounds() : whole;
  const int n = std::max(options.samples_per_line, 2);

  // Walks (u(s), v(s)) for s in [0, 1], keeping the runs inside the face.
  auto trace = [&](auto uv_of) {
    Polyline run;
    for (int k = 0; k < n; ++k) {
      const auto [u, v] = uv_of(double(k) / (n - 1));
      if (face.trimmed() && !face.trim->contains(u, v)) {
        if (run.size() >= 2) lines.push_back(std::move(run));
        run.clear();
        continue;
      }
      run.push_back(nurbs::evaluate(S, u, v));
    }
    if (run.size() >= 2) lines.push_back(std::move(run));
  };
  auto lerp = [](double a, double b, double s) { return a + (b - a) * s; };

  if (face.trimmed()) {
    for (const BoundaryCurve& c : face.trim->curves()) {
      Polyline edge;
      for (double t : thinned(c.t, options.max_boundary_samples)) {
        const Point3 uv = nurbs::evaluate(c.uv, t);
        // The boundary may stray from the domain by the trim curves' tolerance: clamp it in.
        edge.push_back(nurbs::evaluate(S, std::clamp(uv.x(), whole.u0, whole.u1), std::clamp(uv.y(), whole.v0, whole.v1)));
      }
      if (edge.size() >= 2) lines.push_back(std::move(edge));
    }
  } else {
    for (double u : {whole.u0, whole.u1}) trace([&](double s) { return std::pair{u, lerp(whole.v0, whole.v1, s)}; });
    for (double v : {whole.v0, whole.v1}) trace([&](double s) { return std::pair{lerp(whole.u0, whole.u1, s), v}; });
  }
  for (int i = 1; i <= options.isolines; ++i) {
    const double f = double(i) / (options.isolines + 1);
    const double u = lerp(box.u0, box.u1, f), v = lerp(box.v0, box.v1, f);
    trace([&](double s) { return std::pair{u, lerp(box.v0, box.v1, s)}; });
    trace([&](double s) { return std::pair{lerp(box.u0, box.u1, s), v}; });
  }
  return lines;
}

}  // namespace probecomp::cad
