#include "probecomp/nurbs/basis.hpp"

#include <algorithm>

namespace probecomp::nurbs {

namespace {

// A2.2, with the degree fixed at compile time where P > 0 (the loops unroll; the same arithmetic in the same order).
template <int P>
void basis_functions_impl(const KnotVector& U, int span, double u, double* N) {
  const int p = P > 0 ? P : U.degree();
  double left[kMaxDegree + 1];
  double right[kMaxDegree + 1];
  N[0] = 1.0;
  for (int j = 1; j <= p; ++j) {
    left[j] = u - U[span + 1 - j];
    right[j] = U[span + j] - u;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      const double temp = N[r] / (right[r + 1] + left[j - r]);
      N[r] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    N[j] = saved;
  }
}

}  // namespace

void basis_functions(const KnotVector& U, int span, double u, double* N) {
  if (U.degree() == 3) return basis_functions_impl<3>(U, span, u, N);  // bicubic fits and evaluations
  basis_functions_impl<0>(U, span, u, N);
}

namespace {

// A2.3 with the degree as a template parameter where it is known at compile time (P > 0): the loops unroll
// and the tables fit the degree; so does the order of the derivatives, N ≥ 0 (a bicubic's value, first and second
// derivatives: 507 instructions a call with n read at run time, 186 with it fixed, counted by callgrind on the
// 10 000-point case). P = 0 is the general case with the degree read at run time. The arithmetic
// and its order are the same either way, so both give bit-identical results. Every division of A2.3 is by a knot
// difference of the lower triangle: each is inverted once (p(p + 1)/2 divisions instead of about 26 for a cubic's
// second derivatives) and multiplied by, which makes the closest-point Newton, which evaluates this twice a step,
// markedly faster.
template <int P, int N = -1>
void derivatives_impl(const KnotVector& U, int span, double u, int n_runtime, double* ders) {
  const int n = N >= 0 ? N : n_runtime;
  const int p = P > 0 ? P : U.degree();
  constexpr int W = (P > 0 ? P : kMaxDegree) + 1;
  double ndu[W][W];  // ndu[j][r]: basis functions (upper triangle incl. diagonal) and knot differences
  double inv[W][W];  // inv[j][r] = 1 / ndu[j][r] in the lower triangle (j > r)
  // GCC cannot see that the cases with n read at run time read only the lower triangle they set
  // (-Wmaybe-uninitialized); zeroed there alone, so that the closest-point Newton's calls pay nothing for it.
  if constexpr (N < 0) std::fill(&inv[0][0], &inv[0][0] + W * W, 0.0);
  double a[2][W];
  double left[W];
  double right[W];

  ndu[0][0] = 1.0;
  for (int j = 1; j <= p; ++j) {
    left[j] = u - U[span + 1 - j];
    right[j] = U[span + j] - u;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      ndu[j][r] = right[r + 1] + left[j - r];  // lower triangle: knot differences
      inv[j][r] = 1.0 / ndu[j][r];
      const double temp = ndu[r][j - 1] * inv[j][r];
      ndu[r][j] = saved + right[r + 1] * temp;  // upper triangle: basis functions
      saved = left[j - r] * temp;
    }
    ndu[j][j] = saved;
  }
  for (int j = 0; j <= p; ++j) ders[j] = ndu[j][p];

