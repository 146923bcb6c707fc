#pragma once
// A point's basis row for the penalised fit (penalized.cpp, cross_validation.cpp): the fitted functions non-zero
// at its parameters, their values and their unknowns, in the tensor space of a surface or in a hierarchical basis
// over it. Private to fitting/.

#include <algorithm>
#include <numeric>
#include <span>
#include <vector>

#include "band.hpp"
#include "hierarchical_rows.hpp"
#include "probecomp/fitting/hierarchical.hpp"
#include "probecomp/fitting/least_squares.hpp"
#include "rational_basis.hpp"

namespace probecomp::fitting::detail {

using nurbs::Surface;

// The unknown each of rb's basis functions multiplies, in idx.
inline void row_unknowns(const Surface& s, const Ordering& order, const RationalBasis& rb, int* idx) {
  const int p = s.p(), q = s.q();
  for (int i = 0; i <= p; ++i)
    for (int j = 0; j <= q; ++j) idx[i * (q + 1) + j] = order.index(rb.i0 + i, rb.j0 + j);
}

// The start surface's control points in Cartesian form, row i (u) major: made once per fit for every basis row,
// which would otherwise divide each of its (p+1)(q+1) homogeneous points by its weight again.
inline std::vector<Point3> cartesian_net(const Surface& s) {
  std::vector<Point3> net(static_cast<std::size_t>(s.num_u()) * static_cast<std::size_t>(s.num_v()));
  for (int i = 0; i < s.num_u(); ++i)
    for (int j = 0; j < s.num_v(); ++j) net[static_cast<std::size_t>(i) * s.num_v() + j] = s.control_point(i, j);
  return net;
}

// A point's basis row: the fitted functions non-zero at t, their values and unknowns. Those are the surface s's
// rational basis functions, or with a hierarchical basis (hierarchical.hpp, s its output surface) the THB
// functions reduced from them. Rows are `m` long: a THB row shorter than that is padded with zero values on its
// last unknown, which add nothing to any sum, and `len` says how many are its own. `key` names t's knot span of s
// (its first control point's index in `order`): rows with one key have the same unknowns.
struct RowMaker {
  const Surface& s;
  std::span<const Point3> net;  // cartesian_net(s)
  const Ordering& order;        // of s's control points
  const HierarchicalBasis* thb = nullptr;
  int n = 0;  // unknowns
  int m = 0;  // row length
  RowMaker(const Surface& s_, std::span<const Point3> net_, const Ordering& order_, const HierarchicalBasis* thb_)
      : s(s_), net(net_), order(order_), thb(thb_), n(thb_ ? thb_->unknowns : s_.num_u() * s_.num_v()),
        m(thb_ ? thb_->max_row : (s_.p() + 1) * (s_.q() + 1)) {}
  [[nodiscard]] int bandwidth() const {
    return std::min(thb ? thb->bandwidth : order.bandwidth(s.p(), s.q()), n - 1);
  }
  // The row at t in R, idx, key and len; returns the start surface's point S⁰(t), which every use of a row needs.
  Vector3 operator()(const SurfaceParameter& t, RationalBasis& rb, double* R, int* idx, int& key, int& len) const {
    rational_basis(s, t.u, t.v, rb);
    const int p = s.p(), q = s.q();
    Vector3 S0 = Vector3::Zero();
    for (int i = 0; i <= p; ++i) {
      const Point3* row = &net[static_cast<std::size_t>(rb.i0 + i) * s.num_v() + rb.j0];
      for (int j = 0; j <= q; ++j) S0 += rb.R[i * (q + 1) + j] * row[j];
    }
    key = order.index(rb.i0, rb.j0);
    if (thb == nullptr) {
      row_unknowns(s, order, rb, idx);
      std::copy(rb.R, rb.R + m, R);
      len = m;
    } else {
      len = reduce_row(*thb, rb.i0, rb.j0, rb.R, R, idx);
      std::fill(R + len, R + m, 0.0);
      std::fill(idx + len, idx + m, idx[len - 1]);
    }
    return S0;
  }
};

// The envelope (Band::first) of the normal matrix in the maker's basis: two functions meet in AᵀWA and in the
// penalty only where both are non-zero on one knot span. For a hierarchical basis, whose rows vary in width (S11 of
// the shape suite: 246 on average against its widest 386, docs/performance.md); empty for a tensor space, whose rows
// are all about its bandwidth wide.
inline std::vector<int> envelope(const RowMaker& maker) {
  if (maker.thb == nullptr) return {};
  const HierarchicalBasis& basis = *maker.thb;
  std::vector<int> first(static_cast<std::size_t>(basis.unknowns));
  std::iota(first.begin(), first.end(), 0);
  for (std::size_t c = 0; c + 1 < basis.cell_first.size(); ++c) {
    const auto begin = static_cast<std::size_t>(basis.cell_first[c]), end = static_cast<std::size_t>(basis.cell_first[c + 1]);
    if (begin == end) continue;
    const int smallest = basis.cell_unknowns[begin];  // sorted
    for (std::size_t e = begin; e < end; ++e) {
      int& f = first[static_cast<std::size_t>(basis.cell_unknowns[e])];
      f = std::min(f, smallest);
    }
  }
  // Non-decreasing, so that each column's non-zeros below the diagonal run on from it without a gap.
  for (std::size_t I = first.size(); I-- > 1;) first[I - 1] = std::min(first[I - 1], first[I]);
  return first;
}

}  // namespace probecomp::fitting::detail
