#include "probecomp/nurbs/surface.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "probecomp/geometry/cpu.hpp"
#include "probecomp/nurbs/basis.hpp"
#include "probecomp/nurbs/knot_insertion.hpp"

#if PROBECOMP_HAVE_AVX_PATH
#include <immintrin.h>
#endif

namespace probecomp::nurbs {

namespace detail {
std::atomic<bool> avx_evaluation{true};
}  // namespace detail

Surface::Surface(KnotVector U, KnotVector V, const std::vector<Point3>& P, const std::vector<double>& w)
    : U_(std::move(U)), V_(std::move(V)) {
  if (!w.empty() && w.size() != P.size()) throw InvalidGeometry("surface weights and control points differ in number");
  Pw_.resize(P.size());
  for (std::size_t k = 0; k < P.size(); ++k) {
    const double wk = w.empty() ? 1.0 : w[k];
    Pw_[k] << wk * P[k], wk;
  }
  validate();
}

Surface::Surface(KnotVector U, KnotVector V, std::vector<HomogeneousPoint> Pw)
    : U_(std::move(U)), V_(std::move(V)), Pw_(std::move(Pw)) {
  validate();
}

void Surface::validate() {
  const auto expected = static_cast<std::size_t>(num_u()) * static_cast<std::size_t>(num_v());
  if (Pw_.size() != expected) {
    throw InvalidGeometry("surface has " + std::to_string(Pw_.size()) + " control points but its knot vectors need " +
                          std::to_string(num_u()) + " x " + std::to_string(num_v()));
  }
  for (std::size_t k = 0; k < Pw_.size(); ++k) {
    if (!(Pw_[k].w() > 0.0) || !Pw_[k].allFinite()) {
      throw InvalidGeometry("control point " + std::to_string(k) + " has a non-positive or non-finite weight");
    }
  }
  rational_ = std::any_of(Pw_.begin(), Pw_.end(), [&](const HomogeneousPoint& q) { return q.w() != Pw_[0].w(); });
}

Point3 Surface::control_point(int i, int j) const {
  const auto& q = homogeneous(i, j);
  return q.head<3>() / q.w();
}

namespace {

#if PROBECOMP_HAVE_AVX_PATH
// The bicubic tensor sum below in 256-bit registers: a homogeneous point is one register instead of two, half the
// multiplications and additions of the SSE2 form (the closest-point Newton's evaluation, about 2.7 a query). Each
// lane takes the same multiplication and addition in the same order (no fused multiply-add: -ffp-contract=off and
// no FMA intrinsic), so the results are the portable form's bit for bit; tests compare the two.
template <int D>
__attribute__((target("avx"))) void bicubic_tensor_sum_avx(const HomogeneousPoint* net, int stride, const double* Nu,
                                                           const double* Nv, HomogeneousPoint (&A)[D + 1][D + 1]) {
  __m256d a[D + 1][D + 1];
  for (int k = 0; k <= D; ++k)
    for (int l = 0; l + k <= D; ++l) a[k][l] = _mm256_setzero_pd();
  for (int i = 0; i <= 3; ++i) {
    const HomogeneousPoint* row = net + i * stride;
    __m256d T[D + 1];
    for (int l = 0; l <= D; ++l) T[l] = _mm256_setzero_pd();
    for (int j = 0; j <= 3; ++j) {
      const __m256d P = _mm256_loadu_pd(row[j].data());
      for (int l = 0; l <= D; ++l) T[l] = _mm256_add_pd(T[l], _mm256_mul_pd(_mm256_set1_pd(Nv[l * 4 + j]), P));
    }
    for (int k = 0; k <= D; ++k) {
      const __m256d nk = _mm256_set1_pd(Nu[k * 4 + i]);
      for (int l = 0; l + k <= D; ++l) a[k][l] = _mm256_add_pd(a[k][l], _mm256_mul_pd(nk, T[l]));
    }
  }
  for (int k = 0; k <= D; ++k)
    for (int l = 0; l + k <= D; ++l) _mm256_storeu_pd(A[k][l].data(), a[k][l]);
}
#endif

// Derivatives A[k][l] = ∂^{k+l} Sw / ∂u^k ∂v^l of the homogeneous surface for k + l <= D (A3.6).
// Summing each row of the net over v first and then the rows over u costs (p+1)(q+1)(D+1) + (p+1)·#(k,l)
// four-vector operations instead of (p+1)(q+1)·#(k,l). P, Q > 0 are the degrees fixed at compile time, so that the
// loops unroll; called with 0, a bicubic surface (the closest-point Newton's) is passed on to <D, 3, 3> and any other
// reads its degrees at run time. The arithmetic and its order are the same either way: the results are bit-identical.
template <int D, int P = 0, int Q = 0>
void homogeneous_derivatives(const Surface& s, double u, double v, HomogeneousPoint (&A)[D + 1][D + 1],
                             KnotSpans spans = {}) {
  if constexpr (P == 0 && Q == 0) {
    if (s.p() == 3 && s.q() == 3) return homogeneous_derivatives<D, 3, 3>(s, u, v, A, spans);
  }
  const int p = P > 0 ? P : s.p();
  const int q = Q > 0 ? Q : s.q();
  const Domain dom = s.domain();
  u = std::clamp(u, dom.u0, dom.u1);
  v = std::clamp(v, dom.v0, dom.v1);
  const int su = spans.u >= 0 ? spans.u : s.U().find_span(u);
  const int sv = spans.v >= 0 ? spans.v : s.V().find_span(v);
  double Nu[(D + 1) * (kMaxDegree + 1)];
  double Nv[(D + 1) * (kMaxDegree + 1)];
  if constexpr (D == 0) {
    basis_functions(s.U(), su, u, Nu);
    basis_functions(s.V(), sv, v, Nv);
  } else {
    basis_function_derivatives(s.U(), su, u, D, Nu);
    basis_function_derivatives(s.V(), sv, v, D, Nv);
  }
  const int stride = s.num_v();
  const HomogeneousPoint* net = s.homogeneous().data();
#if PROBECOMP_HAVE_AVX_PATH
  if constexpr (P == 3 && Q == 3) {
    if (geometry::cpu_has_avx() && detail::avx_evaluation.load(std::memory_order_relaxed)) {
      return bicubic_tensor_sum_avx<D>(net + (su - p) * stride + (sv - q), stride, Nu, Nv, A);
    }
  }
#endif
  for (int k = 0; k <= D; ++k)
    for (int l = 0; l + k <= D; ++l) A[k][l].setZero();

  for (int i = 0; i <= p; ++i) {
    const HomogeneousPoint* row = net + (su - p + i) * stride + (sv - q);
    HomogeneousPoint T[D + 1];
    for (int l = 0; l <= D; ++l) T[l].setZero();
    for (int j = 0; j <= q; ++j) {
      for (int l = 0; l <= D; ++l) T[l] += Nv[l * (q + 1) + j] * row[j];
    }
    for (int k = 0; k <= D; ++k) {
      const double nk = Nu[k * (p + 1) + i];
      for (int l = 0; l + k <= D; ++l) A[k][l] += nk * T[l];
    }
  }
}

// A4.4 written out for k + l <= order (at most 2), with A = homogeneous point part and w its weight part:
//   S^{kl} = (A^{kl} - Σ_{j=1..l} C(l,j) w^{0j} S^{k,l-j} - Σ_{i=1..k} C(k,i) w^{i0} S^{k-i,l}
//             - Σ_{i=1..k} Σ_{j=1..l} C(k,i) C(l,j) w^{ij} S^{k-i,l-j}) / w.
// The mixed term needs all three sums (tinynurbs drops one); tests check it by central differences. Orders above
// `order` are left zero. With equal weights (s not rational) the weight's derivatives vanish and S^{kl} = A^{kl}/w.
SurfaceD2 rational_derivatives(const Surface& s, const HomogeneousPoint (&A)[3][3], int order) {
  if (!s.is_rational()) {
    // Equal weights w: S = A/w and its derivatives alike, exactly (A4.4's weight derivatives vanish; computed they
    // would be rounding of Σ N' = 0). The Newton of every closest point evaluates this.
    const double w = s.homogeneous()[0].w();
    SurfaceD2 r;
    r.S = A[0][0].head<3>() / w;
    r.Su = r.Sv = r.Suu = r.Suv = r.Svv = Vector3::Zero();
    if (order >= 1) {
      r.Su = A[1][0].head<3>() / w;
      r.Sv = A[0][1].head<3>() / w;
    }
    if (order >= 2) {
      r.Suu = A[2][0].head<3>() / w;
      r.Suv = A[1][1].head<3>() / w;
      r.Svv = A[0][2].head<3>() / w;
    }
    return r;
  }
  // One division: its reciprocal multiplies (18 divisions were a fifth of a rational bicubic's evaluation).
  const double inv_w = 1.0 / A[0][0].w();
  SurfaceD2 r;
  r.S = A[0][0].head<3>() * inv_w;
  r.Su = r.Sv = r.Suu = r.Suv = r.Svv = Vector3::Zero();
  if (order >= 1) {
    r.Su = (A[1][0].head<3>() - A[1][0].w() * r.S) * inv_w;
    r.Sv = (A[0][1].head<3>() - A[0][1].w() * r.S) * inv_w;
  }
  if (order >= 2) {
    r.Suu = (A[2][0].head<3>() - 2.0 * A[1][0].w() * r.Su - A[2][0].w() * r.S) * inv_w;
    r.Suv = (A[1][1].head<3>() - A[0][1].w() * r.Su - A[1][0].w() * r.Sv - A[1][1].w() * r.S) * inv_w;
    r.Svv = (A[0][2].head<3>() - 2.0 * A[0][1].w() * r.Sv - A[0][2].w() * r.S) * inv_w;
  }
  return r;
}

}  // namespace

Point3 evaluate(const Surface& s, double u, double v, KnotSpans spans) {
  HomogeneousPoint A[1][1];
  homogeneous_derivatives<0>(s, u, v, A, spans);
  return A[0][0].head<3>() / A[0][0].w();
}

SurfaceD1 derivatives_d1(const Surface& s, double u, double v) {
  HomogeneousPoint A[2][2];
  homogeneous_derivatives<1>(s, u, v, A);
  const double w = A[0][0].w();
  SurfaceD1 r;
  r.S = A[0][0].head<3>() / w;
  r.Su = (A[1][0].head<3>() - A[1][0].w() * r.S) / w;
  r.Sv = (A[0][1].head<3>() - A[0][1].w() * r.S) / w;
  return r;
}

SurfaceD2 derivatives_d2(const Surface& s, double u, double v, KnotSpans spans) {
  HomogeneousPoint A[3][3];
  homogeneous_derivatives<2>(s, u, v, A, spans);
  return rational_derivatives(s, A, 2);
}

GridRows::GridRows(const Surface& s, std::vector<double> tv, int order)
    : s_(s), tv_(std::move(tv)), order_(std::clamp(order, 0, 2)) {
  const int q = s.q();
  const Domain dom = s.domain();
  span_v_.resize(tv_.size());
  Nv_.assign(tv_.size() * 3 * static_cast<std::size_t>(q + 1), 0.0);
  for (std::size_t b = 0; b < tv_.size(); ++b) {
    const double v = std::clamp(tv_[b], dom.v0, dom.v1);
    span_v_[b] = s.V().find_span(v);
    basis_function_derivatives(s.V(), span_v_[b], v, std::min(order_, q), &Nv_[b * 3 * static_cast<std::size_t>(q + 1)]);
  }
}

void GridRows::row(double u_in, std::span<SurfaceD2> out) const {
  const Surface& s = s_;
  const int p = s.p(), q = s.q(), nv = s.num_v();
  const int k_max = order_;
  const Domain dom = s.domain();
  const double u = std::clamp(u_in, dom.u0, dom.u1);
  const int span_u = s.U().find_span(u);
  double Nu[3 * (kMaxDegree + 1)] = {};
  basis_function_derivatives(s.U(), span_u, u, std::min(k_max, p), Nu);
  // T[k][j] = Σ_i N_i^(k)(u) Pw_ij: the row's partial sums, for every column j of the net.
  thread_local std::vector<HomogeneousPoint> T;
  T.assign(3 * static_cast<std::size_t>(nv), HomogeneousPoint::Zero());
  for (int k = 0; k <= k_max; ++k) {
    for (int i = 0; i <= p; ++i) {
      const double n = Nu[k * (p + 1) + i];
      if (n == 0.0) continue;
      const HomogeneousPoint* net_row = &s.homogeneous()[static_cast<std::size_t>((span_u - p + i) * nv)];
      for (int j = 0; j < nv; ++j) T[static_cast<std::size_t>(k * nv + j)] += n * net_row[j];
    }
  }
  for (std::size_t b = 0; b < tv_.size(); ++b) {
    const double* N = &Nv_[b * 3 * static_cast<std::size_t>(q + 1)];
    HomogeneousPoint A[3][3];
    for (auto& r : A)
      for (auto& x : r) x.setZero();
    for (int j = 0; j <= q; ++j) {
      const std::size_t col = static_cast<std::size_t>(span_v_[b] - q + j);
      for (int k = 0; k <= k_max; ++k) {
        for (int l = 0; k + l <= k_max; ++l) A[k][l] += N[l * (q + 1) + j] * T[static_cast<std::size_t>(k * nv) + col];
      }
    }
    out[b] = rational_derivatives(s, A, k_max);
  }
}

UnitNormal unit_normal(const Surface& s, double u, double v) {
  const SurfaceD1 d = derivatives_d1(s, u, v);
  return unit_normal(s, u, v, d.Su, d.Sv);
}

UnitNormal unit_normal(const Surface& s, double u, double v, const Vector3& Su, const Vector3& Sv) {
  // |S_u × S_v| below this fraction of |S_u||S_v| (sine of the angle between the tangents) counts as
  // vanishing: at 1e-10 the normal's direction is still good to about 1e-6 rad from rounding alone.
  constexpr double kParallelTangents = 1e-10;
  // A tangent shorter than this fraction of the other is a collapsed edge's (a pole's) to rounding: its
  // direction is noise (the edge's coincident control points differ in their last bits), so S_u × S_v is
  // meaningless there even when not small. Points this close to a pole are given its limit normal.
  constexpr double kCollapsedTangent = 1e-7;
  Vector3 n = Su.cross(Sv);
  const double scale = Su.norm() * Sv.norm();
  const bool collapsed = std::min(Su.norm(), Sv.norm()) <= kCollapsedTangent * std::max(Su.norm(), Sv.norm());
  if (!collapsed && n.norm() > kParallelTangents * scale && n.norm() > 0.0) return {UnitNormal::Status::OK, n.normalized()};

  // At a collapsed edge one tangent vanishes; the normal is its limit from inside the domain. If S_u = 0 along
  // the edge v = v0, then S_u(u, v0 + δ) ≈ δ·S_uv and the limit of S_u × S_v is the direction of δ·S_uv × S_v
  // (L'Hôpital); likewise S_v = 0 along u = u0 gives δ·S_u × S_uv.
  const Domain dom = s.domain();
  const double du_dir = (u - dom.u0 < dom.u1 - u) ? 1.0 : -1.0;
  const double dv_dir = (v - dom.v0 < dom.v1 - v) ? 1.0 : -1.0;
  const SurfaceD2 d2 = derivatives_d2(s, u, v);
  const double su = d2.Su.norm();
  const double sv = d2.Sv.norm();
  Vector3 limit = Vector3::Zero();
  if (su < sv) {
    limit = dv_dir * d2.Suv.cross(d2.Sv);
    if (limit.norm() <= kParallelTangents * d2.Suv.norm() * sv) limit.setZero();
  } else if (sv < su) {
    limit = du_dir * d2.Su.cross(d2.Suv);
    if (limit.norm() <= kParallelTangents * su * d2.Suv.norm()) limit.setZero();
  }
  if (limit.norm() > 0.0) return {UnitNormal::Status::FromNeighbourhood, limit.normalized()};

  // Both tangents vanish (an apex) or the limit above degenerates too: step inwards, growing the step until
  // the tangents separate.
  for (double h = 1e-8; h <= 1e-3; h *= 10.0) {
    const double uu = u + du_dir * h * (dom.u1 - dom.u0);
    const double vv = v + dv_dir * h * (dom.v1 - dom.v0);
    const SurfaceD1 e = derivatives_d1(s, uu, vv);
    n = e.Su.cross(e.Sv);
    if (n.norm() > kParallelTangents * e.Su.norm() * e.Sv.norm() && n.norm() > 0.0) {
      return {UnitNormal::Status::FromNeighbourhood, n.normalized()};
    }
  }
  return {UnitNormal::Status::Degenerate, Vector3::Zero()};
}

BoundingBox bounding_box(const Surface& s) {
  BoundingBox box;
  for (const auto& q : s.homogeneous()) box.extend(q.head<3>() / q.w());
  return box;
}

namespace {
// Each column j (fixed v index) of the net is a curve in u; A5.3 refines the surface by refining each column.
template <class CurveOperation>
Surface apply_to_columns(const Surface& s, CurveOperation op) {
  const int nu = s.num_u();
  const int nv = s.num_v();
  std::vector<HomogeneousPoint> column(nu);
  std::vector<HomogeneousPoint> Qw;
  KnotVector UQ;
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) column[i] = s.homogeneous(i, j);
    auto [U, Q] = op(s.U(), column);
    if (j == 0) {
      UQ = std::move(U);
      Qw.resize(static_cast<std::size_t>(UQ.num_basis()) * nv);
    }
    for (int i = 0; i < UQ.num_basis(); ++i) Qw[i * nv + j] = Q[i];
  }
  return Surface(std::move(UQ), s.V(), std::move(Qw));
}
}  // namespace