  const int nk = std::min(n, p);
  for (int r = 0; r <= p; ++r) {
    int s1 = 0;
    int s2 = 1;
    a[0][0] = 1.0;
    for (int k = 1; k <= nk; ++k) {
      double d = 0.0;
      const int rk = r - k;
      const int pk = p - k;
      if (r >= k) {
        a[s2][0] = a[s1][0] * inv[pk + 1][rk];
        d = a[s2][0] * ndu[rk][pk];
      }
      const int j1 = (rk >= -1) ? 1 : -rk;
      const int j2 = (r - 1 <= pk) ? k - 1 : p - r;
      for (int j = j1; j <= j2; ++j) {
        a[s2][j] = (a[s1][j] - a[s1][j - 1]) * inv[pk + 1][rk + j];
        d += a[s2][j] * ndu[rk + j][pk];
      }
      if (r <= pk) {
        a[s2][k] = -a[s1][k - 1] * inv[pk + 1][r];
        d += a[s2][k] * ndu[r][pk];
      }
      ders[k * (p + 1) + r] = d;
      std::swap(s1, s2);
    }
  }
  // Multiply through by p!/(p-k)!.
  double factor = p;
  for (int k = 1; k <= nk; ++k) {
    for (int j = 0; j <= p; ++j) ders[k * (p + 1) + j] *= factor;
    factor *= (p - k);
  }
  for (int k = nk + 1; k <= n; ++k) {
    for (int j = 0; j <= p; ++j) ders[k * (p + 1) + j] = 0.0;
  }
}

// On a Bézier span (its p knots on each side all equal to its ends, as after refinement to Bézier form) the basis
// functions are the Bernstein polynomials of t = (u − a)/(b − a): from the triangle B^d_i = (1−t) B^{d−1}_i +
// t B^{d−1}_{i−1}, the k-th derivative is p!/(p−k)!/(b−a)^k times the k-th difference of B^{p−k} (The NURBS Book
// eqs. 1.7, 1.9). A fraction of A2.3's work, for the closest-point search, which evaluates only Bézier spans
// (detail::is_bezier_span, basis.hpp).
template <int P, int N = -1>
void bernstein_impl(const KnotVector& U, int span, double u, int n_runtime, double* ders) {
  const int n = N >= 0 ? N : n_runtime;
  const int p = P > 0 ? P : U.degree();
  constexpr int W = (P > 0 ? P : kMaxDegree) + 1;
  const double a = U.knots()[static_cast<std::size_t>(span)];
  const double h = U.knots()[static_cast<std::size_t>(span) + 1] - a;
  // One division: its latency, not the arithmetic, bounded this evaluation (three divisions in a chain).
  const double inv_h = 1.0 / h;
  const double t = (u - a) * inv_h, s = 1.0 - t;
  // B[d][i + 2] = B^d_i, with two zeros in front so that the differences below need no bounds tests.
  double B[W][W + 2] = {};
  B[0][2] = 1.0;
  for (int d = 1; d <= p; ++d) {
    for (int i = 0; i <= d; ++i) B[d][i + 2] = s * B[d - 1][i + 2] + t * B[d - 1][i + 1];
  }
  for (int i = 0; i <= p; ++i) ders[i] = B[p][i + 2];
  if (n >= 1) {
    const double f = p * inv_h;
    for (int i = 0; i <= p; ++i) ders[(p + 1) + i] = p >= 1 ? f * (B[p - 1][i + 1] - B[p - 1][i + 2]) : 0.0;
  }
  if (n >= 2) {
    const double f = p * (p - 1) * (inv_h * inv_h);
    for (int i = 0; i <= p; ++i) {
      ders[2 * (p + 1) + i] = p >= 2 ? f * (B[p - 2][i] - 2.0 * B[p - 2][i + 1] + B[p - 2][i + 2]) : 0.0;
    }
  }
}

}  // namespace

void detail::bezier_span_derivatives(const KnotVector& U, int span, double u, int n, double* ders) {
  switch (U.degree()) {
    case 1: return bernstein_impl<1>(U, span, u, n, ders);
    case 2: return bernstein_impl<2>(U, span, u, n, ders);
    // A cubic with n = 2 is taken by basis_function_derivatives itself (detail::cubic_bernstein_d2, basis.hpp).
    case 3: return bernstein_impl<3>(U, span, u, n, ders);
    default: return bernstein_impl<0>(U, span, u, n, ders);
  }
}

void detail::basis_function_derivatives_a23(const KnotVector& U, int span, double u, int n, double* ders) {
  switch (U.degree()) {
    case 1: return derivatives_impl<1>(U, span, u, n, ders);
    case 2: return derivatives_impl<2>(U, span, u, n, ders);
    case 3:  // the closest-point Newton's (n = 2) and the normals' (n = 1): with n known, the loops unroll fully
      if (n == 2) return derivatives_impl<3, 2>(U, span, u, n, ders);
      if (n == 1) return derivatives_impl<3, 1>(U, span, u, n, ders);
      return derivatives_impl<3>(U, span, u, n, ders);
    case 4: return derivatives_impl<4>(U, span, u, n, ders);
    case 5: return derivatives_impl<5>(U, span, u, n, ders);
    default: return derivatives_impl<0>(U, span, u, n, ders);
  }
}

}  // namespace probecomp::nurbs
