#pragma once
// Closest point on a NURBS surface (point inversion, The NURBS Book §6.1, with a global start search).
//
// refine_closest_point: projected Newton on f(u,v) = ½|S(u,v) − P|² from one start, with the full Hessian
// (second derivatives of S included), an active set for the domain edges and corners, and backtracking.
// ClosestPointSolver: global search over cells. Each knot span is cut into sub-cells, about 2·(degree + 1) per
// span and direction in all, shared out by the spans' lengths on the part so that cells are of similar size.
// Each cell carries three rigorous bounds from its Bézier control points (convex hull property): an oriented
// box (a lower bound on the distance), an axis-aligned box (for a bounding-volume hierarchy over the cells) and
// a normal cone (normal_cone.hpp), which excludes a cell that cannot hold a critical point of the distance. The
// bounds are kept in floats rounded outwards (a cache line a cell: the search's time goes to cache misses as much
// as to arithmetic), and so are the surface's derivatives at each cell's centre, which Newton's first step uses.
// One depth-first pass over the hierarchy gathers the cells whose boxes are nearer than the nearest seed; Newton
// runs inside the nearest seed's cell, then inside every other gathered cell that could still hold a closer
// point; a Newton that stops on a cell's inner edge is followed beyond it. Where the distance is flat at the best
// point (the query near a centre of curvature) or Newton did not settle, those cells are searched again from 16
// starts each. The batch query runs in parallel and gives the same result whatever the thread count.
// Known limit: two minima inside one part of a cell can be missed (Newton finds one); see seeds_per_span.

#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include "probecomp/nurbs/surface.hpp"

namespace probecomp::nurbs {

// One byte: it is kept for every measured point (registration::PointMatch).
enum class ClosestPointStatus : std::uint8_t {
  Converged,       // interior foot point: S − P is orthogonal to S_u and S_v (or P lies on the surface)
  OnBoundary,      // the closest point is on an edge or corner of the domain (constrained minimum)
  NotConverged,    // iteration limit reached without meeting the conditions: the point is not trusted
  NumericalError,  // a non-finite value appeared (degenerate geometry or input)
};

[[nodiscard]] const char* to_string(ClosestPointStatus s);

struct ClosestPointResult {
  ClosestPointStatus status = ClosestPointStatus::NotConverged;
  double u = 0.0;
  double v = 0.0;
  Point3 point = Point3::Zero();
  double distance = std::numeric_limits<double>::infinity();  // |point − query|, mm
  int iterations = 0;                                          // Newton iterations over all starts
  int starts = 0;                                              // Newton starts (seed cells visited)
  // The tangents S_u, S_v at (u, v): where Newton last evaluated them, or carried there to first order over its
  // last step (under 1e-6 mm, taken without an evaluation; the normal from them is then off by the square of that
  // times the curvature's). Zero where unknown (a point found on a trim boundary): a caller that needs the normal
  // evaluates it.
  Vector3 Su = Vector3::Zero(), Sv = Vector3::Zero();
  // The second derivatives where Newton last evaluated them: at (u, v), or its last step (under 1e-6 mm) before it.
  // With the tangents they give the surface's osculating paraboloid there without another evaluation
  // (osculating_patch.hpp). NaN where unknown (a closed form's answer, a point on a trim boundary).
  Vector3 Suu = Vector3::Constant(std::numeric_limits<double>::quiet_NaN());
  Vector3 Suv = Suu, Svv = Suu;
  // How flat the distance is there (1 on a plane, falling towards 0 near a centre of curvature, where a second
  // minimum may lie close by), from Newton's last Hessian; NaN where not known (a global search's answer).
  double flatness = std::numeric_limits<double>::quiet_NaN();

