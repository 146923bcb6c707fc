#include "nurbs/closest_point.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "nurbs/point_tree.hpp"

namespace probecomp::nurbs {

const char* to_string(ClosestPointStatus s) {
  switch (s) {
    case ClosestPointStatus::Converged: return "converged";
    case ClosestPointStatus::OnBoundary: return "on-boundary";
    case ClosestPointStatus::NotConverged: return "not-converged";
    case ClosestPointStatus::NumericalError: return "numerical-error";
  }
  return "unknown";
}

// ---------------------------------------------------------------------------------------------------------
// Local Newton iteration

namespace {

// Cosine below which a stalled iteration (no further decrease of f possible in double precision) still
// counts as a minimum: rounding in S − P limits the attainable cosine to about 1e-16·|P| / |S − P|.
constexpr double kStallCosine = 1e-7;
// Backtracking halvings before a step is declared unable to decrease f.
constexpr int kMaxHalvings = 30;
struct Iterate {
  double u, v;
  SurfaceD2 d;
  Vector3 r;  // S − P
  double f;   // |S − P|²
};

// Near the minimum f is flat: a tangential move of 1e-8 mm changes f by about 1e-16 mm², below its rounding.
// A Newton step is accepted unless it increases f by more than rounding, so the quadratic convergence can
// finish instead of stalling a few digits short. f = |S − P|² is computed from coordinates of size |P|, so
// its rounding is about 2·|S − P|·(ε·|P|) per coordinate: absolute, not relative to f.
double rounding_of_f(const Point3& P, const Iterate& it) {
  constexpr double eps = std::numeric_limits<double>::epsilon();
  return 16.0 * eps * (P.norm() + it.d.S.norm()) * std::sqrt(it.f) + 4.0 * eps * it.f;
}

Iterate make_iterate(const Surface& s, const Point3& P, double u, double v) {
  Iterate it{u, v, derivatives_d2(s, u, v), Vector3::Zero(), 0.0};
  it.r = it.d.S - P;
  it.f = it.r.squaredNorm();
  return it;
}

// Which parameters sit on a domain edge with the gradient pushing them outwards (the active set).
struct ActiveSet {
  bool u = false;
  bool v = false;
};

ActiveSet active_set(const Domain& dom, const Iterate& it, double gu, double gv) {
  return {(it.u <= dom.u0 && gu > 0.0) || (it.u >= dom.u1 && gu < 0.0),
          (it.v <= dom.v0 && gv > 0.0) || (it.v >= dom.v1 && gv < 0.0)};
}

// Newton step on the free parameters; Gauss–Newton (Hessian without the curvature terms, always positive
// semi-definite) where the full Hessian is not positive definite, e.g. far from a concave region's centre.
std::array<double, 2> newton_step(const Iterate& it, double gu, double gv, ActiveSet active) {
  const auto& d = it.d;
  const double Juu = d.Su.dot(d.Su);
  const double Juv = d.Su.dot(d.Sv);
  const double Jvv = d.Sv.dot(d.Sv);
  const double Huu = Juu + it.r.dot(d.Suu);
  const double Huv = Juv + it.r.dot(d.Suv);
  const double Hvv = Jvv + it.r.dot(d.Svv);
  auto solve1 = [](double h, double j, double g) {
    if (h > 0.0) return -g / h;
    if (j > 0.0) return -g / j;
    return 0.0;
  };
  if (active.u) return {0.0, solve1(Hvv, Jvv, gv)};
  if (active.v) return {solve1(Huu, Juu, gu), 0.0};
  const double det = Huu * Hvv - Huv * Huv;
  if (Huu > 0.0 && det > 1e-14 * Huu * Hvv) {
    return {(-gu * Hvv + gv * Huv) / det, (gu * Huv - gv * Huu) / det};
  }
  const double detJ = Juu * Jvv - Juv * Juv;
  if (Juu > 0.0 && detJ > 1e-14 * Juu * Jvv) {
    return {(-gu * Jvv + gv * Juv) / detJ, (gu * Juv - gv * Juu) / detJ};
  }
  // Tangents parallel (a pole): move along each tangent separately.
  return {solve1(Huu, Juu, gu), solve1(Hvv, Jvv, gv)};
}

}  // namespace

ClosestPointResult refine_closest_point(const Surface& s, const Point3& P, double u0, double v0, int max_iterations) {
  return refine_closest_point_in(s, P, u0, v0, s.domain(), max_iterations);
}

ClosestPointResult refine_closest_point_in(const Surface& s, const Point3& P, double u0, double v0, const Domain& dom,
                                           int max_iterations) {
  ClosestPointResult result;
  Iterate it = make_iterate(s, P, std::clamp(u0, dom.u0, dom.u1), std::clamp(v0, dom.v0, dom.v1));

  auto finish = [&](ClosestPointStatus status) {
    result.status = status;
    result.u = it.u;
    result.v = it.v;
    result.point = it.d.S;
    result.distance = std::sqrt(it.f);
    return result;
  };

  for (int k = 0; k < max_iterations; ++k) {
    if (!std::isfinite(it.f) || !it.d.Su.allFinite() || !it.d.Sv.allFinite()) {
      return finish(ClosestPointStatus::NumericalError);
    }
    const double dist = std::sqrt(it.f);
    if (dist == 0.0) return finish(ClosestPointStatus::Converged);
    const double gu = it.r.dot(it.d.Su);
    const double gv = it.r.dot(it.d.Sv);
    const ActiveSet active = active_set(dom, it, gu, gv);
    const double cos_u = std::abs(gu) / (it.d.Su.norm() * dist);
    const double cos_v = std::abs(gv) / (it.d.Sv.norm() * dist);
    const bool u_done = active.u || !(cos_u > kClosestPointZeroCosine);
    const bool v_done = active.v || !(cos_v > kClosestPointZeroCosine);
    const auto converged_status = (active.u || active.v) ? ClosestPointStatus::OnBoundary : ClosestPointStatus::Converged;
    if (u_done && v_done) return finish(converged_status);

    ++result.iterations;
    auto [du, dv] = newton_step(it, gu, gv, active);
    Iterate next = it;
    bool decreased = false;
    for (int h = 0; h <= kMaxHalvings; ++h) {
      next = make_iterate(s, P, std::clamp(it.u + du, dom.u0, dom.u1), std::clamp(it.v + dv, dom.v0, dom.v1));
      if (next.f <= it.f + rounding_of_f(P, it)) {
        decreased = true;
        break;
      }
      du *= 0.5;
      dv *= 0.5;
    }
    if (!decreased) {
      // No representable step decreases f: we are at the minimum to rounding, or stuck at a saddle.
      const bool stalled_ok = (active.u || cos_u <= kStallCosine) && (active.v || cos_v <= kStallCosine);
      return finish(stalled_ok ? converged_status : ClosestPointStatus::NotConverged);
    }
    const double step = ((next.u - it.u) * it.d.Su + (next.v - it.v) * it.d.Sv).norm();
    it = next;
    if (step < kClosestPointStepTolerance) {
      const double g2u = it.r.dot(it.d.Su);
      const double g2v = it.r.dot(it.d.Sv);
      const ActiveSet a2 = active_set(dom, it, g2u, g2v);
      return finish((a2.u || a2.v) ? ClosestPointStatus::OnBoundary : ClosestPointStatus::Converged);
    }
  }
  return finish(ClosestPointStatus::NotConverged);
}

// ---------------------------------------------------------------------------------------------------------
// Global search

namespace {

// The cells along one parameter direction: `per_span` equal sub-cells in each knot span.
struct CellAxis {
  std::vector<double> breaks;  // distinct knots
  int per_span = 1;

