#pragma once
// Knot insertion (The NURBS Book, A5.1 for curves; A5.3 applies it to each row or column of a surface).

#include <utility>
#include <vector>

#include "probecomp/nurbs/knot_vector.hpp"
#include "probecomp/geometry/types.hpp"

namespace probecomp::nurbs {

// Inserts u r times into U and returns the new knot vector and homogeneous control points.
// Throws InvalidGeometry if u is outside the domain or the multiplicity would exceed the degree.
[[nodiscard]] std::pair<KnotVector, std::vector<HomogeneousPoint>> insert_knot_homogeneous(
    const KnotVector& U, const std::vector<HomogeneousPoint>& Pw, double u, int r);

// A5.4: inserts all knots of X (sorted, inside the domain) at once; the curve is unchanged.
// Throws InvalidGeometry if X is unsorted, leaves the domain, or raises a multiplicity above the degree.
[[nodiscard]] std::pair<KnotVector, std::vector<HomogeneousPoint>> refine_knots_homogeneous(
    const KnotVector& U, const std::vector<HomogeneousPoint>& Pw, const std::vector<double>& X);

}  // namespace probecomp::nurbs
