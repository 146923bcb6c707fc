#pragma once
// Degree elevation of a surface in one direction by Bézier decomposition (The NURBS Book §5.5: decompose with
// A5.6's knot insertion, elevate each segment by eq. 5.36 in homogeneous space, join). The shape and the
// parametrisation are unchanged; each interior knot ends with multiplicity p + t, so the result is only C0 in
// parameter at the old knots. That loses nothing where the surface was C0 there anyway, as a degree-1 direction
// always is; A5.9 (which keeps the continuity) is not needed for that use.

#include "probecomp/nurbs/surface.hpp"

namespace probecomp::nurbs {

// Raise the degree in u (or v) by t ≥ 0. Throws InvalidGeometry if the new degree exceeds kMaxDegree.
[[nodiscard]] Surface elevate_degree_u(const Surface& s, int t);
[[nodiscard]] Surface elevate_degree_v(const Surface& s, int t);

}  // namespace probecomp::nurbs
