#pragma once
// The penalised fit's band algebra (band.cpp): the unknowns' order, a symmetric band matrix, its Cholesky factor,
// solves with it and the band of its inverse, and quadratic forms over that inverse. Private to fitting/.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <span>
#include <vector>

#include <tbb/scalable_allocator.h>

#include "probecomp/geometry/types.hpp"
#include "probecomp/nurbs/knot_vector.hpp"

namespace probecomp::fitting::detail {

// Storage of a band and of its inverse's band: megabytes each on a refined face, allocated afresh by every trial λ
// (penalized.cpp keeps each trial's factor and inverse). The system allocator mapped and unmapped them each time, and
// the page faults and zeroing of new pages took about a fifth of a fit with outliers; oneTBB's scalable allocator
// keeps freed blocks for the next trial (timings in docs/performance.md, "CI's time"). AddressSanitizer sees
// overflows only in its own allocator's blocks, so the sanitizer build keeps the standard one.
#if defined(__SANITIZE_ADDRESS__)
#define PROBECOMP_BAND_STANDARD_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PROBECOMP_BAND_STANDARD_ALLOCATOR 1
#endif
#endif
#ifdef PROBECOMP_BAND_STANDARD_ALLOCATOR
using BandValues = std::vector<double>;
#else
using BandValues = std::vector<double, tbb::scalable_allocator<double>>;
#endif

// Control point (i, j) → unknown I, the shorter direction inner so that the band is narrow: every pair of control
// points under one basis row (|Δi| ≤ p, |Δj| ≤ q) is then within b = p·nv + q (or q·nu + p) of each other.
struct Ordering {
  int nu = 0, nv = 0;
  bool v_inner = true;
  Ordering(int nu_, int nv_) : nu(nu_), nv(nv_), v_inner(nv_ <= nu_) {}
  [[nodiscard]] int index(int i, int j) const { return v_inner ? i * nv + j : j * nu + i; }
  [[nodiscard]] int bandwidth(int p, int q) const { return v_inner ? p * nv + q : q * nu + p; }
};

// A symmetric band matrix of order n and half-bandwidth b, its lower half by rows: (I, J), I − b ≤ J ≤ I, at
// a[I·(b+1) + J − I + b]. Rows are contiguous, so the factorisation's inner products run over contiguous memory.
// `first`, when not empty, is its envelope (a variable band): row I is zero left of column first[I] (≥ I − b,
// non-decreasing in I). The Cholesky factor keeps no fill outside an envelope (Jennings 1966), and the inverse's
// entries inside it are found from those alone (Takahashi's recurrence reads Z_kj only for k, j inside), so the
// factor, the solves and band_inverse skip what lies outside: a THB basis's rows are narrower than its widest
// (docs/performance.md). The same numbers as without it, bit for bit; band_inverse then leaves Z zero outside.
struct Band {
  int n = 0, b = 0;
  BandValues a;
  std::vector<int> first;
  Band() = default;
  Band(int n_, int b_) : n(n_), b(b_), a(static_cast<std::size_t>(n_) * static_cast<std::size_t>(b_ + 1), 0.0) {}
  // The first column of row I that may be non-zero.
  [[nodiscard]] int row_start(int I) const { return first.empty() ? std::max(0, I - b) : first[static_cast<std::size_t>(I)]; }
  [[nodiscard]] double& at(int I, int J) { return a[static_cast<std::size_t>(I) * (b + 1) + (J - I + b)]; }
  [[nodiscard]] double at(int I, int J) const { return a[static_cast<std::size_t>(I) * (b + 1) + (J - I + b)]; }
  void add(const Band& o, double scale = 1.0) {
    for (std::size_t k = 0; k < a.size(); ++k) a[k] += scale * o.a[k];
  }
  [[nodiscard]] double trace() const {
    double t = 0.0;
    for (int I = 0; I < n; ++I) t += at(I, I);
    return t;
  }
};

// The factor and the inverse's band in AVX registers where the CPU has them (true), or in the portable form: the same
// bits either way (band.cpp); tests set it false to compare.
extern std::atomic<bool> avx_band_kernels;

// In-place Cholesky factor of a band matrix; false where it is not positive definite (band.cpp).
bool cholesky(Band& L);
// x = (L·Lᵀ)⁻¹ r for the three columns of r (n × 3, row major), in place.
void solve(const Band& L, std::vector<double>& r);
// The entries of (L·Lᵀ)⁻¹ inside the band (inside L's envelope where it has one: zero elsewhere), upper half by
// rows: Z(i, j), i ≤ j ≤ i + b, at z[i·(b+1) + j − i].
BandValues band_inverse(const Band& L);

// rᵀ·Z·r over the unknowns idx[0..m) (all within the band of each other), Z in band_inverse's layout, in two steps
// for runs of points under one basis row: Z's entries there gathered once into a dense symmetric block
// (block[a·m + c], both triangles), then each point's form from it: a basis row's variance factor, or its leverage.
inline void gather_block(std::span<const double> Z, int b, const int* idx, int m, double* block) {
  for (int a = 0; a < m; ++a) {
    for (int c = a; c < m; ++c) {
      const int I = std::min(idx[a], idx[c]), J = std::max(idx[a], idx[c]);
      block[a * m + c] = block[c * m + a] = Z[static_cast<std::size_t>(I) * (b + 1) + (J - I)];
    }
  }
}

// As a full matrix–vector product: twice the products of the triangle's, but in vector registers, where the
// triangle's are a chain of dependent additions (a bicubic row: about 130 ns that way, a few times less this way;
// bicubic rows now have their own form, below, and this serves the biquadratic ones).
template <int M>
double fixed_quadratic_form(const double* block, const double* r) {
  const Eigen::Map<const Eigen::Matrix<double, M, M>> B(block);
  const Eigen::Map<const Eigen::Matrix<double, M, 1>> x(r);
  const Eigen::Matrix<double, M, 1> y = B * x;
  return x.dot(y);
}

// A bicubic row's form, the pipeline's every fit (17 cross-validation trials of every point at 10 000 points): the
// product summed column by column in four 4-vectors that stay in registers. As many instructions as Eigen's general
// matrix–vector kernel, which B * x calls at this size (about 560 a row, callgrind), but without its set-up for any
// size (a faster fit: docs/performance.md). The sums' order differs from the kernel's,
// so the scores differ in their last bits; the λ chosen, and so the output, were the same on every case measured.
inline double bicubic_quadratic_form(const double* block, const double* r) {
  using Piece = Eigen::Matrix<double, 4, 1>;
  Piece y0 = Piece::Zero(), y1 = Piece::Zero(), y2 = Piece::Zero(), y3 = Piece::Zero();
  for (int j = 0; j < 16; ++j) {
    const double x = r[j];
    const double* column = block + 16 * j;
    y0 += Eigen::Map<const Piece>(column) * x;
    y1 += Eigen::Map<const Piece>(column + 4) * x;
    y2 += Eigen::Map<const Piece>(column + 8) * x;
    y3 += Eigen::Map<const Piece>(column + 12) * x;
  }
  return Eigen::Map<const Piece>(r).dot(y0) + Eigen::Map<const Piece>(r + 4).dot(y1) +
         Eigen::Map<const Piece>(r + 8).dot(y2) + Eigen::Map<const Piece>(r + 12).dot(y3);
}

inline double block_quadratic_form(const double* block, const double* r, int m) {
  switch (m) {
    case 16: return bicubic_quadratic_form(block, r);  // bicubic: every fit of the pipeline
    case 9: return fixed_quadratic_form<9>(block, r);
    default: {
      const Eigen::Map<const Eigen::MatrixXd> B(block, m, m);
      const Eigen::Map<const Eigen::VectorXd> x(r, m);
      double buffer[(nurbs::kMaxDegree + 1) * (nurbs::kMaxDegree + 1)];
      Eigen::Map<Eigen::VectorXd> y(buffer, m);
      y.noalias() = B * x;
      return x.dot(y);
    }
  }
}

}  // namespace probecomp::fitting::detail
