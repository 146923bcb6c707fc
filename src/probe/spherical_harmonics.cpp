#include "probecomp/probe/spherical_harmonics.hpp"

#include <algorithm>
#include <cmath>

namespace probecomp::probe {

namespace {

// P̄_lm(cos θ) for 0 ≤ m ≤ l ≤ L, row l at l(l+1)/2 + m: sectoral terms by P̄_mm = √((2m+1)/(2m)) sin θ P̄_{m−1,m−1}
// (√3 sin θ for m = 1), then up each column by the three-term recurrence in l.
std::vector<double> legendre(double c, double s, int degree) {
  const auto at = [](int l, int m) { return static_cast<std::size_t>(l * (l + 1) / 2 + m); };
  std::vector<double> p(at(degree, degree) + 1, 0.0);
  p[0] = 1.0;
  for (int m = 1; m <= degree; ++m) {
    p[at(m, m)] = (m == 1 ? std::sqrt(3.0) : std::sqrt((2.0 * m + 1.0) / (2.0 * m))) * s * p[at(m - 1, m - 1)];
  }
  for (int m = 0; m <= degree; ++m) {
    if (m + 1 <= degree) p[at(m + 1, m)] = std::sqrt(2.0 * m + 3.0) * c * p[at(m, m)];
    for (int l = m + 2; l <= degree; ++l) {
      const double lm = (l - m) * static_cast<double>(l + m);
      const double a = std::sqrt((2.0 * l - 1.0) * (2.0 * l + 1.0) / lm);
      const double b = std::sqrt((2.0 * l + 1.0) * (l + m - 1.0) * (l - m - 1.0) / (lm * (2.0 * l - 3.0)));
      p[at(l, m)] = a * c * p[at(l - 1, m)] - b * p[at(l - 2, m)];
    }
  }
  return p;
}

}  // namespace

std::vector<double> real_harmonics(const Vector3& direction, const std::vector<HarmonicIndex>& terms) {
  const Vector3 d = direction.normalized();
  int degree = 0;
  for (const HarmonicIndex& t : terms) degree = std::max(degree, t.l);
  const double c = std::clamp(d.z(), -1.0, 1.0), s = std::hypot(d.x(), d.y());
  const double phi = s > 0.0 ? std::atan2(d.y(), d.x()) : 0.0;
  const std::vector<double> p = legendre(c, s, degree);
  std::vector<double> out;
  out.reserve(terms.size());
  for (const HarmonicIndex& t : terms) {
    const int m = std::abs(t.m);
    // The m ≠ 0 functions carry √2 in P̄ already (the (2 − δ_m0) of the normalisation).
    const double legendre_lm = p[static_cast<std::size_t>(t.l * (t.l + 1) / 2 + m)];
    out.push_back(t.m >= 0 ? legendre_lm * std::cos(m * phi) : legendre_lm * std::sin(m * phi));
  }
  return out;
}

std::vector<HarmonicIndex> harmonic_terms(int degree, bool skip_degree_one) {
  std::vector<HarmonicIndex> out;
  for (int l = 0; l <= degree; ++l) {
    if (l == 1 && skip_degree_one) continue;
    for (int m = -l; m <= l; ++m) out.push_back({l, m});
  }
  return out;
}

}  // namespace probecomp::probe
