#include "band.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace probecomp::fitting::detail {

// In-place Cholesky factor L (N = L·Lᵀ) of a band matrix, row by row (the band keeps no fill outside it):
// L_IJ = (N_IJ − Σ_{m<J} L_Im L_Jm) / L_JJ. Each entry of row I, once known, is taken at once from all the row's
// later entries (L_IJ' −= L_IJ · L_J'J, J' > J), so that the row's sums advance side by side instead of one long
// chain of dependent subtractions after another; each sum still takes its terms in the order m = 0, 1, …, so the
// factor is the same to the last bit.
bool cholesky(Band& L) {
  const int b = L.b;
  const std::size_t stride = static_cast<std::size_t>(b) + 1;
  for (int I = 0; I < L.n; ++I) {
    const int m0 = L.row_start(I);
    double* rowI = &L.a[static_cast<std::size_t>(I) * stride + static_cast<std::size_t>(m0 - I + b)];  // L_I,m0+t
    const int width = I - m0;
    for (int t = 0; t < width; ++t) {
      const int J = m0 + t;
      const double l = rowI[t] / L.at(J, J);
      rowI[t] = l;
      // L_J',J for J' = J+1 … I: b doubles apart (one band row on, one column back).
      const double* column = &L.a[static_cast<std::size_t>(J + 1) * stride + static_cast<std::size_t>(b - 1)];
      for (int t2 = t + 1; t2 < width; ++t2) rowI[t2] -= l * column[static_cast<std::size_t>(t2 - t - 1) * b];
      rowI[width] -= l * l;
    }
    const double s = rowI[width];
    if (!(s > 0.0) || !std::isfinite(s)) return false;
    rowI[width] = std::sqrt(s);
  }
  return true;
}

namespace {

// The last row of each column of L that may be non-zero: max {k : first[k] ≤ i}, or i + b without an envelope.
std::vector<int> column_ends(const Band& L) {
  std::vector<int> last(static_cast<std::size_t>(L.n));
  int k = 0;
  for (int i = 0; i < L.n; ++i) {
    if (L.first.empty()) {
      last[static_cast<std::size_t>(i)] = std::min(L.n - 1, i + L.b);
      continue;
    }
    while (k + 1 < L.n && L.first[static_cast<std::size_t>(k) + 1] <= i) ++k;
    last[static_cast<std::size_t>(i)] = std::max(k, i);
  }
  return last;
}

}  // namespace

// x = (L·Lᵀ)⁻¹ r for the three columns of r (n × 3, row major), in place.
void solve(const Band& L, std::vector<double>& r) {
  const int n = L.n;
  for (int I = 0; I < n; ++I) {
    for (int c = 0; c < 3; ++c) {
      double s = r[3 * I + c];
      for (int m = L.row_start(I); m < I; ++m) s -= L.at(I, m) * r[3 * m + c];
      r[3 * I + c] = s / L.at(I, I);
    }
  }
  const std::vector<int> last = column_ends(L);
  for (int I = n - 1; I >= 0; --I) {
    for (int c = 0; c < 3; ++c) {
      double s = r[3 * I + c];
      for (int k = I + 1; k <= last[static_cast<std::size_t>(I)]; ++k) s -= L.at(k, I) * r[3 * k + c];
      r[3 * I + c] = s / L.at(I, I);
    }
  }
}

// The entries of Z = (L·Lᵀ)⁻¹ inside the band (Takahashi, Fagan and Chin 1973): from Lᵀ·Z = L⁻¹, whose upper
// triangle is diag(1/L_ii), Z_ij = (δ_ij / L_ii − Σ_{k>i} L_ki Z_kj) / L_ii for j ≥ i, from the last row up.
// Every Z_kj the sum needs has i < k, j ≤ i + b, inside the band already computed. Upper half by rows:
// Z(i, j), i ≤ j ≤ i + b, at z[i·(b+1) + j − i].
// Row i's sums for j > i advance side by side, one k at a time (each still takes its terms in the order k = i+1, i+2,
// …: the same Z to the last bit), over contiguous memory: Z_kj for j ≥ k is row k of z, and for j < k (Z_jk) row k of
// a copy of the band's lower half, kept for the b rows below i only (a ring of b + 1 rows).
std::vector<double> band_inverse(const Band& L) {
  const int n = L.n, b = L.b;
  const std::size_t stride = static_cast<std::size_t>(b) + 1;
  std::vector<double> z(static_cast<std::size_t>(n) * stride, 0.0);
  // lower(k, j) = Z_jk for k − b ≤ j < k, at ring[(k mod (b+1))·(b+1) + j − k + b].
  std::vector<double> ring(stride * stride, 0.0);
  auto ring_row = [&](int k) { return &ring[static_cast<std::size_t>(k % (b + 1)) * stride]; };
  std::vector<double> column(stride), sum(stride);
  const std::vector<int> ends = column_ends(L);
  for (int i = n - 1; i >= 0; --i) {
    const int last = ends[static_cast<std::size_t>(i)];
    const int width = last - i;
    for (int k = i + 1; k <= last; ++k) column[static_cast<std::size_t>(k - i)] = L.at(k, i);
    const double d = L.at(i, i);
    std::fill(sum.begin(), sum.begin() + width + 1, 0.0);  // sum[j − i], j = i+1 … last
    for (int k = i + 1; k <= last; ++k) {
      const double c = column[static_cast<std::size_t>(k - i)];
      const double* lower = ring_row(k) + (b - k + i);                          // lower[j − i] = Z_jk, j < k
      const double* upper = &z[static_cast<std::size_t>(k) * stride] - (k - i);  // upper[j − i] = Z_kj, j ≥ k
      for (int t = 1; t < k - i; ++t) sum[static_cast<std::size_t>(t)] -= c * lower[t];
      for (int t = k - i; t <= width; ++t) sum[static_cast<std::size_t>(t)] -= c * upper[t];
    }
    double* zi = &z[static_cast<std::size_t>(i) * stride];
    for (int t = 1; t <= width; ++t) {
      zi[t] = sum[static_cast<std::size_t>(t)] / d;
      ring_row(i + t)[static_cast<std::size_t>(b - t)] = zi[t];  // lower(i + t, i)
    }
    double s = 1.0 / d;
    for (int t = 1; t <= width; ++t) s -= column[static_cast<std::size_t>(t)] * zi[t];
    zi[0] = s / d;
  }
  return z;
}

}  // namespace probecomp::fitting::detail
