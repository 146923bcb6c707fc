#pragma once
// B-spline basis functions and their derivatives (The NURBS Book, A2.2 and A2.3).

#include "probecomp/nurbs/knot_vector.hpp"

namespace probecomp::nurbs {

// A2.2: the p+1 non-vanishing basis functions N_{span-p,p}(u) .. N_{span,p}(u), written to N[0..p].
void basis_functions(const KnotVector& U, int span, double u, double* N);

// A2.3: derivatives of order 0..n of the same p+1 functions; ders[k*(p+1) + j] = N^(k)_{span-p+j,p}(u).
// Orders above p are zero. n is at most 2 here (all the kernel needs) and at most kMaxDegree in general.
void basis_function_derivatives(const KnotVector& U, int span, double u, int n, double* ders);

}  // namespace probecomp::nurbs
