#pragma once
// The closest-point solver's cells (closest_point_cells.cpp): each cell's bounds, kept in floats, the hierarchy
// over them that a query walks, and the helpers that cut a surface into cells. Private to nurbs/.

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "probecomp/nurbs/closest_point.hpp"

namespace probecomp::nurbs::detail {

// The cells along one parameter direction: each knot span cut into its own number of equal sub-cells.
struct CellAxis {
  std::vector<double> breaks;  // distinct knots
  std::vector<int> first;      // first[s]: the first cell of span s; first.back() = number of cells
  std::vector<int> span_of;    // the span of each cell
  std::vector<int> knot_span;  // each span's index in the Bézier-refined knot vector (KnotVector::find_span)

  CellAxis() = default;
  CellAxis(const KnotVector& K, const std::vector<int>& per_span) : breaks(K.breakpoints()), first{0} {
    for (std::size_t s = 0; s < per_span.size(); ++s) {
      knot_span.push_back(K.find_span(0.5 * (breaks[s] + breaks[s + 1])));
      first.push_back(first.back() + per_span[s]);
      span_of.insert(span_of.end(), static_cast<std::size_t>(per_span[s]), static_cast<int>(s));
    }
  }
  [[nodiscard]] int count() const { return first.back(); }
  [[nodiscard]] int spans() const { return static_cast<int>(breaks.size()) - 1; }
  [[nodiscard]] int span(int c) const { return span_of[static_cast<std::size_t>(c)]; }
  [[nodiscard]] int cells_in(int s) const { return first[s + 1] - first[s]; }
  // Cell c's part [t0, t1] of its span, as fractions of the span.
  [[nodiscard]] double t0(int c) const { return static_cast<double>(c - first[span(c)]) / cells_in(span(c)); }
  [[nodiscard]] double t1(int c) const { return static_cast<double>(c + 1 - first[span(c)]) / cells_in(span(c)); }
  [[nodiscard]] bool first_in_span(int c) const { return c == first[span(c)]; }
  [[nodiscard]] bool last_in_span(int c) const { return c + 1 == first[span(c) + 1]; }
  [[nodiscard]] double lower(int c) const { return at(span(c), c - first[span(c)]); }
  [[nodiscard]] double upper(int c) const { return at(span(c), c + 1 - first[span(c)]); }

 private:
  [[nodiscard]] double at(int s, int sub) const {
    const int per = cells_in(s);
    return sub == per ? breaks[s + 1] : breaks[s] + (breaks[s + 1] - breaks[s]) * sub / per;
  }
};

// The largest float not above x (float_below) and the smallest not below it (float_above): a box stored in floats
// rounded so only grows. Infinities and NaN stay what they are; a finite x beyond the float range gives the largest
// float or an infinity, on the right side.
inline float float_below(double x) {
  constexpr double top = std::numeric_limits<float>::max();
  constexpr float inf = std::numeric_limits<float>::infinity();
  if (std::isnan(x) || std::isinf(x)) return static_cast<float>(x);
  if (x > top) return std::numeric_limits<float>::max();
  if (x < -top) return -inf;
  const float f = static_cast<float>(x);
  if (!(static_cast<double>(f) > x)) return f;
  // The float before f, as std::nextafter(f, −inf) gives it, without the library call (six a query): f is finite
  // here, and −FLT_MAX only where x is below it, which returned above.
  if (f == 0.0f) return -std::numeric_limits<float>::denorm_min();
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(f);
  return std::bit_cast<float>(f > 0.0f ? bits - 1 : bits + 1);
}
inline float float_above(double x) { return -float_below(-x); }
// The query rounded to floats both ways, for lower bounds on its distance to boxes stored in floats.
struct QueryInFloats {
  explicit QueryInFloats(const Point3& q)
      : up{float_above(q.x()), float_above(q.y()), float_above(q.z())},
        down{float_below(q.x()), float_below(q.y()), float_below(q.z())} {}
  float up[3], down[3];
};
// Three floats as doubles (exactly).
inline Vector3 widened(const float (&a)[3]) { return {a[0], a[1], a[2]}; }

// Each cell is bounded by an oriented box in the frame of its seed c: tangent t1 (along S_u), t2 = n × t1,
// normal n. The box encloses the cell's Bézier control points (the surface refined so that every cell is a
// Bézier patch, A5.4); with positive weights a rational patch lies in the convex hull of its control points,
// so the box contains the cell and the distance from a query to the box is a rigorous lower bound. The box
// tightens quadratically in the normal direction as cells shrink. The floor absorbs rounding.
constexpr double kCellBoundFloor = 1e-9;  // mm
// The box is kept in floats, one cache line a cell (in doubles it took two and a half; a search reads the boxes
// of the cells near the query in random order). Its frame, rounded to floats, is orthonormal to about 1e-7, and
// the extents are taken along the rounded frame and rounded outwards, so they hold the cell exactly. The bounds
// below then allow for the frame's stretch (its norm is at most 1 + 4e-7) with a slack a few times larger.
constexpr double kFrameSlack = 1e-6;

struct alignas(64) CellBox {
  float t1[3] = {1, 0, 0}, t2[3] = {0, 1, 0}, n[3] = {0, 0, 1};
  float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};  // box extent along (t1, t2, n), relative to the seed
  // tan of the half-angle of the cell's normal cone about n, rounded up with the slack; infinite where a minimum
  // need not be a critical point (cells on the domain's edges or on a C0 knot line) or no cone below 90° exists.
  float cone_tan = std::numeric_limits<float>::infinity();