  [[nodiscard]] int count() const { return static_cast<int>(breaks.size() - 1) * per_span; }
  [[nodiscard]] double lower(int c) const { return at(c / per_span, c % per_span); }
  [[nodiscard]] double upper(int c) const { return at(c / per_span, c % per_span + 1); }

 private:
  [[nodiscard]] double at(int span, int sub) const {
    return sub == per_span ? breaks[span + 1] : breaks[span] + (breaks[span + 1] - breaks[span]) * sub / per_span;
  }
};

// Each cell is bounded by an oriented box in the frame of its seed c: tangent t1 (along S_u), t2 = n × t1,
// normal n. The box encloses the cell's Bézier control points (the surface refined so that every cell is a
// Bézier patch, A5.4); with positive weights a rational patch lies in the convex hull of its control points,
// so the box contains the cell and the distance from a query to the box is a rigorous lower bound. The box
// tightens quadratically in the normal direction as cells shrink. The floor absorbs rounding.
constexpr double kCellBoundFloor = 1e-9;  // mm

struct CellBox {
  Vector3 t1, t2, n;
  Eigen::Array3d lo, hi;  // box extent along (t1, t2, n), relative to the seed

  // The box of the Cartesian points of a Bézier net (row-major, (p+1)·(q+1) homogeneous points) in this frame.
  void enclose(const Point3& origin, std::span<const HomogeneousPoint> net) {
    lo = Eigen::Array3d::Constant(std::numeric_limits<double>::infinity());
    hi = -lo;
    for (const HomogeneousPoint& P : net) {
      const Vector3 e = P.head<3>() / P.w() - origin;
      const Eigen::Array3d x(e.dot(t1), e.dot(t2), e.dot(n));
      lo = lo.min(x);
      hi = hi.max(x);
    }
    lo -= kCellBoundFloor;
    hi += kCellBoundFloor;
  }

