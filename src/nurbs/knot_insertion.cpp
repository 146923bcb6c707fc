#include "probecomp/nurbs/knot_insertion.hpp"

#include <algorithm>
#include <sstream>

namespace probecomp::nurbs {

std::pair<KnotVector, std::vector<HomogeneousPoint>> insert_knot_homogeneous(
    const KnotVector& U, const std::vector<HomogeneousPoint>& Pw, double u, int r) {
  const int p = U.degree();
  const int np = U.num_basis() - 1;  // n in A5.1
  const int s = U.multiplicity(u);
  if (r < 0) throw InvalidGeometry("knot insertion: negative count");
  if (!(u > U.front() && u < U.back())) {
    std::ostringstream m;
    m << "knot insertion: u = " << u << " is not inside the domain (" << U.front() << ", " << U.back() << ")";
    throw InvalidGeometry(m.str());
  }
  if (s + r > p) {
    std::ostringstream m;
    m << "knot insertion: u = " << u << " would reach multiplicity " << s + r << " above the degree " << p;
    throw InvalidGeometry(m.str());
  }
  if (r == 0) return {U, Pw};
  const int k = U.find_span(u);
  const auto uk = U.knots();

  std::vector<double> UQ(uk.size() + r);
  for (int i = 0; i <= k; ++i) UQ[i] = uk[i];
  for (int i = 1; i <= r; ++i) UQ[k + i] = u;
  for (int i = k + 1; i < static_cast<int>(uk.size()); ++i) UQ[i + r] = uk[i];

  std::vector<HomogeneousPoint> Qw(Pw.size() + r);
  for (int i = 0; i <= k - p; ++i) Qw[i] = Pw[i];
  for (int i = k - s; i <= np; ++i) Qw[i + r] = Pw[i];
  std::vector<HomogeneousPoint> Rw(p - s + 1);
  for (int i = 0; i <= p - s; ++i) Rw[i] = Pw[k - p + i];
  int L = 0;
  for (int j = 1; j <= r; ++j) {
    L = k - p + j;
    for (int i = 0; i <= p - j - s; ++i) {
      const double alpha = (u - uk[L + i]) /
                           (uk[i + k + 1] - uk[L + i]);
      Rw[i] = alpha * Rw[i + 1] + (1.0 - alpha) * Rw[i];
    }
    Qw[L] = Rw[0];
    Qw[k + r - j - s] = Rw[p - j - s];
  }
  for (int i = L + 1; i < k - s; ++i) Qw[i] = Rw[i - L];
  return {KnotVector(std::move(UQ), p), std::move(Qw)};
}

std::pair<KnotVector, std::vector<HomogeneousPoint>> refine_knots_homogeneous(
    const KnotVector& U, const std::vector<HomogeneousPoint>& Pw, const std::vector<double>& X) {
  if (X.empty()) return {U, Pw};
  if (!std::is_sorted(X.begin(), X.end())) throw InvalidGeometry("knot refinement: the knots to insert are not sorted");
  if (!(X.front() > U.front() && X.back() < U.back())) {
    throw InvalidGeometry("knot refinement: a knot to insert is not inside the domain");
  }
  const int p = U.degree();
  const int n = U.num_basis() - 1;
  const int m = n + p + 1;
  const int r = static_cast<int>(X.size()) - 1;
  const auto u = U.knots();
  const int a = U.find_span(X.front());
  const int b = U.find_span(X.back()) + 1;

  std::vector<double> Ubar(u.size() + X.size());
  std::vector<HomogeneousPoint> Qw(Pw.size() + X.size());
  for (int j = 0; j <= a - p; ++j) Qw[j] = Pw[j];
  for (int j = b - 1; j <= n; ++j) Qw[j + r + 1] = Pw[j];
  for (int j = 0; j <= a; ++j) Ubar[j] = u[j];
  for (int j = b + p; j <= m; ++j) Ubar[j + r + 1] = u[j];
  int i = b + p - 1;
  int k = b + p + r;
  for (int j = r; j >= 0; --j) {
    while (X[j] <= u[i] && i > a) {
      Qw[k - p - 1] = Pw[i - p - 1];
      Ubar[k] = u[i];
      --k;
      --i;
    }
    Qw[k - p - 1] = Qw[k - p];
    for (int l = 1; l <= p; ++l) {
      const int ind = k - p + l;
      double alpha = Ubar[k + l] - X[j];
      if (alpha == 0.0) {
        Qw[ind - 1] = Qw[ind];
      } else {
        alpha /= Ubar[k + l] - u[i - p + l];
        Qw[ind - 1] = alpha * Qw[ind - 1] + (1.0 - alpha) * Qw[ind];
      }
    }
    Ubar[k] = X[j];
    --k;
  }
  // The KnotVector constructor rejects multiplicities above the degree.
  return {KnotVector(std::move(Ubar), p), std::move(Qw)};
}

}  // namespace probecomp::nurbs
