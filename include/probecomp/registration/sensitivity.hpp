#pragma once
// How far a registration would move, to first order, if some of its points were left out: whether registering
// again without them could be told from the registration there is (compensation leaves out the outliers its fits
// flag, compensation/pipeline.hpp).

#include <cstddef>
#include <span>

#include "probecomp/cad/locator.hpp"
#include "probecomp/geometry/rigid.hpp"
#include "probecomp/geometry/types.hpp"
#include "probecomp/registration/icp.hpp"

namespace probecomp::registration {

// The first order holds for a few points only: leaving out more than this share of the points used moves the
// robust scale, and so every weight, with them too.
inline constexpr double kMaxSkippedShare = 1e-3;

// To first order, how leaving the points `left_out` out moves the registration `r`: the Gauss–Newton step of
// their weighted residuals, δ = H⁺ Σ w r J (H⁺ the registration's covariance per unit variance, J as in
// constraints.hpp), a scaled twist about H's centre. `model` is the model `r` registered `machine_points` to, and
// `left_out` indexes `machine_points`. Points of weight 0 (not used) pull on nothing.
[[nodiscard]] geometry::Twist shift_leaving_out(const cad::ModelLocator& model,
                                                std::span<const Point3> machine_points, const RegistrationResult& r,
                                                std::span<const std::size_t> left_out);

// Whether leaving `left_out` out could move the registration by what ICP would tell: true for more than
// kMaxSkippedShare of the points used; else whether that step moves the data, by at most |ω| R + |t| (R: the
// farthest point from H's centre), by more than the tolerance ICP stops at (options.criteria).
[[nodiscard]] bool leaving_out_moves(const cad::ModelLocator& model, std::span<const Point3> machine_points,
                                     const RegistrationOptions& options, const RegistrationResult& r,
                                     std::span<const std::size_t> left_out);

}  // namespace probecomp::registration