  [[nodiscard]] double lower_bound(const Vector3& q_minus_c) const {
    const Eigen::Array3d x(q_minus_c.dot(t1), q_minus_c.dot(t2), q_minus_c.dot(n));
    const Eigen::Array3d gap = (lo - x).max(x - hi).max(0.0);
    return std::sqrt(gap.square().sum());
  }
};

// A Bézier patch in homogeneous form: (p+1)·(q+1) points, row i (u) major, over the parameter box `box`.
struct BezierPatch {
  int p, q;
  Domain box;
  std::vector<HomogeneousPoint> net;
};

// De Casteljau at the middle of the u range (a = 0) or v range (a = 1): the two halves of the patch.
std::array<BezierPatch, 2> split(const BezierPatch& b, int direction) {
  std::array<BezierPatch, 2> halves{b, b};
  const int rows = b.p + 1;
  const int cols = b.q + 1;
  const int deg = direction == 0 ? b.p : b.q;
  const int lines = direction == 0 ? cols : rows;
  HomogeneousPoint work[kMaxDegree + 1];
  for (int line = 0; line < lines; ++line) {
    auto at = [&](int k) -> int { return direction == 0 ? k * cols + line : line * cols + k; };
    for (int k = 0; k <= deg; ++k) work[k] = b.net[at(k)];
    halves[0].net[at(0)] = work[0];
    halves[1].net[at(deg)] = work[deg];
    for (int level = 1; level <= deg; ++level) {
      for (int k = 0; k <= deg - level; ++k) work[k] = 0.5 * (work[k] + work[k + 1]);
      halves[0].net[at(level)] = work[0];
      halves[1].net[at(deg - level)] = work[deg - level];
    }
  }
  if (direction == 0) {
    const double mid = 0.5 * (b.box.u0 + b.box.u1);
    halves[0].box.u1 = mid;
    halves[1].box.u0 = mid;
  } else {
    const double mid = 0.5 * (b.box.v0 + b.box.v1);
    halves[0].box.v1 = mid;
    halves[1].box.v0 = mid;
  }
  return halves;
}

bool closer(const ClosestPointResult& a, const ClosestPointResult& b) {
  if (a.distance != b.distance) return a.distance < b.distance;
  if (a.u != b.u) return a.u < b.u;  // deterministic tie-break
  return a.v < b.v;
}

}  // namespace

struct ClosestPointSolver::Seeds {
  explicit Seeds(Surface refined) : bezier(std::move(refined)) {}
  CellAxis axis_u, axis_v;
  Surface bezier;  // the surface refined so that knot span (i, j) has control points i·p .. i·p+p by j·q .. j·q+q
  PointCloud cloud;
  std::vector<double> u, v, radius;  // radius: largest distance from the seed to its cell's control points
  std::vector<CellBox> box;
  std::vector<char> in_region;  // the cell meets the region (all cells without one)
  double max_radius = 0.0;
  std::unique_ptr<PointTree> tree;
};

namespace {

// The part [t0, t1] ⊂ [0, 1] of a Bézier curve w[0..deg], in place: de Casteljau at t0 keeping the right part
// (ascending sweep: w[k] ends as P_k^(deg−k)), then at the matching point keeping the left part (descending
// sweep: w[k] ends as P_0^(k)).
void restrict_bezier(HomogeneousPoint* w, int deg, double t0, double t1) {
  if (t0 > 0.0) {
    for (int level = 1; level <= deg; ++level) {
      for (int k = 0; k <= deg - level; ++k) w[k] = (1.0 - t0) * w[k] + t0 * w[k + 1];
    }
  }
  const double s = t0 < 1.0 ? (t1 - t0) / (1.0 - t0) : 1.0;
  if (s < 1.0) {
    for (int level = 1; level <= deg; ++level) {
      for (int k = deg; k >= level; --k) w[k] = (1.0 - s) * w[k - 1] + s * w[k];
    }
  }
}

// Seed cell (cu, cv) as a Bézier patch: its knot span's Bézier net (from the refined surface) cut down to the
// cell's part of the span by de Casteljau, and its parameter box. Refining only at the breakpoints keeps the
// refined net near the surface's own size, where refining at every cell boundary multiplied it by the cells
// per span squared (5 million points for a 105 × 83-span face).
BezierPatch cell_patch(const Surface& bezier, const CellAxis& axis_u, const CellAxis& axis_v, int cu, int cv) {
  const int p = bezier.p();
  const int q = bezier.q();
  const int su = cu / axis_u.per_span, sv = cv / axis_v.per_span;
  BezierPatch patch{p, q, {axis_u.lower(cu), axis_u.upper(cu), axis_v.lower(cv), axis_v.upper(cv)}, {}};
  patch.net.reserve(static_cast<std::size_t>((p + 1) * (q + 1)));
  for (int a = 0; a <= p; ++a)
    for (int b = 0; b <= q; ++b) patch.net.push_back(bezier.homogeneous(su * p + a, sv * q + b));
  const double u0 = static_cast<double>(cu % axis_u.per_span) / axis_u.per_span;
  const double v0 = static_cast<double>(cv % axis_v.per_span) / axis_v.per_span;
  HomogeneousPoint work[kMaxDegree + 1];
  for (int b = 0; b <= q; ++b) {
    for (int a = 0; a <= p; ++a) work[a] = patch.net[static_cast<std::size_t>(a * (q + 1) + b)];
    restrict_bezier(work, p, u0, u0 + 1.0 / axis_u.per_span);
    for (int a = 0; a <= p; ++a) patch.net[static_cast<std::size_t>(a * (q + 1) + b)] = work[a];
  }
  for (int a = 0; a <= p; ++a) {
    HomogeneousPoint* row = patch.net.data() + a * (q + 1);
    restrict_bezier(row, q, v0, v0 + 1.0 / axis_v.per_span);
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
}  // namespace

ClosestPointSolver::ClosestPointSolver(Surface surface, ClosestPointOptions options, const ParameterRegion* region)
    : surface_(std::move(surface)), options_(options), region_(region) {
  seeds_ = std::make_unique<Seeds>(surface_);
  Seeds& sd = *seeds_;
  const int p = surface_.p();
  const int q = surface_.q();
  int per_u = options_.seeds_per_span > 0 ? options_.seeds_per_span : 2 * (p + 1);
  int per_v = options_.seeds_per_span > 0 ? options_.seeds_per_span : 2 * (q + 1);
  const double spans = static_cast<double>(surface_.U().num_spans()) * surface_.V().num_spans();
  if (options_.seeds_per_span == 0 && spans * per_u * per_v > options_.max_cells) {
    const int per = std::max(2, static_cast<int>(std::sqrt(options_.max_cells / spans)));
    per_u = std::min(per_u, per);
    per_v = std::min(per_v, per);
  }
  sd.axis_u = {surface_.U().breakpoints(), per_u};
  sd.axis_v = {surface_.V().breakpoints(), per_v};
  const int nu = sd.axis_u.count();
  const int nv = sd.axis_v.count();
  sd.bezier =
      refine_knots_v(refine_knots_u(surface_, bezier_knots(surface_.U())), bezier_knots(surface_.V()));

  const std::size_t n = static_cast<std::size_t>(nu) * nv;
  sd.cloud.points.resize(n);
  sd.u.resize(n);
  sd.v.resize(n);
  sd.radius.resize(n);
  sd.box.resize(n);
  sd.in_region.assign(n, 1);
  tbb::parallel_for(0, nu, [&](int i) {
    for (int j = 0; j < nv; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * nv + j;
      sd.u[k] = 0.5 * (sd.axis_u.lower(i) + sd.axis_u.upper(i));
      sd.v[k] = 0.5 * (sd.axis_v.lower(j) + sd.axis_v.upper(j));
      const SurfaceD1 d = derivatives_d1(surface_, sd.u[k], sd.v[k]);
      const UnitNormal un = unit_normal(surface_, sd.u[k], sd.v[k]);
      CellBox& box = sd.box[k];
      // Any orthonormal frame gives a valid bound; the tangent frame gives a thin box.
      if (un.status != UnitNormal::Status::Degenerate && d.Su.norm() > 0.0) {
        box.n = un.n;
        box.t1 = (d.Su - d.Su.dot(un.n) * un.n).normalized();
        box.t2 = box.n.cross(box.t1);
      } else {
        box.t1 = Vector3::UnitX();
        box.t2 = Vector3::UnitY();
        box.n = Vector3::UnitZ();
      }
      const BezierPatch patch = cell_patch(sd.bezier, sd.axis_u, sd.axis_v, i, j);
      box.enclose(d.S, patch.net);
      double r = 0.0;
      for (const HomogeneousPoint& P : patch.net) r = std::max(r, (P.head<3>() / P.w() - d.S).norm());
      if (region_ != nullptr) sd.in_region[k] = region_->meets(patch.box) ? 1 : 0;
      sd.cloud.points[k] = d.S;
      sd.radius[k] = r + kCellBoundFloor;
    }
  });
  // Only cells that can be searched widen the seed query: a small face trimmed from a large surface keeps a
  // small reach.
  for (std::size_t k = 0; k < n; ++k) {
    if (sd.in_region[k]) sd.max_radius = std::max(sd.max_radius, sd.radius[k]);
  }
  sd.tree = std::make_unique<PointTree>(3, sd.cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  sd.tree->buildIndex();
}

ClosestPointSolver::~ClosestPointSolver() = default;
ClosestPointSolver::ClosestPointSolver(ClosestPointSolver&&) noexcept = default;
ClosestPointSolver& ClosestPointSolver::operator=(ClosestPointSolver&&) noexcept = default;

std::size_t ClosestPointSolver::seed_count() const { return seeds_->cloud.points.size(); }

std::vector<Point3> ClosestPointSolver::seed_points_in_region() const {
  const Seeds& sd = *seeds_;
  std::vector<Point3> out;
  for (std::size_t k = 0; k < sd.cloud.points.size(); ++k) {
    if (region_ == nullptr || (sd.in_region[k] && region_->contains(sd.u[k], sd.v[k]))) out.push_back(sd.cloud.points[k]);
  }
  return out;
}

namespace {

// How often a cell may be split in four when Newton inside it stops on one of its inner edges while its
// bound still allows a closer point: such a cell may hold a second minimum (e.g. beside a C0 crease).
constexpr int kMaxSubdivisionDepth = 3;
static_assert(kMaxSubdivisionDepth > 0, "a seed cell whose Newton stops on an inner edge is always split once");

struct CellSearch {
  const Surface& surface;
  const Point3& query;
  const CellBox& frame;  // the seed cell's frame, reused for its sub-cells' boxes
  const Point3& origin;
  const ParameterRegion* region;
  int max_iterations;
  ClosestPointResult& best;
  int iterations = 0;
  int starts = 0;

  // Newton inside `box`; the point it finds, followed beyond the box's edge if it stops there and is the best
  // so far. Returns whether it stopped on an inner edge (so the box may hold another, closer minimum).
  bool run(const Domain& box) {
    const Domain whole = surface.domain();
    ClosestPointResult r = refine_closest_point_in(surface, query, 0.5 * (box.u0 + box.u1), 0.5 * (box.v0 + box.v1),
                                                   box, max_iterations);
    ++starts;
    iterations += r.iterations;
    const bool on_inner_edge = r.status == ClosestPointStatus::OnBoundary &&
                               ((r.u == box.u0 && r.u != whole.u0) || (r.u == box.u1 && r.u != whole.u1) ||
                                (r.v == box.v0 && r.v != whole.v0) || (r.v == box.v1 && r.v != whole.v1));
    if (r.status == ClosestPointStatus::OnBoundary && !on_inner_edge) {
      const bool on_domain_edge = r.u == whole.u0 || r.u == whole.u1 || r.v == whole.v0 || r.v == whole.v1;
      r.status = on_domain_edge ? ClosestPointStatus::OnBoundary : ClosestPointStatus::Converged;
    }
    // Outside the region (a trimmed face) the point does not count, and the cell is not split for it: the
    // region's own boundary, searched by the caller, holds the minimum of the cell's part inside the region
    // unless that part has an interior minimum of its own which Newton did not reach (accepted, rare).
    if (region != nullptr && !region->contains(r.u, r.v)) return false;
    if (on_inner_edge && closer(r, best)) {
      // The minimum lies beyond the edge: follow it (f only decreases on the way).
      ClosestPointResult polished = refine_closest_point(surface, query, r.u, r.v, max_iterations);
      iterations += polished.iterations;
      const bool polished_ok = polished.status == ClosestPointStatus::Converged ||
                               polished.status == ClosestPointStatus::OnBoundary;
      if (polished_ok && (region == nullptr || region->contains(polished.u, polished.v))) {
        r = polished;
      } else if (!polished_ok) {
        // Newton cannot settle across the edge: the surface is only C0 there (a crease along a knot line, e.g.
        // a knot of full multiplicity) and the box's minimum on it is the minimum of both sides. The
        // neighbouring cell is searched in its own right, so a closer point beyond would still be found.
        r.status = ClosestPointStatus::Converged;
      }
    }
    if (closer(r, best)) best = r;
    return on_inner_edge;
  }

  // Branch and bound: a box whose Newton stopped on an inner edge may hold another minimum; split it while
  // the boxes of its parts are nearer than the best point.
  void search(const BezierPatch& patch, int depth) {
    if (run(patch.box) && depth < kMaxSubdivisionDepth) search_parts(patch, depth);
  }

  void search_parts(const BezierPatch& patch, int depth) {
    for (const BezierPatch& half : split(patch, 0)) {
      for (const BezierPatch& quarter : split(half, 1)) {
        if (region != nullptr && !region->meets(quarter.box)) continue;
        CellBox sub = frame;
        sub.enclose(origin, quarter.net);
        if (sub.lower_bound(query - origin) < best.distance) search(quarter, depth + 1);
      }
    }
  }
};

}  // namespace

void ClosestPointSolver::search_cell(const Point3& query, std::uint32_t k, ClosestPointResult& best, int& iterations,
                                     int& starts) const {
  const Seeds& sd = *seeds_;
  const int nv = sd.axis_v.count();
  const int cu = static_cast<int>(k) / nv;
  const int cv = static_cast<int>(k) % nv;
  // Newton inside the cell finds the cell's own minimum; unconstrained, it could run across a knot where the
  // surface is only C0 or C1 into a neighbour's basin and miss a closer point here.
  // The cell's Bézier net is gathered only when the cell has to be split, which is rare.
  CellSearch search{surface_, query, sd.box[k], sd.cloud.points[k], region_, options_.max_iterations, best};
  const Domain cell{sd.axis_u.lower(cu), sd.axis_u.upper(cu), sd.axis_v.lower(cv), sd.axis_v.upper(cv)};
  // Newton may have found a closer point beyond the cell's edge, which can put the whole cell out of reach.
  if (search.run(cell) && sd.box[k].lower_bound(query - sd.cloud.points[k]) < best.distance) {
    search.search_parts(cell_patch(sd.bezier, sd.axis_u, sd.axis_v, cu, cv), 0);
  }
  iterations += search.iterations;
  starts += search.starts;
}

ClosestPointResult ClosestPointSolver::closest_point(const Point3& query) const {
  return closest_point(query, ClosestPointResult{});
}

ClosestPointResult ClosestPointSolver::closest_point(const Point3& query, const ClosestPointResult& bound) const {
  const Seeds& sd = *seeds_;
  if (!query.allFinite()) {
    ClosestPointResult bad;
    bad.status = ClosestPointStatus::NumericalError;
    return bad;
  }
  const double q[3] = {query.x(), query.y(), query.z()};
  ClosestPointResult best = bound;
  int iterations = 0;
  int starts = 0;

  // Without a bound, Newton first runs in the nearest seed's cell so that the ball searched below is small.
  // With one (the best point on other faces, or a trimmed face's boundary), the ball is already known and
  // the nearest candidate comes first anyway.
  double seed_bound = std::numeric_limits<double>::infinity();
  std::uint32_t nearest = std::numeric_limits<std::uint32_t>::max();
  if (!std::isfinite(best.distance)) {
    double nearest_dist_sq = 0.0;  // squared (nanoflann)
    nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(1);
    knn.init(&nearest, &nearest_dist_sq);
    sd.tree->findNeighbors(knn, q, nanoflann::SearchParams());
    if (sd.in_region[nearest] && sd.box[nearest].lower_bound(query - sd.cloud.points[nearest]) < best.distance) {
      search_cell(query, nearest, best, iterations, starts);
    }
    // The nearest seed bounds the distance only when it lies on the searched surface (no region).
    if (region_ == nullptr) seed_bound = std::sqrt(nearest_dist_sq);
  }

  // Every cell that could hold a closer point has its seed within best.distance + its radius: search that
  // ball, then visit each cell once unless its bounding box is already farther than the best point.
  const double reach = std::min(best.distance, seed_bound) + sd.max_radius;
  thread_local std::vector<std::pair<std::uint32_t, double>> candidates;  // (seed, squared distance)
  nanoflann::RadiusResultSet<double, std::uint32_t> within(reach * reach, candidates);
  sd.tree->findNeighbors(within, q, nanoflann::SearchParams());
  std::sort(candidates.begin(), candidates.end(),
            [](const auto& a, const auto& b) { return a.second < b.second || (a.second == b.second && a.first < b.first); });

  for (const auto& [k, dist_sq] : candidates) {
    if (k == nearest || !sd.in_region[k]) continue;
    if (std::sqrt(dist_sq) - sd.radius[k] >= best.distance) continue;
    if (sd.box[k].lower_bound(query - sd.cloud.points[k]) >= best.distance) continue;
    search_cell(query, k, best, iterations, starts);
  }
  best.iterations = iterations;
  best.starts = starts;
  return best;
}

std::vector<ClosestPointResult> ClosestPointSolver::closest_points(std::span<const Point3> queries) const {
  std::vector<ClosestPointResult> out(queries.size());
  // Each query is independent and written to its own slot, so the result does not depend on the partition.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, queries.size(), 256), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) out[i] = closest_point(queries[i]);
  });
  return out;
}

}  // namespace probecomp::nurbs
