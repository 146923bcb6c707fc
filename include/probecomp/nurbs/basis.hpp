#pragma once
// B-spline basis functions and their derivatives (The NURBS Book, A2.2 and A2.3).

#include <cstddef>

#include "probecomp/nurbs/knot_vector.hpp"

namespace probecomp::nurbs {

// A2.2: the p+1 non-vanishing basis functions N_{span-p,p}(u) .. N_{span,p}(u), written to N[0..p].
void basis_functions(const KnotVector& U, int span, double u, double* N);

namespace detail {

// Whether knot span `span` is a Bézier span: its p knots on each side all equal to its ends, as after refinement to
// Bézier form (the closest-point search's surfaces).
[[nodiscard]] inline bool is_bezier_span(const KnotVector& U, int span) {
  const int p = U.degree();
  const auto k = U.knots();
  for (int i = 1; i < p; ++i) {
    if (k[static_cast<std::size_t>(span - i)] != k[static_cast<std::size_t>(span)] ||
        k[static_cast<std::size_t>(span + 1 + i)] != k[static_cast<std::size_t>(span + 1)]) {
      return false;
    }
  }
  return true;
}

// A cubic's values, first and second derivatives on a Bézier span: the Bernstein triangle (basis.cpp's
// bernstein_impl<3> with n = 2) written out, the same products and sums (its terms with a zero, s·0 and t·0, left
// out: for t in [0, 1] they add exactly nothing), without its zeroed table and loops. Inline, here: the
// closest-point search's Newton evaluates it twice a step, and a call from another file made the evaluation spill.
inline void cubic_bernstein_d2(const KnotVector& U, int span, double u, double* ders) {
  const double a = U.knots()[static_cast<std::size_t>(span)];
  const double h = U.knots()[static_cast<std::size_t>(span) + 1] - a;
  const double inv_h = 1.0 / h;
  const double t = (u - a) * inv_h, s = 1.0 - t;
  // B^1 = (s, t); B^2 = (s·s, s·t + t·s, t·t); B^3 from B^2 likewise (B[d][i] = s·B[d−1][i] + t·B[d−1][i−1]).
  const double b20 = s * s, b21 = s * t + t * s, b22 = t * t;
  ders[0] = s * b20;
  ders[1] = s * b21 + t * b20;
  ders[2] = s * b22 + t * b21;
  ders[3] = t * b22;
  const double f1 = 3 * inv_h;
  ders[4] = f1 * (0.0 - b20);
  ders[5] = f1 * (b20 - b21);
  ders[6] = f1 * (b21 - b22);
  ders[7] = f1 * (b22 - 0.0);
  const double f2 = 6 * (inv_h * inv_h);
  ders[8] = f2 * ((0.0 - 2.0 * 0.0) + s);
  ders[9] = f2 * ((0.0 - 2.0 * s) + t);
  ders[10] = f2 * ((s - 2.0 * t) + 0.0);
  ders[11] = f2 * ((t - 2.0 * 0.0) + 0.0);
}

// basis_function_derivatives on a Bézier span, n ≤ 2, any degree: the Bernstein triangle (basis.cpp).
void bezier_span_derivatives(const KnotVector& U, int span, double u, int n, double* ders);
// basis_function_derivatives by A2.3, for any span (basis.cpp).
void basis_function_derivatives_a23(const KnotVector& U, int span, double u, int n, double* ders);

}  // namespace detail

// A2.3: derivatives of order 0..n of the same p+1 functions; ders[k*(p+1) + j] = N^(k)_{span-p+j,p}(u).
// Orders above p are zero. n is at most 2 here (all the kernel needs) and at most kMaxDegree in general.
// A Bézier span (n ≤ 2) takes the Bernstein form, decided here once for either path.
inline void basis_function_derivatives(const KnotVector& U, int span, double u, int n, double* ders) {
  if (n <= 2 && detail::is_bezier_span(U, span)) {
    if (n == 2 && U.degree() == 3) return detail::cubic_bernstein_d2(U, span, u, ders);
    return detail::bezier_span_derivatives(U, span, u, n, ders);
  }
  detail::basis_function_derivatives_a23(U, span, u, n, ders);
}

}  // namespace probecomp::nurbs