  void set_frame(const Vector3& T1, const Vector3& T2, const Vector3& N);
  // The rounded normal, of unit length: the axis of the cell's normal cone.
  [[nodiscard]] Vector3 axis() const { return widened(n).normalized(); }
  void set_cone(double tan_half_angle);

  [[nodiscard]] Eigen::Array3d coordinates(const Vector3& e) const {
    return {e.dot(widened(t1)), e.dot(widened(t2)), e.dot(widened(n))};
  }

  // The box of the Cartesian points of a Bézier net (row-major, (p+1)·(q+1) homogeneous points) in this frame.
  void enclose(const Point3& origin, std::span<const HomogeneousPoint> net);

  // Whether the cell may hold a point nearer to q than `distance` that is a minimum of the distance to q.
  // Nearer: the distance to the box (along the rounded frame, whose stretch the slack allows for) is below it.
  // A minimum: a critical point (q − x parallel to the normal at x), given that every normal of the cell is within
  // the angle atan(cone_tan) of n; at such a point the component of q − x across n is at most cone_tan times its
  // component along n, and over the box the first is at least the tangential gap, the second at most the farther of
  // the box's two faces.
  [[nodiscard]] bool may_hold_closer_point(const Vector3& q_minus_c, double distance) const {
    const Eigen::Array3d x = coordinates(q_minus_c);
    const Eigen::Array3d gap = (widened(lo).array() - x).max(x - widened(hi).array()).max(0.0);
    if (!(std::sqrt(gap.square().sum()) < distance * (1.0 + kFrameSlack))) return false;
    if (!(cone_tan < std::numeric_limits<float>::infinity())) return true;
    const double height = std::max(std::abs(x[2] - lo[2]), std::abs(x[2] - hi[2]));
    return std::sqrt(gap[0] * gap[0] + gap[1] * gap[1]) <= cone_tan * height + kCellBoundFloor;
  }
};
static_assert(sizeof(CellBox) == 64);

// A Bézier patch in homogeneous form: (p+1)·(q+1) points, row i (u) major, over the parameter box `box`.
struct BezierPatch {
  Domain box;
  std::vector<HomogeneousPoint> net;
};

// Seed cell (cu, cv) of `bezier` (the surface in Bézier form) as a Bézier patch over its parameter box.
BezierPatch cell_patch(const Surface& bezier, const CellAxis& axis_u, const CellAxis& axis_v, int cu, int cv);
// The knots that make every knot span a Bézier segment.
std::vector<double> bezier_knots(const KnotVector& U);
// Each knot span's length on the part along `direction` (0: u, 1: v).
std::vector<double> span_lengths(const Surface& bezier, int direction);
// Cells per span, at least `min_cells` each, proportional to the spans' lengths, about `budget` in all.
std::vector<int> share_cells(const std::vector<double>& length, double budget, int min_cells);

}  // namespace probecomp::nurbs::detail

