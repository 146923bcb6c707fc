#include "probecomp/nurbs/basis.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace probecomp::nurbs {
namespace {

// Cox–de Boor recursion (The NURBS Book, eq. 2.5), straight from the definition: an independent reference.
double cox_de_boor(const KnotVector& U, int i, int p, double u) {
  if (p == 0) return (U[i] <= u && u < U[i + 1]) ? 1.0 : 0.0;  // u < back() in these tests
  double a = 0.0, b = 0.0;
  if (U[i + p] != U[i]) a = (u - U[i]) / (U[i + p] - U[i]) * cox_de_boor(U, i, p - 1, u);
  if (U[i + p + 1] != U[i + 1]) b = (U[i + p + 1] - u) / (U[i + p + 1] - U[i + 1]) * cox_de_boor(U, i + 1, p - 1, u);
  return a + b;
}

TEST(Basis, MatchesCoxDeBoorAndIsAPartitionOfUnity) {
  const KnotVector U({0, 0, 0, 0, 0.1, 0.35, 0.35, 0.6, 1, 1, 1, 1}, 3);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> dist(0.0, 1.0);
  for (int t = 0; t < 500; ++t) {
    const double u = dist(rng);
    const int span = U.find_span(u);
    double N[kMaxDegree + 1];
    basis_functions(U, span, u, N);
    double sum = 0.0;
    for (int j = 0; j <= 3; ++j) {
      EXPECT_NEAR(N[j], cox_de_boor(U, span - 3 + j, 3, u), 1e-14);
      EXPECT_GE(N[j], 0.0);
      sum += N[j];
    }
    EXPECT_NEAR(sum, 1.0, 1e-15);
  }
}

TEST(Basis, DerivativesMatchCentralDifferencesAndTheValues) {
  const KnotVector U({0, 0, 0, 0, 0.2, 0.5, 0.7, 1, 1, 1, 1}, 3);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> dist(0.02, 0.98);
  const double h = 1e-6;
  for (int t = 0; t < 300; ++t) {
    double u = dist(rng);
    // Keep the difference stencil inside one span, where the functions are polynomials.
    const int span = U.find_span(u);
    u = std::clamp(u, U[span] + 2 * h, U[span + 1] - 2 * h);
    double ders[4 * (kMaxDegree + 1)];
    basis_function_derivatives(U, span, u, 3, ders);
    double N0[kMaxDegree + 1], Np[kMaxDegree + 1], Nm[kMaxDegree + 1];
    basis_functions(U, span, u, N0);
    basis_functions(U, span, u + h, Np);
    basis_functions(U, span, u - h, Nm);
    double d1p[4 * (kMaxDegree + 1)], d1m[4 * (kMaxDegree + 1)];
    basis_function_derivatives(U, span, u + h, 3, d1p);
    basis_function_derivatives(U, span, u - h, 3, d1m);
    double sum1 = 0.0;
    for (int j = 0; j <= 3; ++j) {
      EXPECT_NEAR(ders[j], N0[j], 1e-15);
      EXPECT_NEAR(ders[4 + j], (Np[j] - Nm[j]) / (2 * h), 1e-6);
      EXPECT_NEAR(ders[8 + j], (d1p[4 + j] - d1m[4 + j]) / (2 * h), 1e-5);
      EXPECT_NEAR(ders[12 + j], (d1p[8 + j] - d1m[8 + j]) / (2 * h), 1e-4);
      sum1 += ders[4 + j];
    }
    EXPECT_NEAR(sum1, 0.0, 1e-12);  // derivative of a partition of unity
  }
}

// The cubic's first and second derivatives alone (the closest-point Newton's and the normals' calls, with the order
// fixed at compile time so that A2.3's loops unroll) are the same numbers, bit for bit, as the rows of the general
// call: the same arithmetic in the same order.
TEST(Basis, ACubicsFirstAndSecondDerivativesAloneAreBitIdenticalToTheGeneralOnes) {
  const KnotVector U({0, 0, 0, 0, 0.13, 0.4, 0.4, 0.55, 0.9, 1, 1, 1, 1}, 3);
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> dist(0.0, 1.0);
  for (int t = 0; t < 500; ++t) {
    const double u = dist(rng);
    const int span = U.find_span(u);
    double all[4 * (kMaxDegree + 1)], d2[3 * (kMaxDegree + 1)], d1[2 * (kMaxDegree + 1)];
    basis_function_derivatives(U, span, u, 3, all);
    basis_function_derivatives(U, span, u, 2, d2);
    basis_function_derivatives(U, span, u, 1, d1);
    for (int j = 0; j < 12; ++j) EXPECT_EQ(d2[j], all[j]) << "u " << u << " entry " << j;
    for (int j = 0; j < 8; ++j) EXPECT_EQ(d1[j], all[j]) << "u " << u << " entry " << j;
  }
}

// On a Bézier span (p equal knots at each end) the basis functions are the Bernstein polynomials of
// t = (u − a)/h; their derivatives, written out by hand for the cubic, are an independent reference for the
// Bernstein fast path.
TEST(Basis, OnABezierSpanTheDerivativesAreTheCubicBernsteinOnes) {
  const KnotVector U({0, 0, 0, 0, 0.3, 0.3, 0.3, 1, 1, 1, 1}, 3);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> dist(0.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    const double u = dist(rng);
    const int span = U.find_span(u);
    const double a = U[span], h = U[span + 1] - U[span];
    const double t = (u - a) / h, s = 1.0 - t;
    const double B[3][4] = {{s * s * s, 3 * t * s * s, 3 * t * t * s, t * t * t},
                            {-3 * s * s / h, (3 * s * s - 6 * t * s) / h, (6 * t * s - 3 * t * t) / h, 3 * t * t / h},
                            {6 * s / (h * h), (18 * t - 12) / (h * h), (6 - 18 * t) / (h * h), 6 * t / (h * h)}};
    double ders[3 * (kMaxDegree + 1)];
    basis_function_derivatives(U, span, u, 2, ders);
    for (int k = 0; k <= 2; ++k)
      for (int j = 0; j <= 3; ++j) EXPECT_NEAR(ders[k * 4 + j], B[k][j], 1e-12 * std::pow(1.0 / h, k)) << k << " " << j;
    for (int j = 0; j <= 3; ++j) EXPECT_NEAR(ders[j], cox_de_boor(U, span - 3 + j, 3, u), 1e-14);
  }
}

// The cubic Bézier span's values and derivatives to second order written out (the closest-point search's Newton) are
// the Bernstein triangle's numbers bit for bit: against the triangle's own values and first derivatives (asked for
// alone, n = 1, it still runs the triangle).
TEST(Basis, OnABezierSpanTheWrittenOutCubicIsTheBernsteinTrianglesBitForBit) {
  const KnotVector U({0, 0, 0, 0, 0.3, 0.3, 0.3, 1, 1, 1, 1}, 3);
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> dist(0.0, 1.0);
  for (int trial = 0; trial < 500; ++trial) {
    const double u = trial == 0 ? 0.0 : trial == 1 ? 1.0 : trial == 2 ? 0.3 : dist(rng);
    const int span = U.find_span(u);
    double d2[3 * (kMaxDegree + 1)], d1[2 * (kMaxDegree + 1)];
    basis_function_derivatives(U, span, u, 2, d2);
    basis_function_derivatives(U, span, u, 1, d1);
    for (int j = 0; j < 8; ++j) EXPECT_EQ(d2[j], d1[j]) << "u " << u << " entry " << j;
  }
}

TEST(Basis, OrdersAboveTheDegreeAreZero) {
  const KnotVector U = KnotVector::uniform(1, 3);
  double ders[3 * (kMaxDegree + 1)];
  basis_function_derivatives(U, U.find_span(0.4), 0.4, 2, ders);
  EXPECT_EQ(ders[4], 0.0);
  EXPECT_EQ(ders[5], 0.0);
  EXPECT_DOUBLE_EQ(ders[2] + ders[3], 0.0);  // first derivatives of a linear pair cancel
}

}  // namespace
}  // namespace probecomp::nurbs
