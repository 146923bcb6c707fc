#include "closest_point_cells.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "probecomp/nurbs/de_casteljau.hpp"

namespace probecomp::nurbs {

namespace detail {

void CellBox::set_frame(const Vector3& T1, const Vector3& T2, const Vector3& N) {
  for (int x = 0; x < 3; ++x) {
    t1[x] = static_cast<float>(T1[x]);
    t2[x] = static_cast<float>(T2[x]);
    n[x] = static_cast<float>(N[x]);
  }
}

void CellBox::set_cone(double tan_half_angle) {
  // An angle a slack wider (tan(θ + δ) ≤ (tan θ + 2δ) / (1 − 2δ tan θ) for small δ), then the frame's stretch.
  const double denominator = 1.0 - 2.0 * kFrameSlack * tan_half_angle;
  cone_tan = denominator > 0.5
                 ? float_above((tan_half_angle + 2.0 * kFrameSlack) / denominator * (1.0 + kFrameSlack) + kFrameSlack)
                 : std::numeric_limits<float>::infinity();
}

void CellBox::enclose(const Point3& origin, std::span<const HomogeneousPoint> net) {
  Eigen::Array3d low = Eigen::Array3d::Constant(std::numeric_limits<double>::infinity()), high = -low;
  for (const HomogeneousPoint& P : net) {
    const Eigen::Array3d x = coordinates(P.head<3>() / P.w() - origin);
    low = low.min(x);
    high = high.max(x);
  }
  for (int x = 0; x < 3; ++x) {
    lo[x] = float_below(low[x] - kCellBoundFloor);
    hi[x] = float_above(high[x] + kCellBoundFloor);
  }
}

}  // namespace detail

ClosestPointSolver::Seeds::Built ClosestPointSolver::Seeds::build(int i0, int i1, int j0, int j1,
                                                                  const std::vector<Eigen::Array3d>& leaf_lo,
                                                                  const std::vector<Eigen::Array3d>& leaf_hi) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  if (i1 - i0 <= 2 && j1 - j0 <= 2) {
    const std::size_t nv = static_cast<std::size_t>(axis_v.count());
    Built leaf{leaf_ref(static_cast<std::size_t>(i0) * nv + static_cast<std::size_t>(j0), i1 - i0, j1 - j0),
               Eigen::Array3d::Constant(inf), Eigen::Array3d::Constant(-inf), false};
    for (int i = i0; i < i1; ++i)
      for (int j = j0; j < j1; ++j) {
        const std::size_t k = static_cast<std::size_t>(i) * nv + static_cast<std::size_t>(j);
        leaf.lo = leaf.lo.min(leaf_lo[k]);
        leaf.hi = leaf.hi.max(leaf_hi[k]);
        leaf.meets = leaf.meets || cell[k].in_region != 0;
      }
    if (!leaf.meets) leaf.lo = Eigen::Array3d::Constant(inf), leaf.hi = Eigen::Array3d::Constant(-inf);
    return leaf;
  }
  // Two halvings, the longer index range first each time; a half already of leaf size is a child as it is.
  struct Range {
    int i0, i1, j0, j1;
  };
  auto is_leaf = [](const Range& r) { return r.i1 - r.i0 <= 2 && r.j1 - r.j0 <= 2; };
  auto halves = [](const Range& r) {
    if (r.i1 - r.i0 >= r.j1 - r.j0) {
      const int mid = (r.i0 + r.i1) / 2;
      return std::array<Range, 2>{Range{r.i0, mid, r.j0, r.j1}, Range{mid, r.i1, r.j0, r.j1}};
    }
    const int mid = (r.j0 + r.j1) / 2;
    return std::array<Range, 2>{Range{r.i0, r.i1, r.j0, mid}, Range{r.i0, r.i1, mid, r.j1}};
  };
  Range children[kFanOut];
  int count = 0;
  for (const Range& h : halves({i0, i1, j0, j1})) {
    if (is_leaf(h)) {
      children[count++] = h;
    } else {
      for (const Range& g : halves(h)) children[count++] = g;
    }
  }
  const std::size_t at = nodes.size();
  nodes.emplace_back();
  Built all{static_cast<std::int64_t>(at), Eigen::Array3d::Constant(inf), Eigen::Array3d::Constant(-inf), false};
  for (int c = 0; c < kFanOut; ++c) {
    Built b{0, Eigen::Array3d::Constant(inf), Eigen::Array3d::Constant(-inf), false};
    if (c < count) b = build(children[c].i0, children[c].i1, children[c].j0, children[c].j1, leaf_lo, leaf_hi);
    Node& node = nodes[at];  // build() may have moved the nodes
    node.child[c] = b.ref;
    for (int x = 0; x < 3; ++x) {
      node.lo[x][c] = detail::float_below(b.lo[x]);
      node.hi[x][c] = detail::float_above(b.hi[x]);
    }
    all.lo = all.lo.min(b.lo);
    all.hi = all.hi.max(b.hi);
    all.meets = all.meets || b.meets;
  }
  return all;
}

