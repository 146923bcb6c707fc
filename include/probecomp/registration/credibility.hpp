#pragma once
// Whether a registration of raw probe centres to the radius-offset model can be believed, and a coarse global
// alignment for when it cannot (issue 20). ICP converges to the nearest local minimum: started a few mm and ~10°
// off, it can settle with the points on the wrong side of a thin wall or across a fillet, and still report
// "converged". Three things a right registration of probe centres shows, whatever the part's form error:
//   overlap     most points have a correspondence inside a face (not past its edge);
//   probe side  the centres lie outside the material: a tip centre more than r/2 inside the nominal part
//               (a correspondence r/2 below the offset surface) cannot be a touch unless the part is deformed
//               by that much there, which a credible part is at a few points, not at a tenth of them;
//   residuals   their robust scale is small against r: at a scale of r/4, the closest point on the offset
//               model is no longer a reliable correspondence (a feature 2r wide is within reach of either side).
// Residuals are compared with r and not with the noise: the deviations are what is measured, and a part's
// form error is not a registration failure. Nor can these figures alone tell a wrong registration from a part
// deformed by about r (the cylinder study's 1.5 mm sine with r = 1 mm: 21 % of the points r/2 inside, scale
// 0.73 mm): a registration that fails them is a reason to look for a better one (coarse_align), and a verdict
// only when one is found or when the data hardly touch the model.

#include <string>

#include "probecomp/cad/locator.hpp"
#include "probecomp/geometry/tip_radii.hpp"
#include "probecomp/registration/icp.hpp"

namespace probecomp::registration {

// Below this share of points with a correspondence inside a face, the data and the model hardly overlap.
inline constexpr double kMinOverlap = 0.5;
// Above this share of used points more than half the radius inside the material, the points sit on the wrong side.
inline constexpr double kMaxInsideShare = 0.1;
// The robust residual scale may be at most this fraction of the probe radius.
inline constexpr double kMaxScaleOverRadius = 0.25;

struct Credibility {
  enum class Status { OK, LittleOverlap, InsideMaterial, LargeResiduals };
  Status status = Status::OK;
  double overlap = 0.0;       // share of all points with a usable correspondence
  double inside_share = 0.0;  // share of those more than r/2 inside the material
  double scale = 0.0;         // the registration's robust residual scale, mm
  std::string reason;         // one line when not OK: what failed, with the figures
  [[nodiscard]] bool ok() const { return status == Status::OK; }
};

// r is each point's own tip radius; the residual scale is held against the smallest.
[[nodiscard]] Credibility assess_registration(const RegistrationResult& r, const geometry::TipRadii& radii);

// How well a registration fits, to compare registrations of the same points from different starts: the median
// |residual|, a point without a usable correspondence or more than r/2 inside the material counting as r. mm.
[[nodiscard]] double registration_score(const RegistrationResult& r, const geometry::TipRadii& radii);

struct CoarseAlignmentOptions {
  // Starts: the given initial transform, and each turned by ± these angles (degrees) about the points' three
  // principal axes through their centroid. ICP's basin reaches a few mm and several degrees on a typical part;
  // the turned starts reach the rotations beyond it.
  std::vector<double> angles{10.0, 20.0};
  std::size_t subset_points = 512;  // each start registers a spread subset of about this many points
  int max_iterations = 40;          // per start
};

struct CoarseAlignment {
  geometry::RigidTransform transform = geometry::RigidTransform::Identity();  // CAD to machine, the best start's
  int starts = 0;     // starts tried
  double score = 0.0; // the best start's registration_score on the subset, mm
};

// Multi-start ICP on a subset: the start whose registration has the best registration_score. Deterministic.
// `offset_model` is offset by radii.smallest(); larger tips' centres are registered that much farther out.
[[nodiscard]] CoarseAlignment coarse_align(const cad::ModelLocator& offset_model, std::span<const Point3> raw_centres,
                                           const geometry::TipRadii& radii, const RegistrationOptions& options,
                                           const CoarseAlignmentOptions& coarse = {});

}  // namespace probecomp::registration
