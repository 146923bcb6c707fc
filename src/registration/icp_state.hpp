#pragma once
// The steps of an ICP iteration on all the points (icp.cpp's iterate): their correspondences and the robust weights
// that come with them, the osculating patches and the slides on them between searches, the data's frame, and the
// result's matches. Private to registration/.

#include <cstddef>
#include <span>
#include <vector>

#include "probecomp/cad/locator.hpp"
#include "probecomp/geometry/rigid.hpp"
#include "probecomp/nurbs/osculating_patch.hpp"
#include "probecomp/registration/icp.hpp"

namespace probecomp::registration::detail {

// The points' box centre and radius bound how far an update moves any of them. Their centroid and RMS
// radius are the twist's frame; both travel with the data.
struct DataFrame {
  Point3 centroid = Point3::Zero();
  double length = 1.0;
  Point3 centre = Point3::Zero();
  double max_radius = 0.0;

  // The frame of the points `x` (CAD frame; the ones not finite left out).
  [[nodiscard]] static DataFrame of(std::span<const Point3> x);
  // Moves the frame with the data; returns the largest motion of any point, mm.
  double move(const geometry::RigidTransform& motion);
};

// The per-point arrays of one registration: each point in the CAD frame, its correspondence (foot and target),
// residual, weight and patch, and the residuals' robust scale.
class IcpState {
 public:
  using Search = cad::ModelLocator::HintedSearch;

  // `hints` (empty, or one per point) start the first pass's Newton; `offsets` as for register_points.
  IcpState(const cad::ModelLocator& model, std::span<const Point3> machine_points, const RegistrationOptions& options,
           std::vector<cad::ModelPoint> hints, std::span<const double> offsets);

  // Correspondences at the current transform. The first pass searches the whole model; later ones start
  // Newton from the previous feet and, while the estimate moves, skip re-searching each point's own face for
  // other minima (Local). Convergence is only accepted after an exact pass (the global search, bounded by the
  // local answer) has confirmed the correspondences.
  // Returns the number of points in use.
  std::size_t correspondences(const geometry::RigidTransform& to_cad, Search mode);

  // Between searches the points move against their targets' osculating paraboloids (osculating_patch.hpp) rather
  // than searching again: a pass over the arrays instead of a closest-point search each step, while reweighting
  // converges the robust weights (IRLS, linear: many steps). The paraboloid also gives the parameters of each point's
  // foot, so a point whose foot crosses its face's edge or trim leaves the estimate (or joins it) as the next search
  // would have it. Tangent planes saw neither the curvature, which fixes the motions a gently curved face fixes only
  // weakly, nor the edges: a million points on the demo's panel needed 3 searches (the one after the slides still
  // moved them 9e-5 mm, from 38 points that crossed the panel's edge); with paraboloids the one after the slides
  // confirms.
  // Returns the number of points in use.
  std::size_t slide(const geometry::RigidTransform& motion);

  // The result's matches, used and inlier counts, RMS and scale, from the last correspondences.
  void finish(RegistrationResult& result) const;

  [[nodiscard]] std::span<const Point3> points() const { return x_; }
  // With offsets, each foot moved out along its normal by its point's offset: the targets the estimate uses.
  [[nodiscard]] const std::vector<cad::ModelPoint>& targets() const { return offsets_.empty() ? feet_ : moved_; }
  [[nodiscard]] std::span<const double> weights() const { return w_; }
  [[nodiscard]] std::span<const nurbs::OsculatingPatch> patches() const { return patches_; }
  [[nodiscard]] double scale() const { return scale_; }

 private:
  // Robust weights and scale from the residuals r of the points in use.
  std::size_t robust_weights();
  // Each target's patch from the surface's derivatives at its foot; `missing_only`: only where the search gave none.
  void osculating_patches(bool missing_only);
  // The point may locate the part (RegistrationOptions::located_by).
  [[nodiscard]] bool locates(std::size_t i) const { return options_.located_by.empty() || options_.located_by[i] != 0; }

  const cad::ModelLocator& model_;
  std::span<const Point3> machine_points_;
  const RegistrationOptions& options_;
  std::span<const double> offsets_;
  std::size_t n_;

  std::vector<Point3> x_;
  std::vector<cad::ModelPoint> feet_;  // the model's closest points: the next pass's hints
  std::vector<cad::ModelPoint> moved_;
  std::vector<double> r_, w_;
  std::vector<char> use_;  // the point's correspondence enters the estimate (its weight may still be 0)
  std::vector<double> used_r_;
  // The surface about each target to second order, for the slides between searches: from a local search's Newton,
  // else made at the first slide after the search (a search that confirms convergence needs none).
  std::vector<nurbs::OsculatingPatch> patches_;
  bool patches_current_ = false;
  double scale_;
};

}  // namespace probecomp::registration::detail
