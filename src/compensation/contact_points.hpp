#pragma once
// A raw centre as the smallest tip's would be, and how far a fitted normal's error can put a contact point off:
// shared by the faces' fits (face_fits.cpp), the contact points (contact_points.cpp) and the warnings.
// Private to compensation/.

#include <cmath>
#include <cstddef>
#include <span>

#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/fitting/least_squares.hpp"
#include "probecomp/nurbs/surface.hpp"
#include "probecomp/registration/icp.hpp"

namespace probecomp::compensation::detail {

// Raw centre k as the smallest tip's centre would be: a larger tip's moved in by the difference of their radii
// along the outward normal (machine frame) of `fit` at `at` (the face's fitted centre surface, whose outward side
// is `outward`), or where there is no fit or it has no normal there, of the registered nominal face at the
// point's correspondence. Exact when the normal is the actual surface's.
Point3 as_smallest_tip(const PreparedModel& prepared, const registration::RegistrationResult& registration,
                       std::span<const Point3> raw, std::size_t k, const nurbs::Surface* fit = nullptr,
                       int outward = 1, fitting::SurfaceParameter at = {});

// How far off along the normal a contact point offset by r can be when the fit's normal is θ from the actual one.
inline double normal_doubt(double r, double theta) { return std::isnan(theta) ? r : r * (1.0 - std::cos(theta)); }
// That doubt is worth a warning from a micrometre (mm): what the users' tolerances are stated to.
inline constexpr double kNormalDoubtReported = 1e-3;

}  // namespace probecomp::compensation::detail
