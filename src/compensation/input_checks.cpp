#include "input_checks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "probecomp/error.hpp"
#include "probecomp/geometry/point_set.hpp"
#include "probecomp/geometry/statistics.hpp"
#include "probecomp/nurbs/surface.hpp"

#include "warnings.hpp"

namespace probecomp::compensation::detail {

namespace {

// Points whose spread across their main direction is below this fraction of the spread along it lie on a line.
// A scan line across a curved face bends by far more (the free-form panel's shallowest line: 1e-3 of its length).
constexpr double kLineRatio = 1e-6;

}  // namespace

void check_points_near(const cad::ModelLocator& locator, std::span<const Point3> points,
                       const geometry::RigidTransform& initial, double fraction) {
  BoundingBox box;
  for (const cad::Face& f : locator.model().faces) {
    const BoundingBox b = nurbs::bounding_box(f.surface);
    box.extend(b.min);
    box.extend(b.max);
  }
  // 257 points give the median to within a few per cent of the distribution: plenty for a gross check.
  std::vector<Point3> subset = geometry::spread_subset(points, 257);
  if (subset.empty()) throw InputError("no finite points to compensate");
  const geometry::RigidTransform to_cad = initial.inverse();
  for (Point3& p : subset) p = to_cad * p;
  const std::vector<cad::ModelPoint> feet = locator.closest_points(subset);
  std::vector<double> d;
  for (const cad::ModelPoint& m : feet) d.push_back(m.ok() ? std::abs(m.distance) : std::numeric_limits<double>::infinity());
  const double median = geometry::upper_median_in_place(d);
  const double limit = fraction * box.diagonal();
  if (!(median <= limit)) {
    throw InputError("the points are nowhere near the model: their median distance from it is " + mm(median) +
                                " mm, more than " + mm(limit) + " mm (" + mm(100 * fraction) +
                                " % of its size); check the CAD file, the frame and the units");
  }
}

void check_point_spread(std::span<const Point3> raw) {
  const geometry::PrincipalAxes axes = geometry::principal_axes(raw);
  const std::size_t n = axes.count;
  if (n == 0) throw InputError("no finite points to compensate");
  const Point3& centre = axes.centroid;
  const Eigen::Vector3d& spread = axes.spread;  // ascending
  if (spread[2] <= kSamePosition) {
    throw InputError("all " + std::to_string(n) + " points are at one position (" + mm(centre.x()) + ", " +
                     mm(centre.y()) + ", " + mm(centre.z()) +
                     "): they fix neither the part's position nor any surface");
  }
  if (spread[1] <= std::max(kLineRatio * spread[2], kSamePosition)) {
    throw InputError("the " + std::to_string(n) + " points lie on one line (spread " + mm(spread[1]) +
                     " mm across it, " + mm(spread[2]) +
                     " mm along it): they cannot fix the part's rotation about that line nor measure a surface");
  }
}

void check_model_and_radii(const cad::Model& model, const geometry::TipRadii& radii, std::size_t points) {
  if (!(radii.smallest() > 0.0) || !std::isfinite(radii.largest())) {
    throw InputError("the probe radius must be a positive number of mm");
  }
  if (!radii.uniform() && radii.count() != points) {
    throw InputError("the points have " + std::to_string(radii.count()) + " tip radii for " + std::to_string(points) +
                     " points");
  }
  if (model.faces.empty()) throw InputError("the CAD model has no faces");
}

geometry::TipRadii tip_radii(const CompensateOptions& options, std::size_t points) {
  if (options.probe_radii.empty()) return geometry::TipRadii(options.probe_radius);
  if (options.probe_radii.size() != points) {
    throw InputError("the points have " + std::to_string(options.probe_radii.size()) + " tip radii for " +
                     std::to_string(points) + " points");
  }
  for (std::size_t k = 0; k < points; ++k) {
    const double r = options.probe_radii[k];
    if (!(r > 0.0) || !std::isfinite(r)) {
      throw InputError("point " + std::to_string(k + 1) + ": the tip radius must be a positive number of mm, not " +
                       mm(r));
    }
  }
  return geometry::TipRadii(options.probe_radii);
}

}  // namespace probecomp::compensation::detail
