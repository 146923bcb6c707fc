#pragma once
// A rational B-spline (NURBS) surface of degrees (p, q) on knot vectors U and V (The NURBS Book, eq. 4.9):
//   S(u,v) = Σ_i Σ_j N_{i,p}(u) N_{j,q}(v) w_ij P_ij / Σ_i Σ_j N_{i,p}(u) N_{j,q}(v) w_ij.
// Control points are stored homogeneous, Pw_ij = (w_ij P_ij, w_ij), row i (u) major. Weights are positive.

#include <atomic>
#include <span>
#include <vector>

#include "probecomp/nurbs/knot_vector.hpp"
#include "probecomp/geometry/types.hpp"

namespace probecomp::nurbs {

struct Domain {
  double u0, u1, v0, v1;
};

class Surface {
 public:
  // P[i*(m+1) + j] is P_ij, i = 0..n along u, j = 0..m along v. Empty w: non-rational (all weights 1).
  // Throws InvalidGeometry if the counts disagree with the knot vectors or a weight is not positive.
  Surface(KnotVector U, KnotVector V, const std::vector<Point3>& P, const std::vector<double>& w = {});
  Surface(KnotVector U, KnotVector V, std::vector<HomogeneousPoint> Pw);

  [[nodiscard]] int p() const { return U_.degree(); }
  [[nodiscard]] int q() const { return V_.degree(); }
  [[nodiscard]] const KnotVector& U() const { return U_; }
  [[nodiscard]] const KnotVector& V() const { return V_; }
  [[nodiscard]] int num_u() const { return U_.num_basis(); }  // n + 1
  [[nodiscard]] int num_v() const { return V_.num_basis(); }  // m + 1
  [[nodiscard]] const HomogeneousPoint& homogeneous(int i, int j) const { return Pw_[i * num_v() + j]; }
  [[nodiscard]] const std::vector<HomogeneousPoint>& homogeneous() const { return Pw_; }
  [[nodiscard]] Point3 control_point(int i, int j) const;
  [[nodiscard]] double weight(int i, int j) const { return homogeneous(i, j).w(); }
  // Not all weights equal (equal weights make a polynomial surface).
  [[nodiscard]] bool is_rational() const { return rational_; }
  [[nodiscard]] Domain domain() const { return {U_.front(), U_.back(), V_.front(), V_.back()}; }

 private:
  void validate();

  KnotVector U_;
  KnotVector V_;
  std::vector<HomogeneousPoint> Pw_;
  bool rational_ = false;  // set once by validate(): the net never changes after construction
};

struct SurfaceD1 {
  Point3 S;
  Vector3 Su, Sv;
};

struct SurfaceD2 {
  Point3 S;
  Vector3 Su, Sv, Suu, Suv, Svv;
};

// Knot span indices (KnotVector::find_span) of a parameter pair, known in advance by a caller that works inside
// one span (the closest-point search in a cell): the evaluators then skip the span search. The parameters must lie
// in the closed spans; at a span's end the one-sided derivatives of that span are returned. -1: search.
struct KnotSpans {
  int u = -1, v = -1;
};

namespace detail {
// Whether bicubic derivatives may take the 256-bit (AVX) form where the processor has it: true unless a test turns
// it off to compare the two forms (they agree bit for bit).
extern std::atomic<bool> avx_evaluation;
}  // namespace detail

// Parameters outside the domain are clamped to it.
[[nodiscard]] Point3 evaluate(const Surface& s, double u, double v, KnotSpans spans = {});
[[nodiscard]] SurfaceD1 derivatives_d1(const Surface& s, double u, double v);
// A3.6 on the homogeneous net, then A4.4 for the rational derivatives (including the mixed S_uv).
[[nodiscard]] SurfaceD2 derivatives_d2(const Surface& s, double u, double v, KnotSpans spans = {});

// derivatives_d2 on a grid, row by row, to the same formulas: for a fixed u, at every v of `tv`. The tensor
// product is summed in A3.6's two stages, so the u basis and the partial sums over i are made once per row, not
// once per point: several times faster on a dense grid. `order` 0 or 1 leaves the higher derivatives zero.
class GridRows {
 public:
  GridRows(const Surface& s, std::vector<double> tv, int order = 2);
  // out[b] = the derivatives at (u, tv[b]); out must hold tv.size() entries. Thread-safe (const).
  void row(double u, std::span<SurfaceD2> out) const;
  [[nodiscard]] std::size_t size() const { return tv_.size(); }

 private:
  const Surface& s_;
  std::vector<double> tv_;
  int order_;
  std::vector<int> span_v_;
  std::vector<double> Nv_;  // per column b: 3 × (q + 1) basis derivatives
};

struct UnitNormal {
  enum class Status {
    OK,                 // n = S_u × S_v / |S_u × S_v|
    FromNeighbourhood,  // S_u × S_v vanishes here (a pole or collapsed edge): n is its limit from inside
    Degenerate,         // no normal could be found; n is zero
  };
  Status status;
  Vector3 n;
};
// The unit normal in the direction of S_u × S_v (which may point into or out of the material).
[[nodiscard]] UnitNormal unit_normal(const Surface& s, double u, double v);
// The same from S_u and S_v the caller has already evaluated at (u, v): no evaluation unless (u, v) is at a pole.
[[nodiscard]] UnitNormal unit_normal(const Surface& s, double u, double v, const Vector3& Su, const Vector3& Sv);

// Axis-aligned box of the control points: it contains the surface (convex-hull property, weights > 0).
[[nodiscard]] BoundingBox bounding_box(const Surface& s);

// A5.3: insert a knot r times in u or in v; shape and parametrisation are unchanged.
[[nodiscard]] Surface insert_knot_u(const Surface& s, double u, int r = 1);
[[nodiscard]] Surface insert_knot_v(const Surface& s, double v, int r = 1);

// A5.4 applied to every column (u) or row (v): inserts all knots of X (sorted) at once; shape unchanged.
[[nodiscard]] Surface refine_knots_u(const Surface& s, const std::vector<double>& X);
[[nodiscard]] Surface refine_knots_v(const Surface& s, const std::vector<double>& X);

// The surface moved by the affine map x ↦ T·x (exact: NURBS are affinely invariant; weights are kept).
[[nodiscard]] Surface transformed(const Surface& s, const Eigen::Isometry3d& T);

// The same surface with u and v exchanged: T(v,u) = S(u,v), so its normal S_v × S_u is reversed.
[[nodiscard]] Surface transposed(const Surface& s);

}  // namespace probecomp::nurbs
