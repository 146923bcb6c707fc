#pragma once
// De Casteljau on one Bézier line of control values (points, homogeneous points, vectors) in place: the part
// [t0, t1] ⊂ [0, 1] of the curve, reparametrised to [0, 1] (The NURBS Book §1.3 and A5.4's Bézier pieces).

#include <cstddef>

namespace probecomp::nurbs {

// w[0], w[stride], …, w[deg·stride]: de Casteljau at t0 keeping the right part (ascending sweep: w[k] ends as
// P_k^(deg−k)), then at the matching point keeping the left part (descending sweep: w[k] ends as P_0^(k)).
template <class T>
void restrict_bezier(T* w, int deg, std::size_t stride, double t0, double t1) {
  auto at = [&](int k) -> T& { return w[static_cast<std::size_t>(k) * stride]; };
  if (t0 > 0.0) {
    for (int level = 1; level <= deg; ++level)
      for (int k = 0; k <= deg - level; ++k) at(k) = (1.0 - t0) * at(k) + t0 * at(k + 1);
  }
  const double s = t0 < 1.0 ? (t1 - t0) / (1.0 - t0) : 1.0;
  if (s < 1.0) {
    for (int level = 1; level <= deg; ++level)
      for (int k = deg; k >= level; --k) at(k) = (1.0 - s) * at(k - 1) + s * at(k);
  }
}

}  // namespace probecomp::nurbs
