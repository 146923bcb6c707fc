#pragma once
// The non-zero rational basis functions of a surface at a parameter, and their second derivatives: the rows of
// the least-squares fitters' design matrix and of the thin-plate energy. Private to fitting/.

#include "probecomp/nurbs/basis.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::fitting::detail {

// The (p+1)·(q+1) non-zero rational basis functions at (u, v) and the index of the first control point:
// R[a·(q+1) + b] belongs to control point (su − p + a, sv − q + b).
struct RationalBasis {
  int i0 = 0, j0 = 0;
  double R[(nurbs::kMaxDegree + 1) * (nurbs::kMaxDegree + 1)];
};

inline void rational_basis(const nurbs::Surface& s, double u, double v, RationalBasis& out) {
  const int p = s.p();
  const int q = s.q();
  const int su = s.U().find_span(u);
  const int sv = s.V().find_span(v);
  double Nu[nurbs::kMaxDegree + 1];
  double Nv[nurbs::kMaxDegree + 1];
  nurbs::basis_functions(s.U(), su, u, Nu);
  nurbs::basis_functions(s.V(), sv, v, Nv);
  out.i0 = su - p;
  out.j0 = sv - q;
  double W = 0.0;
  for (int a = 0; a <= p; ++a) {
    for (int b = 0; b <= q; ++b) {
      const double r = Nu[a] * Nv[b] * s.weight(out.i0 + a, out.j0 + b);
      out.R[a * (q + 1) + b] = r;
      W += r;
    }
  }
  const int n = (p + 1) * (q + 1);
  for (int k = 0; k < n; ++k) out.R[k] /= W;
}

// The second derivatives R_uu, R_uv, R_vv of the same functions, at (u, v) inside spans (su, sv), by the
// quotient rule on R = B/W (B = N_i N_j w_ij, W = Σ B): The NURBS Book eq. 4.20 applied to the basis.
struct RationalBasisD2 {
  int i0 = 0, j0 = 0;
  double Ruu[(nurbs::kMaxDegree + 1) * (nurbs::kMaxDegree + 1)];
  double Ruv[(nurbs::kMaxDegree + 1) * (nurbs::kMaxDegree + 1)];
  double Rvv[(nurbs::kMaxDegree + 1) * (nurbs::kMaxDegree + 1)];
};

inline void rational_basis_d2(const nurbs::Surface& s, int su, int sv, double u, double v, RationalBasisD2& out) {
  const int p = s.p();
  const int q = s.q();
  double Du[3 * (nurbs::kMaxDegree + 1)] = {};
  double Dv[3 * (nurbs::kMaxDegree + 1)] = {};
  nurbs::basis_function_derivatives(s.U(), su, u, 2, Du);
  nurbs::basis_function_derivatives(s.V(), sv, v, 2, Dv);
  out.i0 = su - p;
  out.j0 = sv - q;
  double W = 0, Wu = 0, Wv = 0, Wuu = 0, Wuv = 0, Wvv = 0;
  for (int a = 0; a <= p; ++a) {
    for (int b = 0; b <= q; ++b) {
      const double w = s.weight(out.i0 + a, out.j0 + b);
      W += Du[a] * Dv[b] * w;
      Wu += Du[p + 1 + a] * Dv[b] * w;
      Wv += Du[a] * Dv[q + 1 + b] * w;
      Wuu += Du[2 * (p + 1) + a] * Dv[b] * w;
      Wuv += Du[p + 1 + a] * Dv[q + 1 + b] * w;
      Wvv += Du[a] * Dv[2 * (q + 1) + b] * w;
    }
  }
  for (int a = 0; a <= p; ++a) {
    for (int b = 0; b <= q; ++b) {
      const int k = a * (q + 1) + b;
      const double w = s.weight(out.i0 + a, out.j0 + b);
      const double B = Du[a] * Dv[b] * w;
      const double Bu = Du[p + 1 + a] * Dv[b] * w;
      const double Bv = Du[a] * Dv[q + 1 + b] * w;
      const double Buu = Du[2 * (p + 1) + a] * Dv[b] * w;
      const double Buv = Du[p + 1 + a] * Dv[q + 1 + b] * w;
      const double Bvv = Du[a] * Dv[2 * (q + 1) + b] * w;
      const double R = B / W;
      const double Ru = (Bu - R * Wu) / W;
      const double Rv = (Bv - R * Wv) / W;
      out.Ruu[k] = (Buu - 2.0 * Ru * Wu - R * Wuu) / W;
      out.Rvv[k] = (Bvv - 2.0 * Rv * Wv - R * Wvv) / W;
      out.Ruv[k] = (Buv - Ru * Wv - Rv * Wu - R * Wuv) / W;
    }
  }
}

}  // namespace probecomp::fitting::detail
