#include "band.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include "probecomp/geometry/cpu.hpp"

namespace probecomp::fitting::detail {

std::atomic<bool> avx_band_kernels{true};

namespace {

// Σ_m x_m y_m over columns m = first … last − 1 (x and y point at column first), in eight partial sums by column
// mod 8, added at the end: a fixed order, so the same bits on every machine and thread count, that the compiler keeps
// in vector registers (one running sum is a chain of dependent additions it may not reorder without -ffast-math).
// Sums by column, not by position, so that the zeros outside an envelope change no bit (their products add +0).
[[gnu::always_inline]] inline double dot(const double* x, const double* y, int first, int last) {
  double s[8] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  int m = first;
  for (; m < last && (m & 7) != 0; ++m, ++x, ++y) s[m & 7] += *x * *y;
  for (; m + 8 <= last; m += 8, x += 8, y += 8) {
    for (int g = 0; g < 8; ++g) s[g] += x[g] * y[g];
  }
  for (; m < last; ++m, ++x, ++y) s[m & 7] += *x * *y;
  return ((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]));
}

// In-place Cholesky factor L (N = L·Lᵀ) of a band matrix, row by row (the band keeps no fill outside it; Golub and
// Van Loan, Algorithm 4.3.5): L_IJ = (N_IJ − Σ_m L_Im L_Jm) / L_JJ over the columns m < J both rows may hold. Rows
// are contiguous in the band's layout, so each sum is a dot product of two contiguous runs (dot above).
[[gnu::always_inline]] inline bool cholesky_rows(Band& L) {
  const int b = L.b;
  const std::size_t stride = static_cast<std::size_t>(b) + 1;
  // &L_I,m: row I's storage is shifted by I − b.
  auto entry = [&](int I, int m) { return &L.a[static_cast<std::size_t>(I) * stride + static_cast<std::size_t>(m - I + b)]; };
  for (int I = 0; I < L.n; ++I) {
    const int m0 = L.row_start(I);
    double* rowI = entry(I, m0);
    for (int J = m0; J < I; ++J) {
      const int start = std::max(m0, L.row_start(J));
      const double s = rowI[J - m0] - dot(entry(I, start), entry(J, start), start, J);
      rowI[J - m0] = s / *entry(J, J);
    }
    const double s = rowI[I - m0] - dot(rowI, rowI, m0, I);
    if (!(s > 0.0) || !std::isfinite(s)) return false;
    rowI[I - m0] = std::sqrt(s);
  }
  return true;
}

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

// The entries of Z = (L·Lᵀ)⁻¹ inside the band (Takahashi, Fagan and Chin 1973): from Lᵀ·Z = L⁻¹, whose upper
// triangle is diag(1/L_ii), Z_ij = (δ_ij / L_ii − Σ_{k>i} L_ki Z_kj) / L_ii for j ≥ i, from the last row up.
// Every Z_kj the sum needs has i < k, j ≤ i + b, inside the band already computed. Upper half by rows:
// Z(i, j), i ≤ j ≤ i + b, at z[i·(b+1) + j − i].
// Row i's sums for j > i advance side by side, four k at a time (one pass over the sums for four rows of Z), over
// contiguous memory: each row k of Z the sums need, both halves (Z_kj, k − b ≤ j ≤ k + b), is kept whole in a ring
// of b + 1 rows. The terms are grouped by k − i, so that the zeros an envelope skips change no bit.
[[gnu::always_inline]] inline BandValues inverse_rows(const Band& L) {
  const int n = L.n, b = L.b;
  const std::size_t stride = static_cast<std::size_t>(b) + 1;
  const std::size_t full = 2 * static_cast<std::size_t>(b) + 1;
  BandValues z(static_cast<std::size_t>(n) * stride, 0.0);
  // Z_kj at ring_row(k)[j − k + b], k − b ≤ j ≤ k + b, for the b + 1 rows k below and at i.
  std::vector<double> ring(stride * full, 0.0);
  auto ring_row = [&](int k) { return &ring[static_cast<std::size_t>(k % (b + 1)) * full]; };
  std::vector<double> column(stride), sum(stride), zeros(stride, 0.0);
  const std::vector<int> ends = column_ends(L);
  for (int i = n - 1; i >= 0; --i) {
    const int last = ends[static_cast<std::size_t>(i)];
    const int width = last - i;
    for (int k = i + 1; k <= last; ++k) column[static_cast<std::size_t>(k - i)] = L.at(k, i);
    const double d = L.at(i, i);
    std::fill(sum.begin(), sum.begin() + width + 1, 0.0);  // sum[j − i], j = i+1 … last
    // row(k)[t] = Z_k,i+t (its entries for j < i + 1 and j > last are not read).
    auto row = [&](int k) { return ring_row(k) + (i - k + b); };
    // The last group padded with zero terms (c = 0 against a row of zeros), not taken one by one: the same rounding
    // as the full band's group there, whose extra terms are zeros too.
    for (int k = i + 1; k <= last; k += 4) {
      const double* r[4];
      double c[4];
      for (int g = 0; g < 4; ++g) {
        const bool inside = k + g <= last;
        c[g] = inside ? column[static_cast<std::size_t>(k + g - i)] : 0.0;
        r[g] = inside ? row(k + g) : zeros.data();
      }
      for (int t = 1; t <= width; ++t) sum[static_cast<std::size_t>(t)] -= (c[0] * r[0][t] + c[1] * r[1][t]) + (c[2] * r[2][t] + c[3] * r[3][t]);
    }
    double* zi = &z[static_cast<std::size_t>(i) * stride];
    double* own = ring_row(i);
    std::fill(own, own + full, 0.0);  // the slot held row i + b + 1; its lower half is written by the rows above
    for (int t = 1; t <= width; ++t) {
      zi[t] = sum[static_cast<std::size_t>(t)] / d;
      own[static_cast<std::size_t>(b + t)] = zi[t];                   // Z_i,i+t
      ring_row(i + t)[static_cast<std::size_t>(b - t)] = zi[t];       // Z_i+t,i
    }
    double s = 1.0 / d;
    for (int t = 1; t <= width; ++t) s -= column[static_cast<std::size_t>(t)] * zi[t];
    zi[0] = s / d;
    own[static_cast<std::size_t>(b)] = zi[0];
  }
  return z;
}

// The two kernels compiled again for AVX (256-bit registers), chosen at run time where the CPU has it: each lane takes
// the same multiplications and additions in the same order as the portable form (no fused multiply-add:
// -ffp-contract=off, and no FMA in the target), so the results are the same bit for bit; tests compare the two.
#if PROBECOMP_HAVE_AVX_PATH
__attribute__((target("avx"))) bool cholesky_avx(Band& L) { return cholesky_rows(L); }
__attribute__((target("avx"))) BandValues inverse_avx(const Band& L) { return inverse_rows(L); }
bool use_avx() { return geometry::cpu_has_avx() && avx_band_kernels.load(std::memory_order_relaxed); }
#endif

}  // namespace