namespace detail {

// Seed cell (cu, cv) as a Bézier patch: its knot span's Bézier net (from the refined surface) cut down to the
// cell's part of the span by de Casteljau, and its parameter box. Refining only at the breakpoints keeps the
// refined net near the surface's own size, where refining at every cell boundary multiplied it by the cells
// per span squared (5 million points for a 105 × 83-span face).
BezierPatch cell_patch(const Surface& bezier, const CellAxis& axis_u, const CellAxis& axis_v, int cu, int cv) {
  const int p = bezier.p();
  const int q = bezier.q();
  const int su = axis_u.span(cu), sv = axis_v.span(cv);
  BezierPatch patch{{axis_u.lower(cu), axis_u.upper(cu), axis_v.lower(cv), axis_v.upper(cv)}, {}};
  patch.net.reserve(static_cast<std::size_t>((p + 1) * (q + 1)));
  for (int a = 0; a <= p; ++a)
    for (int b = 0; b <= q; ++b) patch.net.push_back(bezier.homogeneous(su * p + a, sv * q + b));

  HomogeneousPoint work[kMaxDegree + 1];
  for (int b = 0; b <= q; ++b) {
    for (int a = 0; a <= p; ++a) work[a] = patch.net[static_cast<std::size_t>(a * (q + 1) + b)];
    restrict_bezier(work, p, 1, axis_u.t0(cu), axis_u.t1(cu));
    for (int a = 0; a <= p; ++a) patch.net[static_cast<std::size_t>(a * (q + 1) + b)] = work[a];
  }
  for (int a = 0; a <= p; ++a) {
    HomogeneousPoint* row = patch.net.data() + a * (q + 1);
    restrict_bezier(row, q, 1, axis_v.t0(cv), axis_v.t1(cv));
  }
  return patch;
}

// The knots that make every knot span a Bézier segment: each interior breakpoint at multiplicity = degree.
std::vector<double> bezier_knots(const KnotVector& U) {
  std::vector<double> X;
  const std::vector<double> breaks = U.breakpoints();
  for (std::size_t c = 1; c + 1 < breaks.size(); ++c) {
    X.insert(X.end(), static_cast<std::size_t>(U.degree() - U.multiplicity(breaks[c])), breaks[c]);
  }
  return X;
}

// Each knot span's length on the part along `direction` (0: u, 1: v): the longest control polygon of the
// surface's Bézier nets across that direction (it bounds the curves' lengths).
std::vector<double> span_lengths(const Surface& bezier, int direction) {
  const int p = bezier.p(), q = bezier.q();
  const int spans = direction == 0 ? (bezier.num_u() - 1) / p : (bezier.num_v() - 1) / q;
  const int deg = direction == 0 ? p : q;
  const int across = direction == 0 ? bezier.num_v() : bezier.num_u();
  std::vector<double> length(static_cast<std::size_t>(spans), 0.0);
  for (int s = 0; s < spans; ++s) {
    for (int line = 0; line < across; ++line) {
      double l = 0.0;
      for (int a = 0; a < deg; ++a) {
        const int k = s * deg + a;
        l += direction == 0 ? (bezier.control_point(k + 1, line) - bezier.control_point(k, line)).norm()
                            : (bezier.control_point(line, k + 1) - bezier.control_point(line, k)).norm();
      }
      length[static_cast<std::size_t>(s)] = std::max(length[static_cast<std::size_t>(s)], l);
    }
  }
  return length;
}

// Cells per span, at least `min_cells` each, proportional to the spans' lengths, about `budget` in all: the
// largest cell length h with Σ max(min_cells, ⌈L_s / h⌉) ≤ budget (bisection; the sum falls as h grows).
std::vector<int> share_cells(const std::vector<double>& length, double budget, int min_cells) {
  const int mean = static_cast<int>(std::ceil(budget / static_cast<double>(length.size())));
  auto cells = [&](double h, std::vector<int>* out) {
    double total = 0.0;
    for (std::size_t s = 0; s < length.size(); ++s) {
      const double c = std::max(static_cast<double>(min_cells), std::ceil(length[s] / h));
      total += c;
      if (out != nullptr) (*out)[s] = static_cast<int>(c);
    }
    return total;
  };
  const double longest = *std::max_element(length.begin(), length.end());
  std::vector<int> per_span(length.size(), std::max(mean, min_cells));
  if (!(longest > 0.0) || !std::isfinite(longest)) return per_span;
  double lo = longest / (4.0 * budget), hi = longest;  // at lo the sum exceeds the budget; at hi it is minimal
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (cells(mid, nullptr) > budget ? lo : hi) = mid;
  }
  cells(hi, &per_span);
  return per_span;
}

}  // namespace detail

}  // namespace probecomp::nurbs
