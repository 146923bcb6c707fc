#pragma once
// The checks made of a run's input before anything else: the model and the tip radii, where the points lie and
// how they spread. Each throws InputError saying what to check. Private to compensation/.

#include <cstddef>
#include <span>

#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/model.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/geometry/rigid.hpp"
#include "probecomp/geometry/tip_radii.hpp"

namespace probecomp::compensation::detail {

// Points identical to within this (mm) are one position: far below any CMM's resolution, far above rounding.
inline constexpr double kSamePosition = 1e-9;

// Stops the run when the points are nowhere near the model (wrong file, frame or unit): ICP would otherwise
// "align" them to whatever is nearest.
void check_points_near(const cad::ModelLocator& locator, std::span<const Point3> points,
                       const geometry::RigidTransform& initial, double fraction);

// Refuses a point set that cannot fix the part (issue 20): every point at one position (a probe that did not
// move, a file of repeated rows), or all on one line (about which nothing fixes the part's rotation, and across
// which no surface is measured). Principal spreads from the points' covariance.
void check_point_spread(std::span<const Point3> raw);

// What both methods and prepare_model need before anything else.
void check_model_and_radii(const cad::Model& model, const geometry::TipRadii& radii, std::size_t points);

// The tip radius of every point: probe_radii where given (each checked, naming the point), else probe_radius.
geometry::TipRadii tip_radii(const CompensateOptions& options, std::size_t points);

}  // namespace probecomp::compensation::detail