bool cholesky(Band& L) {
#if PROBECOMP_HAVE_AVX_PATH
  if (use_avx()) return cholesky_avx(L);
#endif
  return cholesky_rows(L);
}

BandValues band_inverse(const Band& L) {
#if PROBECOMP_HAVE_AVX_PATH
  if (use_avx()) return inverse_avx(L);
#endif
  return inverse_rows(L);
}

// x = (L·Lᵀ)⁻¹ r for the three columns of r (n × 3, row major), in place: L y = r forward, row by row, and Lᵀ x = y
// backward, column by column (column I of Lᵀ is row I of L), so both sweeps read L's rows in contiguous runs.
void solve(const Band& L, std::vector<double>& r) {
  const int n = L.n;
  for (int I = 0; I < n; ++I) {
    double s0 = r[3 * I], s1 = r[3 * I + 1], s2 = r[3 * I + 2];
    for (int m = L.row_start(I); m < I; ++m) {
      const double l = L.at(I, m);
      s0 -= l * r[3 * m];
      s1 -= l * r[3 * m + 1];
      s2 -= l * r[3 * m + 2];
    }
    const double d = L.at(I, I);
    r[3 * I] = s0 / d;
    r[3 * I + 1] = s1 / d;
    r[3 * I + 2] = s2 / d;
  }
  for (int I = n - 1; I >= 0; --I) {
    const double d = L.at(I, I);
    const double x0 = r[3 * I] / d, x1 = r[3 * I + 1] / d, x2 = r[3 * I + 2] / d;
    r[3 * I] = x0;
    r[3 * I + 1] = x1;
    r[3 * I + 2] = x2;
    for (int m = L.row_start(I); m < I; ++m) {
      const double l = L.at(I, m);
      r[3 * m] -= l * x0;
      r[3 * m + 1] -= l * x1;
      r[3 * m + 2] -= l * x2;
    }
  }
}

}  // namespace probecomp::fitting::detail
