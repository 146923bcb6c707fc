#include "probecomp/nurbs/degree_elevation.hpp"

#include <string>

namespace probecomp::nurbs {

Surface elevate_degree_u(const Surface& s, int t) {
  if (t < 0 || s.p() + t > kMaxDegree) {
    throw InvalidGeometry("degree elevation by " + std::to_string(t) + " from degree " + std::to_string(s.p()) +
                          " leaves 0.." + std::to_string(kMaxDegree));
  }
  if (t == 0) return s;
  const int p = s.p();
  // Decompose: every interior knot to multiplicity p, so that segment k owns poles k·p .. k·p + p.
  const std::vector<double> breaks = s.U().breakpoints();
  std::vector<double> X;
  for (std::size_t k = 1; k + 1 < breaks.size(); ++k) {
    for (int m = s.U().multiplicity(breaks[k]); m < p; ++m) X.push_back(breaks[k]);
  }
  const Surface bezier = X.empty() ? s : refine_knots_u(s, X);
  const int segments = static_cast<int>(breaks.size()) - 1;
  const int nv = bezier.num_v();
  const int q = p + t;
  const int nu = segments * q + 1;
  std::vector<HomogeneousPoint> Qw(static_cast<std::size_t>(nu * nv));
  std::vector<HomogeneousPoint> b(static_cast<std::size_t>(q + 1)), e(static_cast<std::size_t>(q + 1));
  for (int j = 0; j < nv; ++j) {
    for (int k = 0; k < segments; ++k) {
      for (int i = 0; i <= p; ++i) {
        b[static_cast<std::size_t>(i)] = bezier.homogeneous()[static_cast<std::size_t>((k * p + i) * nv + j)];
      }
      // Eq. 5.36, once per degree: Q_i = (i/(d+1))·B_{i−1} + (1 − i/(d+1))·B_i for d → d + 1.
      for (int d = p; d < q; ++d) {
        e[0] = b[0];
        e[static_cast<std::size_t>(d + 1)] = b[static_cast<std::size_t>(d)];
        for (int i = 1; i <= d; ++i) {
          const double a = static_cast<double>(i) / (d + 1);
          e[static_cast<std::size_t>(i)] = a * b[static_cast<std::size_t>(i - 1)] + (1.0 - a) * b[static_cast<std::size_t>(i)];
        }
        std::swap(b, e);
      }
      for (int i = 0; i <= q; ++i) Qw[static_cast<std::size_t>((k * q + i) * nv + j)] = b[static_cast<std::size_t>(i)];
    }
  }
  std::vector<double> U(static_cast<std::size_t>(q + 1), breaks.front());
  for (int k = 1; k < segments; ++k) U.insert(U.end(), static_cast<std::size_t>(q), breaks[static_cast<std::size_t>(k)]);
  U.insert(U.end(), static_cast<std::size_t>(q + 1), breaks.back());
  return Surface(KnotVector(std::move(U), q), bezier.V(), std::move(Qw));
}

Surface elevate_degree_v(const Surface& s, int t) { return transposed(elevate_degree_u(transposed(s), t)); }

}  // namespace probecomp::nurbs
