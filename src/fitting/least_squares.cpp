#include "probecomp/fitting/least_squares.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>

#include "probecomp/nurbs/basis.hpp"
#include "assembly.hpp"
#include "rational_basis.hpp"

namespace probecomp::fitting {

namespace {

using nurbs::kMaxDegree;
using nurbs::Surface;
using SparseMatrix = Eigen::SparseMatrix<double>;

using detail::RationalBasis;
using detail::rational_basis;
using detail::inside;
using detail::chunk_count;

// AᵀWA of the data in band form: entry (I, J) with I = (i, j), J = (i + di, j + dj), |di| ≤ p, |dj| ≤ q, at
// band[I·B + (di + p)·(2q + 1) + (dj + q)], B = (2p + 1)(2q + 1). Every row of A has its (p+1)(q+1) non-zeros
// inside that band, so the matrix is never formed densely. AᵀWx alongside.
struct NormalEquations {
  int p, q, nu, nv, B;
  std::vector<double> band;
  Eigen::MatrixX3d rhs;

  NormalEquations(const Surface& s)
      : p(s.p()), q(s.q()), nu(s.num_u()), nv(s.num_v()), B((2 * s.p() + 1) * (2 * s.q() + 1)),
        band(static_cast<std::size_t>(nu) * nv * B, 0.0), rhs(Eigen::MatrixX3d::Zero(nu * nv, 3)) {}

  void add(const RationalBasis& rb, const Point3& x, double w) {
    const int cols = q + 1;
    const int n = (p + 1) * cols;
    for (int k = 0; k < n; ++k) {
      const int a = k / cols, b = k % cols;
      const int I = (rb.i0 + a) * nv + (rb.j0 + b);
      const double wr = w * rb.R[k];
      rhs.row(I) += wr * x.transpose();
      double* row = band.data() + static_cast<std::size_t>(I) * B;
      for (int k2 = 0; k2 < n; ++k2) {
        const int a2 = k2 / cols, b2 = k2 % cols;
        row[(a2 - a + p) * (2 * q + 1) + (b2 - b + q)] += wr * rb.R[k2];
      }
    }
  }

  void add(const NormalEquations& o) {
    for (std::size_t k = 0; k < band.size(); ++k) band[k] += o.band[k];
    rhs += o.rhs;
  }

  [[nodiscard]] double mean_diagonal() const {
    double sum = 0.0;
    const int centre = p * (2 * q + 1) + q;
    for (int I = 0; I < nu * nv; ++I) sum += band[static_cast<std::size_t>(I) * B + centre];
    return sum / (nu * nv);
  }

  void triplets(std::vector<Eigen::Triplet<double>>& out) const {
    for (int i = 0; i < nu; ++i) {
      for (int j = 0; j < nv; ++j) {
        const int I = i * nv + j;
        const double* row = band.data() + static_cast<std::size_t>(I) * B;
        for (int di = -p; di <= p; ++di) {
          for (int dj = -q; dj <= q; ++dj) {
            if (i + di < 0 || i + di >= nu || j + dj < 0 || j + dj >= nv) continue;
            const double value = row[(di + p) * (2 * q + 1) + (dj + q)];
            if (value != 0.0) out.emplace_back(I, (i + di) * nv + (j + dj), value);
          }
        }
      }
    }
  }
};

// Δ²ᵀΔ² for second differences of the control net along u and along v (a discrete bending energy).
SparseMatrix bending(int nu, int nv) {
  std::vector<Eigen::Triplet<double>> t;
  int row = 0;
  for (int i = 1; i + 1 < nu; ++i) {
    for (int j = 0; j < nv; ++j, ++row) {
      t.emplace_back(row, (i - 1) * nv + j, 1.0);
      t.emplace_back(row, i * nv + j, -2.0);
      t.emplace_back(row, (i + 1) * nv + j, 1.0);
    }
  }
  for (int i = 0; i < nu; ++i) {
    for (int j = 1; j + 1 < nv; ++j, ++row) {
      t.emplace_back(row, i * nv + j - 1, 1.0);
      t.emplace_back(row, i * nv + j, -2.0);
      t.emplace_back(row, i * nv + j + 1, 1.0);
    }
  }
  SparseMatrix D(row, nu * nv);
  D.setFromTriplets(t.begin(), t.end());
  return SparseMatrix(D.transpose() * D);
}

}  // namespace

std::vector<double> parametric_residuals(const Surface& s, std::span<const Point3> points,
                                         std::span<const SurfaceParameter> params) {
  std::vector<double> out(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024), [&](const auto& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      out[k] = (nurbs::evaluate(s, params[k].u, params[k].v) - points[k]).norm();
    }
  });
  return out;
}