  [[nodiscard]] bool ok() const {
    return status == ClosestPointStatus::Converged || status == ClosestPointStatus::OnBoundary;
  }
};

// Newton stops when its step moves the foot point by less than this (mm): after such a step the quadratic
// convergence leaves an error far below it, and 1e-8 mm is well under any CMM's resolution.
inline constexpr double kClosestPointStepTolerance = 1e-8;
// Cosine of the angle between S − P and a tangent below which the point counts as orthogonal.
inline constexpr double kClosestPointZeroCosine = 1e-12;

struct ClosestPointOptions {
  // Sub-cells per knot span and direction, the same in every span; 0 means 2·(degree + 1) per span on average,
  // shared out by the spans' lengths. BM_ClosestPointAgainstDenseCells (260 000 queries on wild random surfaces up
  // to 10 mm off, panels, the spiral sheet, against 32 per span): 5 find a farther minimum, by 0.8 µm at most.
  int seeds_per_span = 0;
  // With the default density, a face of many knot spans (a refined fit, a deformed simulation surface: 100 × 80
  // spans) would get half a million cells, costing a second and hundreds of MB to index. Above this many cells
  // the default density is lowered (to 2 per span at least): such spans are small and nearly flat, so fewer,
  // still thin, cells bound them as tightly.
  int max_cells = 1 << 16;
  // The knot spans per direction the surface's shape needs, where the surface has more: an offset surface fitted
  // with knots added only so that it follows the offset has the shape of its nominal surface. The default density
  // is then 2·(degree + 1) cells per shape span, shared out over the surface's spans by their lengths (at least 2
  // each): cells as large on the part as the shape's own spans would get. 0: the surface's own spans.
  int shape_spans_u = 0;
  int shape_spans_v = 0;
  int max_iterations = 40;  // per Newton start
};

// Local point inversion from (u0, v0) over the whole domain.
[[nodiscard]] ClosestPointResult refine_closest_point(const Surface& s, const Point3& query, double u0, double v0,
                                                      int max_iterations = 40);
// The same, restricted to the parameter box `box` (inside the domain): OnBoundary then means the box's edge.
[[nodiscard]] ClosestPointResult refine_closest_point_in(const Surface& s, const Point3& query, double u0, double v0,
                                                         const Domain& box, int max_iterations = 40);

// A part of the parameter domain that results must lie in: a trimmed face's region. `meets` may answer true
// for a box that misses the region (it only prunes), never false for one that meets it.
class ParameterRegion {
 public:
  virtual ~ParameterRegion() = default;
  [[nodiscard]] virtual bool contains(double u, double v) const = 0;
  [[nodiscard]] virtual bool meets(const Domain& box) const = 0;
};

class ClosestPointSolver {
 public:
  // With a region, the solver looks only for minima inside it; the caller adds the region's boundary (see
  // closest_point's `bound`). The region must outlive the solver.
  explicit ClosestPointSolver(Surface surface, ClosestPointOptions options = {}, const ParameterRegion* region = nullptr);
  ~ClosestPointSolver();
  ClosestPointSolver(ClosestPointSolver&&) noexcept;
  ClosestPointSolver& operator=(ClosestPointSolver&&) noexcept;

  [[nodiscard]] const Surface& surface() const { return surface_; }
  [[nodiscard]] std::size_t seed_count() const;
  // The seeds (cell centres, points of the surface) that lie inside the region: each is an upper bound on a
  // query's distance to the region.
  [[nodiscard]] std::vector<Point3> seed_points_in_region() const;

  [[nodiscard]] ClosestPointResult closest_point(const Point3& query) const;
  // The closer of `bound` (a point already known, e.g. the nearest point of a trimmed face's boundary) and
  // the surface's minima inside the region; cells farther than the bound are not searched.
  // `known`, when given, is a minimum of this surface inside the region that Newton found from a start of the
  // caller's (a hint): the cell holding it is not searched again, unless the distance is flat there (where a cell
  // may hold two minima). A search from that cell's centre would find one minimum in it too, so the answer is
  // the one without `known`, to the solver's one-minimum-per-cell limit, at one Newton less per query.
  [[nodiscard]] ClosestPointResult closest_point(const Point3& query, const ClosestPointResult& bound,
                                                 const ClosestPointResult* known = nullptr) const;
  // One result per query, in order; parallel (oneTBB), deterministic.
  [[nodiscard]] std::vector<ClosestPointResult> closest_points(std::span<const Point3> queries) const;

 private:
  struct Seeds;
  struct Search;  // one query's best point so far, how flat the distance is there, and the work done
  // Searches seed cell k, cut into parts × parts boxes: Newton kept inside each box, followed beyond it if it stops
  // on an inner edge and is the best so far.
  void search_cell(const Point3& query, std::uint32_t k, int parts, Search& search) const;
  // Newton from the centre of `box`, a part of one cell whose knot spans are `spans`, kept inside it; `start`, if
  // given, is the surface there with its derivatives in floats.
  void search_box(const Point3& query, const Domain& box, KnotSpans spans, const SurfaceD2* start,
                  Search& search) const;
  // The cell whose parameter box holds (u, v), or −1 when rounding leaves that in doubt.
  [[nodiscard]] long cell_holding(double u, double v) const;

  Surface surface_;
  ClosestPointOptions options_;
  const ParameterRegion* region_ = nullptr;
  std::unique_ptr<Seeds> seeds_;
};

}  // namespace probecomp::nurbs
