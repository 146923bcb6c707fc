#pragma once
// A hierarchical basis's row at a point from its output surface's rational basis row there: the map the
// penalised fit applies to every basis row it makes (hierarchical.hpp). Private to fitting/.

#include <algorithm>

#include "probecomp/fitting/hierarchical.hpp"

namespace probecomp::fitting::detail {

// The THB functions of the span whose first control point is (i0, j0), given the output surface's (p+1)(q+1)
// rational basis values R_out there (R_out[a·(q+1) + b] for control point (i0 + a, j0 + b)): their unknowns,
// sorted, in idx and their values in R; returns their number m (≤ basis.max_row).
inline int reduce_row(const HierarchicalBasis& basis, int i0, int j0, const double* R_out, double* R, int* idx) {
  const int p = basis.surface.p(), q = basis.surface.q(), nv = basis.surface.num_v();
  const int cell = i0 * nv + j0;
  const int begin = basis.cell_first[static_cast<std::size_t>(cell)];
  const int m = basis.cell_first[static_cast<std::size_t>(cell) + 1] - begin;
  const int* ids = &basis.cell_unknowns[static_cast<std::size_t>(begin)];
  std::copy(ids, ids + m, idx);
  std::fill(R, R + m, 0.0);
  for (int a = 0; a <= p; ++a) {
    for (int b = 0; b <= q; ++b) {
      const double r = R_out[a * (q + 1) + b];
      const auto J = static_cast<std::size_t>((i0 + a) * nv + j0 + b);
      for (int e = basis.first[J]; e < basis.first[J + 1]; ++e) {
        const int tau = basis.unknown[static_cast<std::size_t>(e)];
        const int slot = static_cast<int>(std::lower_bound(ids, ids + m, tau) - ids);
        R[slot] += basis.coefficient[static_cast<std::size_t>(e)] * r;
      }
    }
  }
  return m;
}

}  // namespace probecomp::fitting::detail
