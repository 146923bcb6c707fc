#include "probecomp/cad/plan.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "probecomp/error.hpp"

namespace probecomp::cad {

namespace {

// Iso-curves sampled to estimate a face's extent along u and v; a polyline of 64 chords under-estimates an
// arc's length by well under 1 %.
constexpr int kLengthSamples = 64;
constexpr int kIsoCurves = 5;
// A face may not receive more than this many points (a tiny spacing on a large face is a mistake). Twice the
// 10 M points of a dense scan of one panel, the largest case compensate is measured on (docs/performance.md).
constexpr long kMaxPointsPerFace = 20'000'000;

double longest_iso_length(const nurbs::Surface& s, const nurbs::Domain& d, bool along_u) {
  double longest = 0.0;
  for (int c = 0; c < kIsoCurves; ++c) {
    const double fixed = along_u ? d.v0 + (d.v1 - d.v0) * c / (kIsoCurves - 1) : d.u0 + (d.u1 - d.u0) * c / (kIsoCurves - 1);
    double length = 0.0;
    Point3 previous;
    for (int k = 0; k <= kLengthSamples; ++k) {
      const double t = along_u ? d.u0 + (d.u1 - d.u0) * k / kLengthSamples : d.v0 + (d.v1 - d.v0) * k / kLengthSamples;
      const Point3 p = along_u ? nurbs::evaluate(s, t, fixed) : nurbs::evaluate(s, fixed, t);
      if (k > 0) length += (p - previous).norm();
      previous = p;
    }
    longest = std::max(longest, length);
  }
  return longest;
}

}  // namespace

std::vector<PlannedPoint> plan_points(const Model& model, double spacing, const std::vector<int>& faces) {
  if (!(spacing > 0.0) || !std::isfinite(spacing)) throw InputError("spacing must be a positive number of mm");
  std::vector<int> chosen = faces;
  if (chosen.empty()) {
    for (const Face& f : model.faces) chosen.push_back(f.index);
  }
  for (int f : chosen) {
    if (f < 0 || f >= static_cast<int>(model.faces.size())) {
      throw InputError("face " + std::to_string(f) + " does not exist (the model has faces 0 to " +
                                  std::to_string(model.faces.size() - 1) + ")");
    }
  }
  std::vector<PlannedPoint> out;
  for (int f : chosen) {
    const Face& face = model.faces[static_cast<std::size_t>(f)];
    // Over the trim's parameter box only: a small face may be cut from a very large surface.
    nurbs::Domain d = face.surface.domain();
    if (face.trimmed()) {
      const nurbs::Domain t = face.trim->parameter_bounds();
      d = {std::max(d.u0, t.u0), std::min(d.u1, t.u1), std::max(d.v0, t.v0), std::min(d.v1, t.v1)};
    }
    const long nu = std::max(1L, std::lround(std::ceil(longest_iso_length(face.surface, d, true) / spacing)));
    const long nv = std::max(1L, std::lround(std::ceil(longest_iso_length(face.surface, d, false) / spacing)));
    if (nu * nv > kMaxPointsPerFace) {
      throw InputError("spacing " + std::to_string(spacing) + " mm would put more than " +
                                  std::to_string(kMaxPointsPerFace) + " points on face " + std::to_string(f));
    }
    for (long i = 0; i < nu; ++i) {
      const double u = d.u0 + (d.u1 - d.u0) * (static_cast<double>(i) + 0.5) / static_cast<double>(nu);
      for (long j = 0; j < nv; ++j) {
        const double v = d.v0 + (d.v1 - d.v0) * (static_cast<double>(j) + 0.5) / static_cast<double>(nv);
        if (face.trimmed() && !face.trim->contains(u, v)) continue;
        const nurbs::UnitNormal n = nurbs::unit_normal(face.surface, u, v);
        if (n.status == nurbs::UnitNormal::Status::Degenerate) continue;
        out.push_back({nurbs::evaluate(face.surface, u, v), static_cast<double>(face.outward) * n.n, f, u, v});
      }
    }
  }
  return out;
}

}  // namespace probecomp::cad