FitResult fit_control_points(const Surface& start, std::span<const Point3> points,
                             std::span<const SurfaceParameter> params, std::span<const double> weights,
                             const FitOptions& options) {
  FitResult result{.status = FitResult::Status::NotDone, .surface = start};
  const std::size_t n_points = points.size();
  if (n_points == 0 || params.size() != n_points || (!weights.empty() && weights.size() != n_points)) return result;
  const nurbs::Domain dom = start.domain();
  double weight_sum = 0.0;
  for (std::size_t k = 0; k < n_points; ++k) {
    const double w = weights.empty() ? 1.0 : weights[k];
    if (!points[k].allFinite() || !inside(dom, params[k]) || !(w >= 0.0) || !std::isfinite(w)) return result;
    weight_sum += w;
  }
  if (!(weight_sum > 0.0)) return result;

  const int nu = start.num_u();
  const int nv = start.num_v();
  const int n = nu * nv;

  // Assembly, in fixed chunks.
  const NormalEquations empty(start);
  const std::size_t chunk_bytes = empty.band.size() * sizeof(double) + static_cast<std::size_t>(n) * 3 * sizeof(double);
  const std::size_t chunks = chunk_count(n_points, chunk_bytes);
  std::vector<NormalEquations> parts(chunks, empty);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    const std::size_t first = n_points * c / chunks;
    const std::size_t last = n_points * (c + 1) / chunks;
    RationalBasis rb;
    for (std::size_t k = first; k < last; ++k) {
      const double w = weights.empty() ? 1.0 : weights[k];
      if (w == 0.0) continue;
      rational_basis(start, params[k].u, params[k].v, rb);
      parts[c].add(rb, points[k], w);
    }
  });
  NormalEquations& normal = parts[0];
  for (std::size_t c = 1; c < chunks; ++c) normal.add(parts[c]);

  const double scale = normal.mean_diagonal();
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(n) * normal.B + static_cast<std::size_t>(n));
  normal.triplets(t);
  SparseMatrix AtWA(n, n);
  AtWA.setFromTriplets(t.begin(), t.end());
  SparseMatrix identity(n, n);
  identity.setIdentity();
  const SparseMatrix M = (options.pull * scale) * identity + (options.smoothness * scale) * bending(nu, nv);
  const SparseMatrix N = AtWA + M;

  Eigen::SimplicialLLT<SparseMatrix> cholesky(N);
  if (cholesky.info() != Eigen::Success) {
    result.status = FitResult::Status::NumericalError;
    return result;
  }

  Eigen::MatrixX3d P(n, 3);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) P.row(i * nv + j) = start.control_point(i, j).transpose();
  for (int it = 0; it < options.max_iterations; ++it) {
    Eigen::MatrixX3d next = cholesky.solve(normal.rhs + M * P);
    const double moved = (next - P).rowwise().norm().maxCoeff();
    P = std::move(next);
    result.iterations = it + 1;
    if (!std::isfinite(moved)) {
      result.status = FitResult::Status::NumericalError;
      return result;
    }
    if (moved < options.convergence) break;
  }

  std::vector<Point3> control(static_cast<std::size_t>(n));
  std::vector<double> w(static_cast<std::size_t>(n));
  for (int I = 0; I < n; ++I) {
    control[static_cast<std::size_t>(I)] = P.row(I).transpose();
    w[static_cast<std::size_t>(I)] = start.homogeneous()[static_cast<std::size_t>(I)].w();
  }
  result.surface = Surface(start.U(), start.V(), control, w);
  result.status = FitResult::Status::OK;

  const std::vector<double> r = parametric_residuals(result.surface, points, params);
  double sum = 0.0;
  for (std::size_t k = 0; k < n_points; ++k) {
    const double wk = weights.empty() ? 1.0 : weights[k];
    sum += wk * r[k] * r[k];
    if (wk > 0.0) result.max_residual = std::max(result.max_residual, r[k]);
  }
  result.rms = std::sqrt(sum / weight_sum);
  return result;
}

}  // namespace probecomp::fitting