Surface insert_knot_u(const Surface& s, double u, int r) {
  return apply_to_columns(s, [&](const KnotVector& U, const auto& P) { return insert_knot_homogeneous(U, P, u, r); });
}

Surface refine_knots_u(const Surface& s, const std::vector<double>& X) {
  return apply_to_columns(s, [&](const KnotVector& U, const auto& P) { return refine_knots_homogeneous(U, P, X); });
}

Surface refine_knots_v(const Surface& s, const std::vector<double>& X) { return transposed(refine_knots_u(transposed(s), X)); }

Surface transposed(const Surface& s) {
  const int nu = s.num_u();
  const int nv = s.num_v();
  std::vector<HomogeneousPoint> Qw(s.homogeneous().size());
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) Qw[j * nu + i] = s.homogeneous(i, j);
  return Surface(s.V(), s.U(), std::move(Qw));
}

Surface insert_knot_v(const Surface& s, double v, int r) { return transposed(insert_knot_u(transposed(s), v, r)); }

Surface transformed(const Surface& s, const Eigen::Isometry3d& T) {
  std::vector<HomogeneousPoint> Qw(s.homogeneous());
  for (HomogeneousPoint& q : Qw) {
    // (w·P, w) ↦ (w·(R·P + t), w) = (R·(w·P) + w·t, w).
    q.head<3>() = T.linear() * q.head<3>() + q.w() * T.translation();
  }
  return Surface(s.U(), s.V(), std::move(Qw));
}

}  // namespace probecomp::nurbs
