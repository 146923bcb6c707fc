#include "probecomp/registration/credibility.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "probecomp/geometry/point_set.hpp"
#include "probecomp/geometry/statistics.hpp"

namespace probecomp::registration {

namespace {

std::string percent(double share) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0f %%", 100.0 * share);
  return buf;
}

std::string mm(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g mm", v);
  return buf;
}

// A residual for the start's score: |d| where the correspondence is usable and on the probe side, else r.
double scored(const PointMatch& m, double r) {
  if (!m.ok() || m.on_edge || m.distance < -0.5 * r) return r;
  return std::min(std::abs(m.distance), r);
}

// Only the points that located the part are judged: the others may be far off by the part's own deviations.
bool locates(const RegistrationResult& r, std::size_t k) { return r.located_by.empty() || r.located_by[k] != 0; }

}  // namespace

Credibility assess_registration(const RegistrationResult& r, const geometry::TipRadii& radii) {
  Credibility c;
  c.scale = r.scale;
  const double probe_radius = radii.smallest();
  std::size_t used = 0, inside = 0;
  std::size_t locating = 0;
  for (std::size_t k = 0; k < r.matches.size(); ++k) {
    if (!locates(r, k)) continue;
    ++locating;
    const PointMatch& m = r.matches[k];
    if (!m.ok() || m.on_edge) continue;
    ++used;
    inside += m.distance < -0.5 * radii[k];
  }
  const std::size_t n = std::max<std::size_t>(locating, 1);
  c.overlap = static_cast<double>(used) / static_cast<double>(n);
  c.inside_share = used > 0 ? static_cast<double>(inside) / static_cast<double>(used) : 0.0;
  if (c.overlap < kMinOverlap) {
    c.status = Credibility::Status::LittleOverlap;
    c.reason = "only " + percent(c.overlap) + " of the points have a correspondence inside a face (at least " +
               percent(kMinOverlap) + " expected): the points and the model hardly overlap";
  } else if (c.inside_share > kMaxInsideShare) {
    c.status = Credibility::Status::InsideMaterial;
    c.reason = percent(c.inside_share) + " of the points would have the tip centre more than r/2 inside the material (at most " +
               percent(kMaxInsideShare) + " expected): the model sits on the wrong side of them";
  } else if (c.scale > kMaxScaleOverRadius * probe_radius) {
    c.status = Credibility::Status::LargeResiduals;
    c.reason = "the residuals' robust scale is " + mm(c.scale) + ", more than " + mm(kMaxScaleOverRadius * probe_radius) +
               " (r/4): the closest points on the model are not reliable correspondences";
  }
  return c;
}

double registration_score(const RegistrationResult& r, const geometry::TipRadii& radii) {
  std::vector<double> residuals;
  residuals.reserve(r.matches.size());
  for (std::size_t k = 0; k < r.matches.size(); ++k) {
    if (locates(r, k)) residuals.push_back(scored(r.matches[k], radii[k]));
  }
  return residuals.empty() ? radii.smallest() : geometry::median_in_place(residuals);
}

CoarseAlignment coarse_align(const cad::ModelLocator& offset_model, std::span<const Point3> raw,
                             const geometry::TipRadii& radii, const RegistrationOptions& options,
                             const CoarseAlignmentOptions& coarse) {
  const std::vector<std::size_t> chosen = geometry::spread_subset_indices(raw, coarse.subset_points);
  std::vector<Point3> subset;
  for (std::size_t k : chosen) subset.push_back(raw[k]);
  std::vector<double> beyond;
  for (std::size_t k : chosen) {
    if (!radii.uniform()) beyond.push_back(radii[k] - radii.smallest());
  }
  const geometry::TipRadii subset_radii = radii.subset(chosen);
  std::vector<std::uint8_t> subset_located_by;
  for (std::size_t k : chosen) {
    if (!options.located_by.empty()) subset_located_by.push_back(options.located_by[k]);
  }
  CoarseAlignment best;
  best.transform = options.initial;
  if (subset.size() < 6) return best;
  // The points' principal axes through their centroid (machine frame): each start turns the placed model about
  // one of them.
  const geometry::PrincipalAxes axes = geometry::principal_axes(subset);

  std::vector<geometry::RigidTransform> starts{options.initial};
  for (double angle : coarse.angles) {
    for (int axis = 0; axis < 3; ++axis) {
      for (double sign : {1.0, -1.0}) {
        // CAD → machine as the initial transform, then the turn about the axis in the machine frame.
        geometry::RigidTransform turn = geometry::RigidTransform::Identity();
        turn.linear() = Eigen::AngleAxisd(sign * angle * std::numbers::pi / 180.0, axes.axes.col(axis)).toRotationMatrix();
        turn.translation() = axes.centroid - turn.linear() * axes.centroid;
        starts.push_back(turn * options.initial);
      }
    }
  }
  RegistrationOptions o = options;
  o.criteria.max_iterations = coarse.max_iterations;
  o.located_by = subset_located_by;
  best.score = std::numeric_limits<double>::infinity();
  for (const geometry::RigidTransform& start : starts) {
    o.initial = start;
    const RegistrationResult r = register_points(offset_model, subset, o, beyond);
    ++best.starts;
    if (r.status == Status::TooFewPoints || r.status == Status::NumericalError) continue;
    const double score = registration_score(r, subset_radii);
    // Strictly better only: ties keep the earlier start (the given one first), so the choice is deterministic.
    if (score < best.score) {
      best.score = score;
      best.transform = r.transform;
    }
  }
  return best;
}

}  // namespace probecomp::registration
