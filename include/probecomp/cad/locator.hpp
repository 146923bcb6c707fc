#pragma once
// Closest point on a CAD model ("find nominals"): over all faces, inside their trims. A bounding-volume
// hierarchy over the faces' control-net boxes (rigorous: a NURBS lies in its control points' convex hull)
// means a query visits only the faces that could hold a closer point; the nearest of all faces' sample
// points (a k-d tree) gives the first face to search and a tight bound before the hierarchy is walked.

#include <cmath>
#include <memory>
#include <span>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/nurbs/closest_point.hpp"
#include "probecomp/nurbs/osculating_patch.hpp"

namespace probecomp::cad {

// The small members first, sharing a word: 80 bytes (ICP keeps one for every measured point).
struct ModelPoint {
  nurbs::ClosestPointStatus status = nurbs::ClosestPointStatus::NotConverged;
  bool on_trim_edge = false;         // the point lies on the face's trimming boundary
  int face = -1;
  double u = 0.0, v = 0.0;
  Point3 point = Point3::Zero();
  Vector3 normal = Vector3::Zero();  // outward unit normal of the face at the point (zero where it has none)
  double distance = 0.0;             // signed: + on the outward side of the face, mm

  [[nodiscard]] bool ok() const {
    return status == nurbs::ClosestPointStatus::Converged || status == nurbs::ClosestPointStatus::OnBoundary;
  }
  // On the face's edge: its trim, or its surface's domain boundary.
  [[nodiscard]] bool on_edge() const { return on_trim_edge || status == nurbs::ClosestPointStatus::OnBoundary; }
};
static_assert(sizeof(ModelPoint) == 80);

// Closest point on one trimmed face: the nearer of the nearest boundary point (exact, on the pcurves) and the
// surface's minima inside the trim.
class TrimmedFaceLocator {
 public:
  // The face must outlive the locator (a temporary cannot be given).
  explicit TrimmedFaceLocator(const Face& face);
  explicit TrimmedFaceLocator(const Face&& face) = delete;
  // Only points nearer than `limit` are looked for (the best found so far on other faces); when there is
  // none, the result has status NoneNearer.
  // `known`: a minimum of the face's surface inside its trim found from a hint (see ClosestPointSolver).
  [[nodiscard]] nurbs::ClosestPointResult closest_point(const Point3& query, double limit, bool& on_trim_edge,
                                                        const nurbs::ClosestPointResult* known = nullptr) const;
  [[nodiscard]] nurbs::ClosestPointResult closest_point_on_boundary(const Point3& query, double limit) const;
  // Points of the face (inside its trim): seeds and boundary samples, for a model-wide first guess.
  [[nodiscard]] std::vector<Point3> sample_points() const;
  // Marks a result for "nothing on this face nearer than the limit".
  [[nodiscard]] static bool none_nearer(const nurbs::ClosestPointResult& r) { return std::isnan(r.u); }

 private:
  struct Boundary;
  const Face* face_;
  nurbs::ClosestPointSolver solver_;
  std::shared_ptr<const Boundary> boundary_;
};

class ModelLocator {
 public:
  // The model must outlive the locator. Building it indexes every face (in parallel).
  explicit ModelLocator(const Model& model);
  // A locator on a temporary model would dangle: it does not compile.
  explicit ModelLocator(const Model&& model) = delete;
  ~ModelLocator();

  [[nodiscard]] const Model& model() const { return *model_; }
  [[nodiscard]] ModelPoint closest_point(const Point3& query) const;
  // One result per query, in order; parallel and deterministic (faces are visited in an order fixed by the
  // query alone, and of two faces at the same distance the one visited first is kept).
  [[nodiscard]] std::vector<ModelPoint> closest_points(std::span<const Point3> queries) const;
  // Searches that start from a hint: this point's foot before a small motion, as in an ICP iteration. Newton
  // from the hint's (u, v) on its face gives a tight bound first.
  //   Exact  then the global search visits only the cells and faces that could hold a nearer point: the same
  //          answer as without a hint, found faster;
  //   Local  the hint's face is not searched again (another minimum on it, or its trim boundary, would be
  //          missed), the other faces are: for the iterations of ICP that a final exact pass confirms.
  // A hint that is not ok, or whose Newton leaves the face's trim, gives an unhinted search.
  enum class HintedSearch { Exact, Local };
  [[nodiscard]] ModelPoint closest_point(const Point3& query, const ModelPoint& hint,
                                         HintedSearch search = HintedSearch::Exact) const;
  [[nodiscard]] std::vector<ModelPoint> closest_points(std::span<const Point3> queries, std::span<const ModelPoint> hints,
                                                       HintedSearch search = HintedSearch::Exact) const;
  // The same in place: each foot, the hint on entry, is replaced by the query's closest point (no second array of
  // a million feet, 96 MB, beside the first). `patches`, when given, receive each foot's osculating paraboloid where
  // Newton from the hint found it (from Newton's own derivatives: no evaluation), else an invalid patch.
  void update_closest_points(std::span<const Point3> queries, std::span<ModelPoint> feet,
                             HintedSearch search = HintedSearch::Exact,
                             std::span<nurbs::OsculatingPatch> patches = {}) const;
  // The closest point on any face but `excluded` that is nearer than `limit` (mm); face −1 when there is none. A
  // tip touching a second face (a concave corner) has one there within the noise of its first.
  [[nodiscard]] ModelPoint closest_point_on_other_faces(const Point3& query, int excluded, double limit) const;
  // The outward unit normal of face `face` at (u, v).
  [[nodiscard]] Vector3 outward_normal(int face, double u, double v) const;

 private:
  struct Node {
    BoundingBox box;
    int left = -1, right = -1;  // children, or -1 for a leaf
    int first = 0, count = 0;   // the leaf's faces: order_[first .. first + count)
  };
  int build(int first, int count);
  // Depth-first over the BVH, nearer child first, each face (but `searched`, already asked) asked only for
  // points nearer than `best`.
  void search(const Point3& query, ModelPoint& best, int searched) const;
  void visit_face(const Point3& query, int f, ModelPoint& best, const nurbs::ClosestPointResult* known = nullptr) const;
  [[nodiscard]] ModelPoint closest_point(const Point3& query, const ModelPoint& hint, HintedSearch search,
                                         nurbs::OsculatingPatch* patch) const;
  [[nodiscard]] ModelPoint make_point(const Point3& query, int f, const nurbs::ClosestPointResult& r, bool on_edge) const;
  struct Samples;

  const Model* model_;
  std::vector<std::unique_ptr<TrimmedFaceLocator>> faces_;
  std::vector<BoundingBox> boxes_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
  std::unique_ptr<Samples> samples_;  // every face's sample points in one k-d tree
};

}  // namespace probecomp::cad
