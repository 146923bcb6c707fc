// The penalised fit's band algebra (src/fitting/band.hpp) against Eigen's dense Cholesky and inverse: the factor,
// the solves and the inverse's entries inside the band, and inside a variable band (an envelope) the same, with the
// inverse left zero outside it.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <tuple>
#include <vector>

#include "fitting/band.hpp"

namespace probecomp::fitting::detail {
namespace {

// A symmetric positive definite matrix of order n, non-zero inside half-bandwidth b and, with an envelope, right
// of first[I] in row I (first non-decreasing, I − b ≤ first[I] ≤ I): its band and its dense copy.
struct BandCase {
  Band band;
  Eigen::MatrixXd dense;
};

BandCase random_band(int n, int b, bool with_envelope, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> entry(-1.0, 1.0);
  BandCase c{Band(n, b), Eigen::MatrixXd::Zero(n, n)};
  if (with_envelope) {
    // Rows alternately narrow and wide, as a THB basis's are where its two levels meet.
    c.band.first.resize(static_cast<std::size_t>(n));
    for (int I = 0; I < n; ++I) {
      const int width = (I / 7) % 2 == 0 ? b : b / 4;
      c.band.first[static_cast<std::size_t>(I)] = std::max(0, I - width);
    }
    for (int I = n - 1; I > 0; --I) {
      c.band.first[static_cast<std::size_t>(I) - 1] =
          std::min(c.band.first[static_cast<std::size_t>(I) - 1], c.band.first[static_cast<std::size_t>(I)]);
    }
  }
  for (int I = 0; I < n; ++I) {
    for (int J = c.band.row_start(I); J < I; ++J) c.dense(I, J) = c.dense(J, I) = entry(rng);
  }
  // Diagonally dominant: positive definite.
  for (int I = 0; I < n; ++I) c.dense(I, I) = c.dense.row(I).cwiseAbs().sum() + 1.0 + entry(rng) * 0.5;
  for (int I = 0; I < n; ++I) {
    for (int J = std::max(0, I - b); J <= I; ++J) c.band.at(I, J) = c.dense(I, J);
  }
  return c;
}

void expect_matches_dense(int n, int b, bool with_envelope, unsigned seed) {
  SCOPED_TRACE(::testing::Message() << "n " << n << ", b " << b << (with_envelope ? ", envelope" : ", full band"));
  BandCase c = random_band(n, b, with_envelope, seed);
  const Eigen::LLT<Eigen::MatrixXd> llt(c.dense);
  const Eigen::MatrixXd Ld = llt.matrixL();
  const Eigen::MatrixXd inverse = llt.solve(Eigen::MatrixXd::Identity(n, n));
  Band L = c.band;
  ASSERT_TRUE(cholesky(L));
  for (int I = 0; I < n; ++I) {
    for (int J = L.row_start(I); J <= I; ++J) EXPECT_NEAR(L.at(I, J), Ld(I, J), 1e-12) << I << ", " << J;
    // Outside the envelope the factor is zero: the factorisation kept no fill there.
    for (int J = 0; J < L.row_start(I); ++J) EXPECT_EQ(Ld(I, J), 0.0) << I << ", " << J;
  }
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<double> entry(-1.0, 1.0);
  Eigen::MatrixX3d rhs(n, 3);
  for (int I = 0; I < n; ++I)
    for (int k = 0; k < 3; ++k) rhs(I, k) = entry(rng);
  std::vector<double> x(static_cast<std::size_t>(n) * 3);
  for (int I = 0; I < n; ++I)
    for (int k = 0; k < 3; ++k) x[3 * static_cast<std::size_t>(I) + k] = rhs(I, k);
  solve(L, x);
  const Eigen::MatrixX3d expected = llt.solve(rhs);
  for (int I = 0; I < n; ++I)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(x[3 * static_cast<std::size_t>(I) + k], expected(I, k), 1e-12);
  const BandValues Z = band_inverse(L);
  for (int i = 0; i < n; ++i) {
    for (int j = i; j <= std::min(n - 1, i + b); ++j) {
      const double z = Z[static_cast<std::size_t>(i) * (b + 1) + (j - i)];
      if (L.row_start(j) <= i) {
        EXPECT_NEAR(z, inverse(i, j), 1e-12) << i << ", " << j;
      } else {
        EXPECT_EQ(z, 0.0) << i << ", " << j;  // outside the envelope: not computed
      }
    }
  }
}

TEST(BandAlgebra, FactorSolvesAndInverseInsideTheBandAreEigensDense) {
  expect_matches_dense(1, 0, false, 1);
  expect_matches_dense(40, 39, false, 2);  // the band is the whole matrix
  expect_matches_dense(120, 17, false, 3);
}

TEST(BandAlgebra, InsideAnEnvelopeTheyAreEigensDenseAndTheInverseIsZeroOutside) {
  expect_matches_dense(120, 17, true, 4);
  expect_matches_dense(300, 40, true, 5);
}

TEST(BandAlgebra, AnEnvelopeChangesNoBitOfTheFactorOrTheInverseInsideIt) {
  // The fit's outputs are the same with and without it (docs/performance.md): the skipped terms are zeros.
  BandCase c = random_band(200, 30, true, 6);
  Band with = c.band, without = c.band;
  without.first.clear();
  ASSERT_TRUE(cholesky(with));
  ASSERT_TRUE(cholesky(without));
  const BandValues Zw = band_inverse(with), Zo = band_inverse(without);
  for (int i = 0; i < 200; ++i) {
    for (int J = with.row_start(i); J <= i; ++J) EXPECT_EQ(with.at(i, J), without.at(i, J));
    for (int j = i; j <= std::min(199, i + 30); ++j) {
      if (with.row_start(j) <= i) EXPECT_EQ(Zw[static_cast<std::size_t>(i) * 31 + (j - i)], Zo[static_cast<std::size_t>(i) * 31 + (j - i)]);
    }
  }
}

// The AVX kernels (where this CPU has AVX) and the portable ones: the same factor and inverse to the last bit, on
// bands of every width mod 8 (the factor's partial sums) and with an envelope.
TEST(BandAlgebra, TheAvxAndPortableKernelsGiveTheSameBits) {
  struct Restore {
    ~Restore() { avx_band_kernels = true; }
  } restore;
  for (const auto& [n, b, envelope] : {std::tuple{200, 30, false}, std::tuple{150, 13, true}, std::tuple{97, 96, false},
                                       std::tuple{300, 61, true}}) {
    SCOPED_TRACE(::testing::Message() << "n " << n << ", b " << b << (envelope ? ", envelope" : ""));
    const BandCase c = random_band(n, b, envelope, static_cast<unsigned>(n + b));
    Band fast = c.band, portable = c.band;
    avx_band_kernels = true;
    ASSERT_TRUE(cholesky(fast));
    const BandValues Zf = band_inverse(fast);
    avx_band_kernels = false;
    ASSERT_TRUE(cholesky(portable));
    const BandValues Zp = band_inverse(portable);
    int differ = 0;
    for (std::size_t k = 0; k < fast.a.size(); ++k) differ += fast.a[k] != portable.a[k];
    for (std::size_t k = 0; k < Zf.size(); ++k) differ += Zf[k] != Zp[k];
    EXPECT_EQ(differ, 0);
  }
}

}  // namespace
}  // namespace probecomp::fitting::detail