namespace probecomp::nurbs {

struct ClosestPointSolver::Seeds {
  explicit Seeds(Surface refined) : bezier(std::move(refined)) {}
  detail::CellAxis axis_u, axis_v;
  Surface bezier;  // the surface refined so that knot span (i, j) has control points i·p .. i·p+p by j·q .. j·q+q
  // What the gathering pass reads of each cell, in half a cache line.
  struct Cell {
    Point3 seed;        // the surface at the cell's centre
    float reach = 0.0;  // no point of the cell is farther from the seed (its control points' farthest, rounded up)
    std::uint8_t in_region = 1;  // the cell meets the region (all cells without one)
    std::uint8_t on_face = 1;    // the seed lies in the region (all seeds without one): a point of the face
  };
  std::vector<Cell> cell;
  // The derivatives at each cell's centre, in floats: Newton's first step from the centre, taken without evaluating
  // the surface there (one evaluation of about four fewer a search). One cache line.
  struct alignas(64) Start {
    float d[5][3];  // S_u, S_v, S_uu, S_uv, S_vv
    bool usable = false;  // every value finite and within the float range
    [[nodiscard]] SurfaceD2 at(const Point3& S) const {
      return {S, detail::widened(d[0]), detail::widened(d[1]), detail::widened(d[2]), detail::widened(d[3]),
              detail::widened(d[4])};
    }
  };
  std::vector<Start> start;
  std::vector<double> u, v;  // the cell's centre
  std::vector<detail::CellBox> box;
  // A bounding-volume hierarchy over the cells, built on the parameter grid: halving the longer of the two index
  // ranges keeps every node a compact piece of the surface. A leaf is a block of up to 2 × 2 cells (two levels fewer
  // to walk than one cell a leaf: 12–20 % faster queries on the panel benchmark). An inner node holds up to four
  // children (two halvings at once) and their axis-aligned boxes, in floats rounded outwards (a box only grows, so
  // its distance stays a lower bound), axis by axis so that one SSE operation takes all four: half the levels of a
  // binary hierarchy to walk, each two adjacent cache lines. Queries in random order miss the cache at nearly every
  // step.
  static constexpr int kFanOut = 4;
  struct alignas(64) Node {
    float lo[3][kFanOut], hi[3][kFanOut];  // the children's boxes by axis: empty (lo = +inf, hi = −inf) where no
                                           // cell of the child meets the region, and in unused slots
    std::int64_t child[kFanOut];           // an inner node's index, or a leaf's cells as leaf_ref() encodes them
  };
  std::vector<Node> nodes;
  // Lower bounds on the squared distances from the query to a node's four child boxes, in single precision: the gaps
  // are taken from the query rounded towards the box (lo − up ≤ lo − q, down − hi ≤ q − hi), and the rounding of the
  // float subtractions, squares and sums (each at most 2⁻²⁴ relative, five on a path) is taken back by a factor
  // 1 − 2⁻²⁰ (also rounded: the product stays below the exact sum). An empty slot (lo = +inf) is infinitely far.
  // The four lanes in one SSE register where there is one (x86-64 always has SSE2).
  static std::array<float, kFanOut> children_distance_sq(const Node& node, const detail::QueryInFloats& q) {
    constexpr float kShrink = 1.0f - 0x1p-20f;
    std::array<float, kFanOut> sum{};
#if defined(__SSE2__)
    static_assert(kFanOut == 4);
    __m128 s = _mm_setzero_ps();
    for (int x = 0; x < 3; ++x) {
      const __m128 below = _mm_sub_ps(_mm_load_ps(node.lo[x]), _mm_set1_ps(q.up[x]));
      const __m128 above = _mm_sub_ps(_mm_set1_ps(q.down[x]), _mm_load_ps(node.hi[x]));
      const __m128 gap = _mm_max_ps(_mm_max_ps(below, above), _mm_setzero_ps());
      s = _mm_add_ps(s, _mm_mul_ps(gap, gap));
    }
    _mm_storeu_ps(sum.data(), _mm_mul_ps(s, _mm_set1_ps(kShrink)));
#else
    for (int x = 0; x < 3; ++x) {
      for (std::size_t c = 0; c < kFanOut; ++c) {
        const float gap = std::max(std::max(node.lo[x][c] - q.up[x], q.down[x] - node.hi[x][c]), 0.0f);
        sum[c] += gap * gap;
      }
    }
    for (float& v : sum) v *= kShrink;
#endif
    return sum;
  }

  // A leaf as a negative reference: its first cell (lowest u and v) and its block of cells_u × cells_v ≤ 2 × 2.
  static std::int64_t leaf_ref(std::size_t cell, int cells_u, int cells_v) {
    return -1 - static_cast<std::int64_t>(4 * cell + 2 * static_cast<std::size_t>(cells_u - 1) +
                                          static_cast<std::size_t>(cells_v - 1));
  }
  struct Leaf {
    std::uint32_t cell;
    int cells_u, cells_v;
  };
  static Leaf leaf(std::int64_t ref) {
    const std::uint64_t x = static_cast<std::uint64_t>(-1 - ref);
    return {static_cast<std::uint32_t>(x / 4), static_cast<int>((x / 2) % 2) + 1, static_cast<int>(x % 2) + 1};
  }

  struct Built {
    std::int64_t ref;
    Eigen::Array3d lo, hi;  // empty where no cell meets the region
    bool meets;             // some cell meets the region
  };
  Built root{};  // the whole hierarchy: the root's reference (as Node::child) and box
  // The hierarchy over cells [i0, i1) × [j0, j1); `leaf_lo`, `leaf_hi`: each cell's axis-aligned box.
  Built build(int i0, int i1, int j0, int j1, const std::vector<Eigen::Array3d>& leaf_lo,
              const std::vector<Eigen::Array3d>& leaf_hi);
};

}  // namespace probecomp::nurbs
