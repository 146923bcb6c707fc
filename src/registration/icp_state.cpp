#include "icp_state.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "probecomp/geometry/statistics.hpp"
#include "probecomp/registration/robust.hpp"

namespace probecomp::registration::detail {

using nurbs::OsculatingPatch;

namespace {

// The fewest points a block holds in passes that evaluate the surface or a patch (tens to hundreds of ns a point:
// 10 000 points in one block of the default grain would leave a core idle).
constexpr std::size_t kEvaluatingGrain = 1024;

// f(first, last) over consecutive blocks of at least `grain` points of [0, n), in parallel: for the per-point passes
// of each step, which write only their own points' entries.
template <class F>
void for_blocks(std::size_t n, F&& f, std::size_t grain = 1 << 14) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::size_t>& range) { f(range.begin(), range.end()); });
}

bool usable(const cad::ModelPoint& m, double max_distance) {
  return m.ok() && !m.on_edge() && std::abs(m.distance) <= max_distance;
}

}  // namespace

DataFrame DataFrame::of(std::span<const Point3> x) {
  DataFrame frame;
  BoundingBox box;
  std::size_t finite = 0;
  for (const Point3& p : x) {
    if (!p.allFinite()) continue;
    box.extend(p);
    frame.centroid += p;
    ++finite;
  }
  frame.centroid /= static_cast<double>(finite);
  double L2 = 0.0;
  for (const Point3& p : x) {
    if (p.allFinite()) L2 += (p - frame.centroid).squaredNorm();
  }
  // A length for the rotation scale even when all points coincide (then no rotation is fixed anyway).
  frame.length = std::max(std::sqrt(L2 / static_cast<double>(finite)), 1e-3);
  frame.centre = 0.5 * (box.min + box.max);
  frame.max_radius = 0.5 * box.diagonal();
  return frame;
}

double DataFrame::move(const geometry::RigidTransform& motion) {
  // The update acts on the points in the CAD frame; their box moves with them, so bound about its image.
  const double moved = geometry::largest_motion(motion, centre, max_radius);
  centre = motion * centre;
  centroid = motion * centroid;
  return moved;
}

IcpState::IcpState(const cad::ModelLocator& model, std::span<const Point3> machine_points,
                   const RegistrationOptions& options, std::vector<cad::ModelPoint> hints,
                   std::span<const double> offsets)
    : model_(model), machine_points_(machine_points), options_(options), offsets_(offsets), n_(machine_points.size()),
      x_(n_), feet_(std::move(hints)), r_(n_), w_(n_), use_(n_, 0), scale_(options.robust.min_scale) {}

std::size_t IcpState::robust_weights() {
  // The used residuals gathered in parallel: each chunk's count, then its copies at its offset.
  constexpr std::size_t kChunks = 64;
  std::array<std::size_t, kChunks + 1> offset{};
  tbb::parallel_for(std::size_t{0}, kChunks, [&](std::size_t c) {
    std::size_t count = 0;
    for (std::size_t i = n_ * c / kChunks; i < n_ * (c + 1) / kChunks; ++i) count += use_[i] != 0;
    offset[c + 1] = count;
  });
  for (std::size_t c = 0; c < kChunks; ++c) offset[c + 1] += offset[c];
  used_r_.resize(offset[kChunks]);
  tbb::parallel_for(std::size_t{0}, kChunks, [&](std::size_t c) {
    std::size_t at = offset[c];
    for (std::size_t i = n_ * c / kChunks; i < n_ * (c + 1) / kChunks; ++i) {
      if (use_[i]) used_r_[at++] = r_[i];
    }
  });
  scale_ = geometry::robust_scale_in_place(used_r_, options_.robust.min_scale);  // used_r_ is rebuilt at every call
  for_blocks(n_, [&](std::size_t first, std::size_t last) {
    for (std::size_t i = first; i < last; ++i) {
      w_[i] = use_[i] ? robust_weight(options_.robust.loss, r_[i], scale_) : 0.0;
    }
  });
  return used_r_.size();
}

void IcpState::osculating_patches(bool missing_only) {
  const cad::Model& cad_model = model_.model();
  patches_.resize(n_, OsculatingPatch::invalid());
  for_blocks(n_, [&](std::size_t first, std::size_t last) {
    for (std::size_t i = first; i < last; ++i) {
      if (missing_only && patches_[i].valid()) continue;
      const cad::ModelPoint& m = feet_[i];
      patches_[i] = OsculatingPatch::invalid();
      if (!m.ok() || m.face < 0 || !x_[i].allFinite()) continue;
      const cad::Face& face = cad_model.faces[static_cast<std::size_t>(m.face)];
      patches_[i] = OsculatingPatch::at(nurbs::derivatives_d2(face.surface, m.u, m.v), m.normal,
                                        offsets_.empty() ? 0.0 : offsets_[i]);
    }
  }, kEvaluatingGrain);
  patches_current_ = true;
}

