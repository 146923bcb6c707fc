#include "probecomp/nurbs/closest_point.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "probecomp/nurbs/normal_cone.hpp"
#include "probecomp/geometry/parallel.hpp"

#include "closest_point_cells.hpp"
#include "closest_point_newton.hpp"

// The closest point's Newton is in closest_point_newton.cpp, its cells and their hierarchy in closest_point_cells.cpp;
// here the solver that searches them.

namespace probecomp::nurbs {

using detail::BezierPatch;
using detail::CellAxis;
using detail::CellBox;
using detail::QueryInFloats;
using detail::bezier_knots;
using detail::cell_patch;
using detail::flatness;
using detail::float_above;
using detail::hessian;
using detail::kCellBoundFloor;
using detail::make_iterate;
using detail::refine_in;
using detail::share_cells;
using detail::span_lengths;

// ---------------------------------------------------------------------------------------------------------
// Global search

namespace {

bool closer(const ClosestPointResult& a, const ClosestPointResult& b) {
  if (a.distance != b.distance) return a.distance < b.distance;
  if (a.u != b.u) return a.u < b.u;  // deterministic tie-break
  return a.v < b.v;
}

}  // namespace

ClosestPointSolver::ClosestPointSolver(Surface surface, ClosestPointOptions options, const ParameterRegion* region)
    : surface_(std::move(surface)), options_(options), region_(region) {
  seeds_ = std::make_unique<Seeds>(surface_);
  Seeds& sd = *seeds_;
  const int p = surface_.p();
  const int q = surface_.q();
  sd.bezier =
      refine_knots_v(refine_knots_u(surface_, bezier_knots(surface_.U())), bezier_knots(surface_.V()));
  const int spans_u = surface_.U().num_spans();
  const int spans_v = surface_.V().num_spans();
  int per_u = options_.seeds_per_span > 0 ? options_.seeds_per_span : 2 * (p + 1);
  int per_v = options_.seeds_per_span > 0 ? options_.seeds_per_span : 2 * (q + 1);
  const double spans = static_cast<double>(spans_u) * spans_v;
  if (options_.seeds_per_span == 0 && spans * per_u * per_v > options_.max_cells) {
    const int per = std::max(2, static_cast<int>(std::sqrt(options_.max_cells / spans)));
    per_u = std::min(per_u, per);
    per_v = std::min(per_v, per);
  }
  if (options_.seeds_per_span > 0) {
    sd.axis_u = CellAxis(sd.bezier.U(), std::vector<int>(static_cast<std::size_t>(spans_u), per_u));
    sd.axis_v = CellAxis(sd.bezier.V(), std::vector<int>(static_cast<std::size_t>(spans_v), per_v));
  } else {
    // The same number of cells per direction, shared out by the spans' lengths on the part: knot spans of very
    // different sizes (random or refined knots) get cells of similar size, so no cell is large enough to hold
    // two minima while tiny spans waste none.
    // An offset surface's added spans get no cells of their own (shape_spans): its cells are the size of its
    // nominal surface's.
    const int shape_u = options_.shape_spans_u > 0 ? std::min(options_.shape_spans_u, spans_u) : spans_u;
    const int shape_v = options_.shape_spans_v > 0 ? std::min(options_.shape_spans_v, spans_v) : spans_v;
    sd.axis_u = CellAxis(sd.bezier.U(), share_cells(span_lengths(sd.bezier, 0), static_cast<double>(per_u) * shape_u, 2));
    sd.axis_v = CellAxis(sd.bezier.V(), share_cells(span_lengths(sd.bezier, 1), static_cast<double>(per_v) * shape_v, 2));
  }
  const int nu = sd.axis_u.count();
  const int nv = sd.axis_v.count();

  const std::size_t n = static_cast<std::size_t>(nu) * nv;
  sd.cell.resize(n);
  sd.start.resize(n);
  std::vector<Eigen::Array3d> aabb_lo(n), aabb_hi(n);  // each cell's control points' axis-aligned box
  sd.u.resize(n);
  sd.v.resize(n);
  sd.box.resize(n);

  // A minimum on the domain's edge or on a knot line where the surface is only C0 (multiplicity ≥ degree) need
  // not be a critical point: cells touching one are never culled by their normal cone.
  auto edge_or_crease = [](const CellAxis& axis, const KnotVector& K, int c) {
    auto crease = [&](int b) { return b == 0 || b == axis.spans() || K.multiplicity(axis.breaks[b]) >= K.degree(); };
    return (axis.first_in_span(c) && crease(axis.span(c))) || (axis.last_in_span(c) && crease(axis.span(c) + 1));
  };
  tbb::parallel_for(0, nu, [&](int i) {
    for (int j = 0; j < nv; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * nv + j;
      sd.u[k] = 0.5 * (sd.axis_u.lower(i) + sd.axis_u.upper(i));
      sd.v[k] = 0.5 * (sd.axis_v.lower(j) + sd.axis_v.upper(j));
      // On the Bézier form in the cell's known spans, as the search's Newton evaluates: Bernstein polynomials.
      const KnotSpans spans{sd.axis_u.knot_span[static_cast<std::size_t>(sd.axis_u.span(i))],
                            sd.axis_v.knot_span[static_cast<std::size_t>(sd.axis_v.span(j))]};
      const SurfaceD2 d = derivatives_d2(sd.bezier, sd.u[k], sd.v[k], spans);
      const Vector3* dk[5] = {&d.Su, &d.Sv, &d.Suu, &d.Suv, &d.Svv};
      sd.start[k].usable = true;
      for (int a = 0; a < 5; ++a)
        for (int x = 0; x < 3; ++x) {
          const double value = (*dk[a])[x];
          sd.start[k].usable = sd.start[k].usable && std::abs(value) < std::numeric_limits<float>::max();
          sd.start[k].d[a][x] = sd.start[k].usable ? static_cast<float>(value) : 0.0f;
        }
      const UnitNormal un = unit_normal(surface_, sd.u[k], sd.v[k], d.Su, d.Sv);
      CellBox& box = sd.box[k];
      // Any orthonormal frame gives a valid bound; the tangent frame gives a thin box.
      if (un.status != UnitNormal::Status::Degenerate && d.Su.norm() > 0.0) {
        const Vector3 t1 = (d.Su - d.Su.dot(un.n) * un.n).normalized();
        box.set_frame(t1, un.n.cross(t1), un.n);
      }
      const BezierPatch patch = cell_patch(sd.bezier, sd.axis_u, sd.axis_v, i, j);
      box.enclose(d.S, patch.net);
      aabb_lo[k] = Eigen::Array3d::Constant(std::numeric_limits<double>::infinity());
      aabb_hi[k] = -aabb_lo[k];
      double reach = 0.0;
      for (const HomogeneousPoint& P : patch.net) {
        const Point3 x = P.head<3>() / P.w();
        aabb_lo[k] = aabb_lo[k].min(x.array());
        aabb_hi[k] = aabb_hi[k].max(x.array());
        reach = std::max(reach, (x - d.S).norm());
      }
      aabb_lo[k] -= kCellBoundFloor;
      aabb_hi[k] += kCellBoundFloor;
      Seeds::Cell& c = sd.cell[k];
      c.seed = d.S;
      c.reach = float_above(reach + kCellBoundFloor);
      if (region_ != nullptr) c.in_region = region_->meets(patch.box) ? 1 : 0;
    }
  });
  // Normal cones: each knot span's normal polynomial (normal_cone.hpp) cut into its cells, about each cell's frame.
  tbb::parallel_for(0, spans_u * spans_v, [&](int span) {
    const int su = span / spans_v, sv = span % spans_v;
    std::vector<HomogeneousPoint> net;
    for (int a = 0; a <= p; ++a)
      for (int b = 0; b <= q; ++b) net.push_back(sd.bezier.homogeneous(su * p + a, sv * q + b));
    const int first_u = sd.axis_u.first[static_cast<std::size_t>(su)], first_v = sd.axis_v.first[static_cast<std::size_t>(sv)];
    const std::vector<BernsteinVectorPatch> rows = split_patch(normal_polynomial(p, q, net), 0, sd.axis_u.cells_in(su));
    for (int a = 0; a < sd.axis_u.cells_in(su); ++a) {
      const int i = first_u + a;
      if (edge_or_crease(sd.axis_u, surface_.U(), i)) continue;
      const std::vector<BernsteinVectorPatch> cells = split_patch(rows[static_cast<std::size_t>(a)], 1, sd.axis_v.cells_in(sv));
      for (int b = 0; b < sd.axis_v.cells_in(sv); ++b) {
        const int j = first_v + b;
        if (edge_or_crease(sd.axis_v, surface_.V(), j)) continue;
        const std::size_t k = static_cast<std::size_t>(i) * nv + j;
        const double c = normal_cone_cosine(cells[static_cast<std::size_t>(b)], sd.box[k].axis());
        if (c > 0.0) sd.box[k].set_cone(std::sqrt(std::max(0.0, 1.0 - c * c)) / c);
      }
    }
  });
  sd.nodes.reserve(n / 2 + 1);
  sd.root = sd.build(0, nu, 0, nv, aabb_lo, aabb_hi);
  if (region_ != nullptr) {
    for (std::size_t k = 0; k < n; ++k) {
      sd.cell[k].on_face = sd.cell[k].in_region && region_->contains(sd.u[k], sd.v[k]) ? 1 : 0;
    }
  }
}

ClosestPointSolver::~ClosestPointSolver() = default;
ClosestPointSolver::ClosestPointSolver(ClosestPointSolver&&) noexcept = default;
ClosestPointSolver& ClosestPointSolver::operator=(ClosestPointSolver&&) noexcept = default;

std::size_t ClosestPointSolver::seed_count() const { return seeds_->cell.size(); }

std::vector<Point3> ClosestPointSolver::seed_points_in_region() const {
  const Seeds& sd = *seeds_;
  std::vector<Point3> out;
  for (const Seeds::Cell& c : sd.cell) {
    if (c.on_face) out.push_back(c.seed);
  }
  return out;
}

namespace {

// Where flatness() at the best point is below this, the cells are searched again from kFocalParts² starts each.
// Measured on BM_ClosestPointAgainstDenseCells: below 0.3 are 23 of the 24 interior results that missed a closer
// minimum without this second search, and 2.2 % of all its (hard) queries.
constexpr double kFocalFlatness = 0.3;
constexpr int kFocalParts = 4;

// Squared distance from q to an axis-aligned box: a lower bound on the distance to anything inside it.
inline double box_distance_sq(const Point3& q, const Eigen::Array3d& lo, const Eigen::Array3d& hi) {
  const Eigen::Array3d x = q.array();
  return (lo - x).max(x - hi).max(0.0).square().sum();
}

}  // namespace

struct ClosestPointSolver::Search {
  ClosestPointResult best;
  double flat = 1.0;  // flatness() at the best point
  bool found = false;  // the best point is this search's own, not the bound it was given
  int iterations = 0;
  int starts = 0;
};

void ClosestPointSolver::search_cell(const Point3& query, std::uint32_t k, int parts, Search& search) const {
  const Seeds& sd = *seeds_;
  const int nv = sd.axis_v.count();
  const int cu = static_cast<int>(k) / nv;
  const int cv = static_cast<int>(k) % nv;
  const Domain cell{sd.axis_u.lower(cu), sd.axis_u.upper(cu), sd.axis_v.lower(cv), sd.axis_v.upper(cv)};
  // Newton kept inside the cell finds the cell's own minimum; unconstrained, it could run across a knot where the
  // surface is only C0 or C1 into a neighbour's basin and miss a closer point here. It runs on the Bézier form,
  // in the cell's known span: cheaper to evaluate.
  const KnotSpans spans{sd.axis_u.knot_span[static_cast<std::size_t>(sd.axis_u.span(cu))],
                        sd.axis_v.knot_span[static_cast<std::size_t>(sd.axis_v.span(cv))]};
  const double du = (cell.u1 - cell.u0) / parts, dv = (cell.v1 - cell.v0) / parts;
  // A whole cell's search starts from its centre, where the derivatives are stored.
  const Seeds::Start& at_centre = sd.start[k];
  const bool from_centre = parts == 1 && at_centre.usable;
  const SurfaceD2 start = from_centre ? at_centre.at(sd.cell[k].seed) : SurfaceD2{};
  for (int a = 0; a < parts; ++a) {
    for (int b = 0; b < parts; ++b) {
      const Domain box{a == 0 ? cell.u0 : cell.u0 + a * du, a + 1 == parts ? cell.u1 : cell.u0 + (a + 1) * du,
                       b == 0 ? cell.v0 : cell.v0 + b * dv, b + 1 == parts ? cell.v1 : cell.v0 + (b + 1) * dv};
      search_box(query, box, spans, from_centre ? &start : nullptr, search);
    }
  }
}

[[gnu::always_inline]] inline void ClosestPointSolver::search_box(const Point3& query, const Domain& box, KnotSpans spans, const SurfaceD2* start,
                                    Search& search) const {
  const Domain whole = surface_.domain();
  double flat = 1.0;
  ClosestPointResult r = refine_in(seeds_->bezier, query, 0.5 * (box.u0 + box.u1), 0.5 * (box.v0 + box.v1), box,
                                   options_.max_iterations, spans, &flat, start);
  ++search.starts;
  search.iterations += r.iterations;
  const bool on_inner_edge = r.status == ClosestPointStatus::OnBoundary &&
                             ((r.u == box.u0 && r.u != whole.u0) || (r.u == box.u1 && r.u != whole.u1) ||
                              (r.v == box.v0 && r.v != whole.v0) || (r.v == box.v1 && r.v != whole.v1));
  if (r.status == ClosestPointStatus::OnBoundary && !on_inner_edge) {
    const bool on_domain_edge = r.u == whole.u0 || r.u == whole.u1 || r.v == whole.v0 || r.v == whole.v1;
    r.status = on_domain_edge ? ClosestPointStatus::OnBoundary : ClosestPointStatus::Converged;
  }
  // Outside the region (a trimmed face) the point does not count: the region's own boundary, searched by the
  // caller, holds the minimum of the box's part inside the region unless that part has an interior minimum of
  // its own which Newton did not reach (accepted, rare).
  if (region_ != nullptr && !region_->contains(r.u, r.v)) return;
  if (on_inner_edge && closer(r, search.best)) {
    // The minimum lies beyond the edge: follow it (f only decreases on the way).
    const ClosestPointResult polished = refine_in(surface_, query, r.u, r.v, whole, options_.max_iterations, {}, &flat);
    search.iterations += polished.iterations;
    if (polished.ok() && (region_ == nullptr || region_->contains(polished.u, polished.v))) {
      r = polished;
    } else if (!polished.ok()) {
      // Newton cannot settle across the edge: the surface is only C0 there (a crease along a knot line, e.g. a
      // knot of full multiplicity) and the box's minimum on it is the minimum of both sides. The neighbouring
      // cell is searched in its own right, so a closer point beyond would still be found.
      r.status = ClosestPointStatus::Converged;
      flat = 1.0;
    }
  }
  if (closer(r, search.best)) {
    search.best = r;
    search.flat = flat;
    search.found = true;
  }
}

ClosestPointResult ClosestPointSolver::closest_point(const Point3& query) const {
  return closest_point(query, ClosestPointResult{});
}

long ClosestPointSolver::cell_holding(double u, double v) const {
  const Seeds& sd = *seeds_;
  auto cell_along = [](const CellAxis& axis, double t) -> int {
    const auto& b = axis.breaks;
    if (!(t >= b.front() && t <= b.back())) return -1;
    const int s = std::clamp(static_cast<int>(std::upper_bound(b.begin(), b.end(), t) - b.begin()) - 1, 0, axis.spans() - 1);
    const int per = axis.cells_in(s);
    const int c = axis.first[static_cast<std::size_t>(s)] +
                  std::clamp(static_cast<int>((t - b[s]) / (b[s + 1] - b[s]) * per), 0, per - 1);
    return axis.lower(c) <= t && t <= axis.upper(c) ? c : -1;
  };
  const int cu = cell_along(sd.axis_u, u), cv = cell_along(sd.axis_v, v);
  if (cu < 0 || cv < 0) return -1;
  return static_cast<long>(cu) * sd.axis_v.count() + cv;
}

ClosestPointResult ClosestPointSolver::closest_point(const Point3& query, const ClosestPointResult& bound,
                                                     const ClosestPointResult* known) const {
  const Seeds& sd = *seeds_;
  if (!query.allFinite()) {
    ClosestPointResult bad;
    bad.status = ClosestPointStatus::NumericalError;
    return bad;
  }
  Search search{bound};
  const ClosestPointResult& best = search.best;

  // One pass depth first over the cell hierarchy, nearer child first, gathers the cells whose boxes are nearer
  // than the bound: the best point given, or the nearest seed on the face seen so far (a point of the surface),
  // whichever is smaller. Squared distances throughout the pass.
  using Candidate = std::pair<double, std::uint32_t>;  // (seed's squared distance, cell)
  using Entry = std::pair<double, std::int64_t>;        // (squared distance to the node's box, node or leaf)
  thread_local std::vector<Candidate> candidates;
  thread_local std::vector<Entry> stack;
  candidates.clear();
  stack.clear();
  double bound_sq = best.distance * best.distance;
  const int nv_cells = sd.axis_v.count();
  const QueryInFloats near(query);
  constexpr std::size_t npos = std::numeric_limits<std::size_t>::max();
  std::size_t nearest = npos;  // the nearest candidate's index in `candidates`
  if (sd.root.meets) stack.emplace_back(box_distance_sq(query, sd.root.lo, sd.root.hi), sd.root.ref);
  while (!stack.empty()) {
    auto [lower_sq, ref] = stack.back();
    stack.pop_back();
    if (lower_sq >= bound_sq) continue;  // the bound has shrunk since the node was pushed
    // Down the tree: the nearest child nearer than the bound is walked next, its siblings nearer than the bound are
    // pushed farthest first (ties in slot order: the order depends on the query alone).
    while (ref >= 0) {
      const Seeds::Node& node = sd.nodes[static_cast<std::size_t>(ref)];
      const std::array<float, Seeds::kFanOut> d = Seeds::children_distance_sq(node, near);
      Entry passed[Seeds::kFanOut];
      int count = 0;
      for (int c = 0; c < Seeds::kFanOut; ++c) {
        const double dc = d[static_cast<std::size_t>(c)];
        if (!(dc < bound_sq)) continue;
        int at = count++;
        for (; at > 0 && passed[at - 1].first < dc; --at) passed[at] = passed[at - 1];
        passed[at] = {dc, node.child[c]};
      }
      if (count == 0) break;
      stack.insert(stack.end(), passed, passed + count - 1);
      ref = passed[count - 1].second;
    }
    if (ref >= 0) continue;
    const Seeds::Leaf leaf = Seeds::leaf(ref);
    for (int a = 0; a < leaf.cells_u; ++a)
      for (int b = 0; b < leaf.cells_v; ++b) {
        const std::uint32_t k = leaf.cell + static_cast<std::uint32_t>(a * nv_cells + b);
        const Seeds::Cell& c = sd.cell[k];
        if (!c.in_region) continue;
        const double seed_sq = (query - c.seed).squaredNorm();
        if (c.on_face && seed_sq < bound_sq) {
          bound_sq = seed_sq;
          // The nearest seed's cell is searched first, from its stored derivatives: ask for them while the pass
          // goes on (queries in random order find them outside the cache: 3–5 % of the query's time).
          __builtin_prefetch(&sd.start[k]);
        }
        // The nearest candidate as std::min_element would pick it (the first of the least (distance, cell) pairs).
        if (nearest == npos || Candidate{seed_sq, k} < candidates[nearest]) nearest = candidates.size();
        candidates.emplace_back(seed_sq, k);
      }
  }
  // Nearest seed first: without a bound its cell is searched whatever its tests, and its point bounds the rest;
  // after it, in the order gathered, a cell is searched only if its oriented box is nearer than the best point
  // and its normals allow a critical point there (or it lies on an edge or a crease). The order depends on the
  // query alone.
  if (!candidates.empty()) std::swap(candidates.front(), candidates[nearest]);
  long skip = -1;
  if (known != nullptr && known->ok()) {
    // Newton's own flatness when it found the known point (one evaluation fewer for every hinted exact search).
    double flat = known->flatness;
    if (std::isnan(flat)) flat = flatness(hessian(make_iterate(surface_, query, known->u, known->v, {})));
    if (flat >= kFocalFlatness) skip = cell_holding(known->u, known->v);
  }
  // The seed's distance less the cell's reach is a looser bound than the oriented box's, but needs nothing more
  // read from memory: it turns candidates away before their boxes are loaded.
  auto may_hold_closer = [&](double seed_sq, std::uint32_t k) {
    // √seed_sq − reach ≥ best: decided on the squares where they lie more than a relative 1e-14 apart (far
    // beyond the roundings of either form, so the answer is the same), the root taken only in between.
    const double reach = sd.cell[k].reach;
    const double edge = best.distance + reach;
    if (seed_sq > edge * edge * (1.0 + 1e-14)) return false;
    if (!(seed_sq < edge * edge * (1.0 - 1e-14)) && std::sqrt(seed_sq) - reach >= best.distance) return false;
    const Vector3 q_minus_c = query - sd.cell[k].seed;
    return sd.box[k].may_hold_closer_point(q_minus_c, best.distance);
  };
  for (const auto& [seed_sq, k] : candidates) {
    if (static_cast<long>(k) == skip) continue;
    if (!std::isfinite(best.distance) || may_hold_closer(seed_sq, k)) search_cell(query, k, 1, search);
  }
  // Near a centre of curvature the distance is flat: a cell may hold two minima, of which Newton finds one, and
  // Newton may not settle. There (or after any Newton that did not settle) every cell that could still hold a
  // closer point is searched again from kFocalParts² starts.
  if (search.found &&
      (best.status == ClosestPointStatus::NotConverged || (best.ok() && search.flat < kFocalFlatness))) {
    for (const auto& [seed_sq, k] : candidates) {
      if (may_hold_closer(seed_sq, k)) search_cell(query, k, kFocalParts, search);
    }
  }
  search.best.iterations = search.iterations;
  search.best.starts = search.starts;
  return search.best;
}

std::vector<ClosestPointResult> ClosestPointSolver::closest_points(std::span<const Point3> queries) const {
  return geometry::parallel_map<ClosestPointResult>(queries.size(), 256,
                                                    [&](std::size_t i) { return closest_point(queries[i]); });
}

}  // namespace probecomp::nurbs
