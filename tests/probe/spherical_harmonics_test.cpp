// Real spherical harmonics against closed forms and their orthonormality under an exact product quadrature.
#include "probecomp/probe/spherical_harmonics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace probecomp::probe {
namespace {

// Gauss–Legendre nodes and weights on [−1, 1] by Newton on P_n (exact for polynomials of degree 2n − 1).
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
  x.assign(n, 0.0);
  w.assign(n, 0.0);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5)), dp = 0.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    x[static_cast<std::size_t>(i)] = z;
    w[static_cast<std::size_t>(i)] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
}

TEST(SphericalHarmonics, LowDegreesAreTheirClosedForms) {
  const std::vector<HarmonicIndex> terms = harmonic_terms(3, false);
  ASSERT_EQ(terms.size(), 16u);
  for (const Vector3& raw : {Vector3(0.3, -0.5, 0.81), Vector3(0, 0, 1), Vector3(-1, 0.2, -0.1), Vector3(0, 0, -2)}) {
    const Vector3 d = raw.normalized();
    const double x = d.x(), y = d.y(), z = d.z();
    const std::vector<double> h = real_harmonics(raw, terms);
    // Index of (l, m): l² + l + m.
    EXPECT_NEAR(h[0], 1.0, 1e-15);
    EXPECT_NEAR(h[1], std::sqrt(3.0) * y, 1e-14);  // (1, −1)
    EXPECT_NEAR(h[2], std::sqrt(3.0) * z, 1e-14);  // (1, 0)
    EXPECT_NEAR(h[3], std::sqrt(3.0) * x, 1e-14);  // (1, 1)
    EXPECT_NEAR(h[6], std::sqrt(5.0) * (3 * z * z - 1) / 2, 1e-14);        // (2, 0)
    EXPECT_NEAR(h[4], std::sqrt(15.0) * x * y, 1e-14);                     // (2, −2)
    EXPECT_NEAR(h[8], std::sqrt(15.0) / 2 * (x * x - y * y), 1e-14);       // (2, 2)
    EXPECT_NEAR(h[7], std::sqrt(15.0) * x * z, 1e-14);                     // (2, 1)
    EXPECT_NEAR(h[15], std::sqrt(35.0 / 8.0) * (x * x * x - 3 * x * y * y), 1e-14);  // (3, 3)
    EXPECT_NEAR(h[12], std::sqrt(7.0) / 2 * z * (5 * z * z - 3), 1e-14);   // (3, 0)
  }
}

TEST(SphericalHarmonics, AreOrthonormalOverTheSphere) {
  // Degree ≤ 8: products of degree ≤ 16, integrated exactly by 9 Gauss–Legendre nodes in cos θ and 18 azimuths.
  const std::vector<HarmonicIndex> terms = harmonic_terms(8, false);
  std::vector<double> x, w;
  gauss_legendre(9, x, w);
  const int azimuths = 18;
  const std::size_t k = terms.size();
  std::vector<double> gram(k * k, 0.0);
  for (std::size_t a = 0; a < x.size(); ++a) {
    for (int b = 0; b < azimuths; ++b) {
      const double phi = 2 * std::numbers::pi * b / azimuths, s = std::sqrt(1 - x[a] * x[a]);
      const std::vector<double> h = real_harmonics(Vector3(s * std::cos(phi), s * std::sin(phi), x[a]), terms);
      // The mean over the sphere: ∫ f dΩ / 4π = Σ w_a / 2 · (1 / azimuths) Σ f.
      for (std::size_t i = 0; i < k; ++i) {
        for (std::size_t j = 0; j < k; ++j) gram[i * k + j] += w[a] / 2.0 / azimuths * h[i] * h[j];
      }
    }
  }
  for (std::size_t i = 0; i < k; ++i) {
    for (std::size_t j = 0; j < k; ++j) {
      EXPECT_NEAR(gram[i * k + j], i == j ? 1.0 : 0.0, 1e-12) << terms[i].l << "," << terms[i].m << " x " << terms[j].l << "," << terms[j].m;
    }
  }
}

TEST(SphericalHarmonics, TermsLeaveDegreeOneOutWhenAsked) {
  const std::vector<HarmonicIndex> t = harmonic_terms(3, true);
  ASSERT_EQ(t.size(), 13u);
  for (const HarmonicIndex& h : t) EXPECT_NE(h.l, 1);
}

}  // namespace
}  // namespace probecomp::probe