std::size_t IcpState::correspondences(const geometry::RigidTransform& to_cad, Search mode) {
  const std::vector<cad::ModelPoint>& targets = this->targets();
  for_blocks(n_, [&](std::size_t first, std::size_t last) {
    for (std::size_t i = first; i < last; ++i) x_[i] = to_cad * machine_points_[i];
  });
  if (patches_current_) {
    // After slides, Newton starts from the parameters each foot's paraboloid predicts where the point now is, not
    // from the foot's own: off by about κt² instead of t (t the slide's tangential part), one Newton step fewer.
    const cad::Model& cad_model = model_.model();
    for_blocks(n_, [&](std::size_t first, std::size_t last) {
      for (std::size_t i = first; i < last; ++i) {
        if (!patches_[i].valid() || !x_[i].allFinite()) continue;
        const OsculatingPatch::Prediction p = patches_[i].predict(targets[i].point, targets[i].normal, x_[i]);
        const nurbs::Domain dom = cad_model.faces[static_cast<std::size_t>(feet_[i].face)].surface.domain();
        feet_[i].u = std::clamp(feet_[i].u + p.du, dom.u0, dom.u1);
        feet_[i].v = std::clamp(feet_[i].v + p.dv, dom.v0, dom.v1);
      }
    }, kEvaluatingGrain);
  }
  patches_current_ = false;
  if (feet_.empty()) {
    feet_ = model_.closest_points(x_);
  } else if (mode == Search::Local && options_.metric == Metric::PointToPlane && offsets_.empty()) {
    // Slides follow a local search: Newton's own derivatives give most patches (a million points: 90 ms less).
    patches_.resize(n_);
    model_.update_closest_points(x_, feet_, mode, patches_);
    osculating_patches(true);
  } else {
    model_.update_closest_points(x_, feet_, mode);
  }
  if (!offsets_.empty()) moved_.resize(n_);
  for_blocks(n_, [&](std::size_t first, std::size_t last) {
    for (std::size_t i = first; i < last; ++i) {
      if (!offsets_.empty()) {
        moved_[i] = feet_[i];
        moved_[i].point += offsets_[i] * moved_[i].normal;
        moved_[i].distance -= offsets_[i];
      }
      const cad::ModelPoint& m = targets[i];
      use_[i] = x_[i].allFinite() && usable(m, options_.max_distance) && locates(i);
      r_[i] = !use_[i] ? 0.0 : options_.metric == Metric::PointToPlane ? m.distance : (x_[i] - m.point).norm();
    }
  });
  return robust_weights();
}

std::size_t IcpState::slide(const geometry::RigidTransform& motion) {
  if (!patches_current_) osculating_patches(false);
  const std::vector<cad::ModelPoint>& targets = this->targets();
  const cad::Model& cad_model = model_.model();
  for_blocks(n_, [&](std::size_t first, std::size_t last) {
    for (std::size_t i = first; i < last; ++i) {
      x_[i] = motion * x_[i];
      const cad::ModelPoint& m = targets[i];
      if (!patches_[i].valid()) {
        if (use_[i]) r_[i] = m.normal.dot(x_[i] - m.point);
        continue;
      }
      const OsculatingPatch::Prediction p = patches_[i].predict(m.point, m.normal, x_[i]);
      const cad::Face& face = cad_model.faces[static_cast<std::size_t>(m.face)];
      const nurbs::Domain dom = face.surface.domain();
      const double u = m.u + p.du, v = m.v + p.dv;
      // Strictly inside: a foot on the domain's edge is a constrained minimum, which the estimate does not use. A
      // foot that crosses a closed face's seam is taken for one that left the face: the search after the slides
      // finds it again (a search more, not a different answer).
      const bool inside = u > dom.u0 && u < dom.u1 && v > dom.v0 && v < dom.v1 &&
                          (!face.trimmed() || face.trim->contains(u, v));
      use_[i] = x_[i].allFinite() && inside && std::abs(p.distance) <= options_.max_distance && locates(i);
      r_[i] = use_[i] ? p.distance : 0.0;
    }
  }, kEvaluatingGrain);
  return robust_weights();
}

void IcpState::finish(RegistrationResult& result) const {
  const std::vector<cad::ModelPoint>& targets = this->targets();
  result.scale = scale_;
  result.matches.resize(n_);
  double ss = 0.0;
  result.used = 0;
  result.inliers = 0;
  for (std::size_t i = 0; i < n_; ++i) {
    PointMatch& pm = result.matches[i];
    if (i < targets.size()) {
      const cad::ModelPoint& m = targets[i];
      pm.status = m.status;
      pm.face = m.face;
      pm.u = m.u;
      pm.v = m.v;
      pm.distance = m.distance;
      pm.on_edge = m.ok() && m.on_edge();
    }
    pm.weight = w_[i];
    result.used += use_[i];
    pm.inlier = use_[i] && std::abs(r_[i]) <= kOutlierSigmas * scale_;
    if (pm.inlier) {
      ++result.inliers;
      ss += pm.distance * pm.distance;
    }
  }
  result.rms = result.inliers > 0 ? std::sqrt(ss / result.inliers) : 0.0;
}

}  // namespace probecomp::registration::detail
