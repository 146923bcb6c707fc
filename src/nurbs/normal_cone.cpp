#include "probecomp/nurbs/normal_cone.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

#include "probecomp/nurbs/de_casteljau.hpp"
#include "probecomp/nurbs/knot_vector.hpp"

namespace probecomp::nurbs {

namespace {

// A scalar polynomial in bivariate Bernstein form, as BernsteinVectorPatch.
struct ScalarPatch {
  int du = 0, dv = 0;
  std::vector<double> c;
};

// Binomial coefficients C(n, k) for n up to the normal polynomial's degree, 3·kMaxDegree − 1.
constexpr int kMaxBinomial = 3 * kMaxDegree;
const std::array<std::array<double, kMaxBinomial + 1>, kMaxBinomial + 1>& binomials() {
  static const auto table = [] {
    std::array<std::array<double, kMaxBinomial + 1>, kMaxBinomial + 1> C{};
    for (int n = 0; n <= kMaxBinomial; ++n) {
      C[n][0] = 1.0;
      for (int k = 1; k <= n; ++k) C[n][k] = C[n - 1][k - 1] + (k < n ? C[n - 1][k] : 0.0);
    }
    return C;
  }();
  return table;
}

// The product of two Bernstein polynomials of degrees (m1, n1) and (m2, n2) (Farouki & Rajan 1988):
// h_rs = Σ_{i+k=r, j+l=s} C(m1,i) C(m2,k) C(n1,j) C(n2,l) / (C(m1+m2,r) C(n1+n2,s)) · f_ij g_kl.
// The factors split by direction, so each direction's table is made once per product.
template <class F, class G, class Op, class T>
void accumulate_product(const F& f, const G& g, Op op, std::vector<T>& h) {
  const auto& C = binomials();
  const int m = f.du + g.du, n = f.dv + g.dv;
  double fu[kMaxBinomial + 1][kMaxBinomial + 1], fv[kMaxBinomial + 1][kMaxBinomial + 1];
  for (int i = 0; i <= f.du; ++i)
    for (int k = 0; k <= g.du; ++k) fu[i][k] = C[f.du][i] * C[g.du][k] / C[m][i + k];
  for (int j = 0; j <= f.dv; ++j)
    for (int l = 0; l <= g.dv; ++l) fv[j][l] = C[f.dv][j] * C[g.dv][l] / C[n][j + l];
  for (int i = 0; i <= f.du; ++i)
    for (int j = 0; j <= f.dv; ++j) {
      const auto& a = f.c[static_cast<std::size_t>(i * (f.dv + 1) + j)];
      for (int k = 0; k <= g.du; ++k)
        for (int l = 0; l <= g.dv; ++l) {
          h[static_cast<std::size_t>((i + k) * (n + 1) + (j + l))] +=
              (fu[i][k] * fv[j][l]) * op(a, g.c[static_cast<std::size_t>(k * (g.dv + 1) + l)]);
        }
    }
}

// The u or v derivative's Bernstein coefficients, without the positive factor (degree): every term of N holds
// exactly one u and one v derivative, so the factors p·q are common to all of N and drop out of its direction.
template <class P>
P difference(const P& f, int direction) {
  P d;
  d.du = f.du - (direction == 0);
  d.dv = f.dv - (direction == 1);
  d.c.resize(static_cast<std::size_t>((d.du + 1) * (d.dv + 1)));
  for (int i = 0; i <= d.du; ++i)
    for (int j = 0; j <= d.dv; ++j) {
      const auto hi = f.c[static_cast<std::size_t>((i + (direction == 0)) * (f.dv + 1) + j + (direction == 1))];
      const auto lo = f.c[static_cast<std::size_t>(i * (f.dv + 1) + j)];
      d.c[static_cast<std::size_t>(i * (d.dv + 1) + j)] = hi - lo;
    }
  return d;
}

// N += s · (a × b) for scalar s and vector polynomials a, b, all raised to N's degree through the products.
void add_scaled_cross(const ScalarPatch& s, const BernsteinVectorPatch& a, const BernsteinVectorPatch& b, BernsteinVectorPatch& N) {
  BernsteinVectorPatch ab{a.du + b.du, a.dv + b.dv, {}};
  ab.c.assign(static_cast<std::size_t>((ab.du + 1) * (ab.dv + 1)), Vector3::Zero());
  accumulate_product(a, b, [](const Vector3& x, const Vector3& y) -> Vector3 { return x.cross(y); }, ab.c);
  assert(s.du + ab.du == N.du && s.dv + ab.dv == N.dv);
  accumulate_product(s, ab, [](double x, const Vector3& y) -> Vector3 { return x * y; }, N.c);
}

}  // namespace

BernsteinVectorPatch normal_polynomial(int p, int q, std::span<const HomogeneousPoint> net) {
  assert(p >= 1 && q >= 1 && net.size() == static_cast<std::size_t>((p + 1) * (q + 1)));
  BernsteinVectorPatch A{p, q, {}};
  ScalarPatch W{p, q, {}};
  for (const HomogeneousPoint& P : net) {
    A.c.push_back(P.head<3>());
    W.c.push_back(P.w());
  }
  const BernsteinVectorPatch Au = difference(A, 0), Av = difference(A, 1);
  if (std::all_of(W.c.begin(), W.c.end(), [&](double w) { return w == W.c.front(); })) {
    // Equal weights: W_u = W_v = 0 and N = W (A_u × A_v), of degree (2p − 1, 2q − 1); the constant W > 0 drops out.
    BernsteinVectorPatch N{2 * p - 1, 2 * q - 1, {}};
    N.c.assign(static_cast<std::size_t>(2 * p * 2 * q), Vector3::Zero());
    accumulate_product(Au, Av, [](const Vector3& x, const Vector3& y) -> Vector3 { return x.cross(y); }, N.c);
    return N;
  }
  const ScalarPatch Wu = difference(W, 0), Wv = difference(W, 1);
  BernsteinVectorPatch N{3 * p - 1, 3 * q - 1, {}};
  N.c.assign(static_cast<std::size_t>(3 * p * 3 * q), Vector3::Zero());
  add_scaled_cross(W, Au, Av, N);
  add_scaled_cross(Wv, A, Au, N);
  add_scaled_cross(Wu, Av, A, N);
  return N;
}

BernsteinVectorPatch restrict_patch(const BernsteinVectorPatch& f, double u0, double u1, double v0, double v1) {
  BernsteinVectorPatch r = f;
  const std::size_t row = static_cast<std::size_t>(f.dv + 1);
  for (int j = 0; j <= f.dv; ++j) restrict_bezier(r.c.data() + j, f.du, row, u0, u1);
  for (int i = 0; i <= f.du; ++i) restrict_bezier(r.c.data() + static_cast<std::size_t>(i) * row, f.dv, 1, v0, v1);
  return r;
}

std::vector<BernsteinVectorPatch> split_patch(const BernsteinVectorPatch& f, int direction, int pieces) {
  std::vector<BernsteinVectorPatch> parts;
  parts.reserve(static_cast<std::size_t>(pieces));
  BernsteinVectorPatch rest = f;
  const int deg = direction == 0 ? f.du : f.dv;
  const int lines = direction == 0 ? f.dv + 1 : f.du + 1;
  const std::size_t stride = direction == 0 ? static_cast<std::size_t>(f.dv + 1) : 1;
  const std::size_t line_step = direction == 0 ? 1 : static_cast<std::size_t>(f.dv + 1);
  for (int k = 0; k + 1 < pieces; ++k) {
    // Cut the rest at t = 1 / (pieces − k): the left part is piece k, the right part the new rest.
    const double t = 1.0 / (pieces - k);
    BernsteinVectorPatch left = rest;
    for (int line = 0; line < lines; ++line) {
      Vector3* w = rest.c.data() + static_cast<std::size_t>(line) * line_step;
      Vector3* l = left.c.data() + static_cast<std::size_t>(line) * line_step;
      auto at = [&](Vector3* base, int i) -> Vector3& { return base[static_cast<std::size_t>(i) * stride]; };
      at(l, 0) = at(w, 0);
      for (int level = 1; level <= deg; ++level) {
        for (int i = 0; i <= deg - level; ++i) at(w, i) = (1.0 - t) * at(w, i) + t * at(w, i + 1);
        at(l, level) = at(w, 0);
      }
    }
    parts.push_back(std::move(left));
  }
  parts.push_back(std::move(rest));
  return parts;
}

double normal_cone_cosine(const BernsteinVectorPatch& N, const Vector3& axis) {
  // min over the coefficients of c·a / |c|, kept squared (c·a)² / |c|² while every c·a is positive.
  double cos_sq_min = 1.0;
  for (const Vector3& c : N.c) {
    const double along = c.dot(axis);
    if (!(along > 0.0)) return 0.0;  // a coefficient on or beyond 90°, or vanishing: no cone below 90°
    cos_sq_min = std::min(cos_sq_min, along * along / c.squaredNorm());
  }
  return std::sqrt(cos_sq_min);
}

}  // namespace probecomp::nurbs
