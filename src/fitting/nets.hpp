#pragma once
// Knot nets of the adaptive fit and its residuals along the normal and by span (nets.cpp). Private to fitting/.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "probecomp/fitting/least_squares.hpp"
#include "probecomp/geometry/types.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::fitting::detail {

// Each point's signed residual along the fit's unit normal at its parameters, and the size of the fit's smoothing
// bias there along the same normal (one evaluation of the surface serves both; `smoothing_bias` may be empty).
struct AlongNormal {
  std::vector<double> residual, bias;
};
[[nodiscard]] AlongNormal along_normal(const nurbs::Surface& s, std::span<const Point3> points,
                                       std::span<const SurfaceParameter> params,
                                       std::span<const Vector3> smoothing_bias);

// `s` with every knot span halved, in the direction whose spans are longer (millimetres along the surface), until it
// has at least `control_points` control points, or as many as it can without passing `cap`: the same shape on a
// finer net.
[[nodiscard]] nurbs::Surface uniformly_refined(nurbs::Surface s, double control_points, double cap);

// `start` with the knots of `fitted` it lacks inserted (each knot vector of `fitted` a refinement of the start's):
// the start's shape on the fit's net.
[[nodiscard]] nurbs::Surface on_net_of(const nurbs::Surface& start, const nurbs::Surface& fitted);

// Each span's spread of the residuals (AdaptiveFitResult::span_spread): 1.4826 × the median |standardised residual|
// over the in-fit points in it and the eight around it (`span`: each point's span, a · nsv + b), never below
// `sigma`; `sigma` where fewer than kMinLocalPoints.
[[nodiscard]] std::vector<double> span_spread(std::span<const double> standardised, std::span<const double> weights,
                                              std::span<const std::uint32_t> span, std::size_t nsu, std::size_t nsv,
                                              double sigma);

}  // namespace probecomp::fitting::detail
