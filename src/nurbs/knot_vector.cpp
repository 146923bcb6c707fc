#include "probecomp/nurbs/knot_vector.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace probecomp::nurbs {

KnotVector::KnotVector(std::vector<double> knots, int p) : U_(std::move(knots)), p_(p) {
  auto fail = [](const std::string& why) { throw InvalidGeometry("invalid knot vector: " + why); };
  if (p < 1 || p > kMaxDegree) {
    fail("degree " + std::to_string(p) + " is outside 1.." + std::to_string(kMaxDegree));
  }
  const auto m = U_.size();
  if (m < 2 * static_cast<std::size_t>(p + 1)) {
    fail(std::to_string(m) + " knots are too few for degree " + std::to_string(p) + " (need at least " +
         std::to_string(2 * (p + 1)) + ")");
  }
  for (std::size_t i = 0; i < m; ++i) {
    if (!std::isfinite(U_[i])) fail("knot " + std::to_string(i) + " is not finite");
    if (i > 0 && U_[i] < U_[i - 1]) {
      std::ostringstream s;
      s << "knots decrease at index " << i << " (" << U_[i - 1] << " > " << U_[i] << ")";
      fail(s.str());
    }
  }
  if (!(front() < back())) fail("the domain [u_p, u_{m-p}] is empty");
  // Clamped ends: the curve interpolates its end control points, which every algorithm here assumes.
  const auto sp = static_cast<std::size_t>(p);
  if (U_[0] != U_[sp] || U_[m - 1] != U_[m - 1 - sp]) {
    fail("the end knots must have multiplicity p+1 = " + std::to_string(p + 1) + " (clamped)");
  }
  if (U_[sp + 1] == U_[sp] || U_[m - 2 - sp] == U_[m - 1 - sp]) {
    fail("an end knot has multiplicity above p+1");
  }
  for (std::size_t i = sp + 1; i + sp + 1 < m;) {
    std::size_t j = i;
    while (j + 1 < m - sp - 1 && U_[j + 1] == U_[i]) ++j;
    const auto mult = j - i + 1;
    if (mult > sp) {
      std::ostringstream s;
      s << "interior knot " << U_[i] << " has multiplicity " << mult << " above the degree " << p
        << " (the basis would be discontinuous)";
      fail(s.str());
    }
    i = j + 1;
  }
}

KnotVector KnotVector::uniform(int p, int spans, double a, double b) {
  if (spans < 1) throw InvalidGeometry("invalid knot vector: a uniform knot vector needs at least one span");
  std::vector<double> U;
  U.reserve(static_cast<std::size_t>(2 * p + spans + 1));
  for (int i = 0; i < p; ++i) U.push_back(a);
  for (int s = 0; s <= spans; ++s) U.push_back(s == spans ? b : a + (b - a) * s / spans);
  for (int i = 0; i < p; ++i) U.push_back(b);
  return KnotVector(std::move(U), p);
}

int KnotVector::find_span(double u) const {
  const int n = num_basis() - 1;
  if (u >= U_[static_cast<std::size_t>(n + 1)]) return n;  // special case u = u_{n+1} (A2.1)
  if (u <= U_[static_cast<std::size_t>(p_)]) return p_;
  // upper_bound over [u_p, u_{n+1}] gives the first knot > u; the span starts one before it.
  const auto first = U_.begin() + p_;
  const auto last = U_.begin() + n + 2;
  return static_cast<int>(std::upper_bound(first, last, u) - U_.begin()) - 1;
}

int KnotVector::multiplicity(double u) const {
  const auto [lo, hi] = std::equal_range(U_.begin(), U_.end(), u);
  return static_cast<int>(hi - lo);
}

std::vector<double> KnotVector::breakpoints() const {
  std::vector<double> b;
  for (int i = p_; i <= num_basis(); ++i) {
    const double x = U_[static_cast<std::size_t>(i)];
    if (b.empty() || x != b.back()) b.push_back(x);
  }
  return b;
}

double KnotVector::greville(int i) const {
  if (p_ == 0) return 0.5 * ((*this)[i] + (*this)[i + 1]);
  double sum = 0.0;
  for (int k = 1; k <= p_; ++k) sum += (*this)[i + k];
  return sum / p_;
}

}  // namespace probecomp::nurbs
