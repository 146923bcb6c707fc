#include "probecomp/cad/locator.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "probecomp/geometry/point_tree.hpp"
#include "probecomp/geometry/parallel.hpp"

namespace probecomp::cad {

using nurbs::ClosestPointResult;
using nurbs::ClosestPointStatus;

namespace {

// Newton on a boundary curve stops when its step moves the point by less than this (mm), as on surfaces.
constexpr double kEdgeStepTolerance = nurbs::kClosestPointStepTolerance;
constexpr int kEdgeMaxIterations = 40;
constexpr int kMaxHalvings = 30;

struct CurvePoint {
  double t, u, v, f;  // f = |S(C(t)) − Q|²
  Point3 S;
};

// "Nothing on this face nearer than `limit`": a result that is not a point (u is NaN, TrimmedFaceLocator::none_nearer)
// at that distance, which the surface search also takes as its bound (cells farther are skipped).
ClosestPointResult none_nearer_than(double limit) {
  ClosestPointResult none;
  none.u = none.v = std::numeric_limits<double>::quiet_NaN();
  none.distance = limit;
  return none;
}

CurvePoint at(const nurbs::Surface& s, const nurbs::Curve& c, const Point3& q, double t) {
  const Point3 uv = nurbs::evaluate(c, t);
  const Point3 S = nurbs::evaluate(s, uv.x(), uv.y());
  return {t, uv.x(), uv.y(), (S - q).squaredNorm(), S};
}

// Minimises |S(C(t)) − Q|² over [ta, tb] from t0: Newton on the composite curve with its exact second
// derivative (chain rule through the surface's and the pcurve's derivatives), Gauss–Newton where that is not
// positive, clamped to the interval, backtracking so that the distance never grows.
CurvePoint refine_on_curve(const nurbs::Surface& s, const nurbs::Curve& c, const Point3& q, double t0, double ta,
                           double tb) {
  CurvePoint cur = at(s, c, q, t0);
  for (int it = 0; it < kEdgeMaxIterations; ++it) {
    const nurbs::CurveD2 cd = nurbs::derivatives_d2(c, cur.t);
    const nurbs::SurfaceD2 sd = nurbs::derivatives_d2(s, cur.u, cur.v);
    const double du = cd.Cu.x(), dv = cd.Cu.y();
    const Vector3 T = sd.Su * du + sd.Sv * dv;
    const Vector3 A =
        sd.Suu * du * du + 2.0 * sd.Suv * du * dv + sd.Svv * dv * dv + sd.Su * cd.Cuu.x() + sd.Sv * cd.Cuu.y();
    const Vector3 r = sd.S - q;
    const double g1 = r.dot(T);
    double g2 = T.dot(T) + r.dot(A);
    if (!(g2 > 0.0)) g2 = T.dot(T);
    if (!(g2 > 0.0)) break;
    double step = -g1 / g2;
    CurvePoint next = cur;
    bool decreased = false;
    for (int h = 0; h <= kMaxHalvings; ++h) {
      next = at(s, c, q, std::clamp(cur.t + step, ta, tb));
      if (next.f <= cur.f) {
        decreased = true;
        break;
      }
      step *= 0.5;
    }
    if (!decreased) break;
    const double moved = (next.S - cur.S).norm();
    cur = next;
    if (moved < kEdgeStepTolerance) break;
  }
  return cur;
}

double box_distance(const BoundingBox& b, const Point3& q) { return std::sqrt(b.squared_distance(q)); }

}  // namespace

struct TrimmedFaceLocator::Boundary {
  geometry::PointCloud cloud;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> where;  // (curve, sample index) of each sample
  std::vector<double> gap;   // longest chord from each sample to a neighbouring sample, mm
  std::vector<std::vector<double>> t;  // sample parameters of each boundary curve
  double max_gap = 0.0;      // longest chord of all
  std::unique_ptr<geometry::PointTree> tree;
};

TrimmedFaceLocator::TrimmedFaceLocator(const Face& face)
    : face_(&face),
      solver_(face.surface, {.shape_spans_u = face.shape_spans_u, .shape_spans_v = face.shape_spans_v},
              face.trim.get()) {
  if (!face.trimmed()) return;
  auto b = std::make_shared<Boundary>();
  const auto& curves = face.trim->curves();
  // Chords no longer than 1/100 of the face's size keep the candidate search around a query small (a long
  // straight edge would otherwise be a single chord and widen every query's reach).
  const double max_chord = nurbs::bounding_box(face.surface).diagonal() / 100.0;
  b->t.resize(curves.size());
  for (std::uint32_t c = 0; c < curves.size(); ++c) {
    const std::vector<double>& trim_t = curves[c].t;
    std::vector<double>& t = b->t[c];
    auto point_at = [&](double tk) {
      const Point3 uv = nurbs::evaluate(curves[c].uv, tk);
      return nurbs::evaluate(face.surface, uv.x(), uv.y());
    };
    auto add_sample = [&](double tk, const Point3& S) {
      t.push_back(tk);
      b->cloud.points.push_back(S);
      b->where.emplace_back(c, static_cast<std::uint32_t>(t.size() - 1));
      b->gap.push_back(0.0);
      if (t.size() > 1) {
        const std::size_t i = b->cloud.points.size() - 1;
        const double chord = (b->cloud.points[i] - b->cloud.points[i - 1]).norm();
        b->gap[i] = std::max(b->gap[i], chord);
        b->gap[i - 1] = std::max(b->gap[i - 1], chord);
        b->max_gap = std::max(b->max_gap, chord);
      }
    };
    Point3 previous = Point3::Zero();
    for (std::size_t k = 0; k < trim_t.size(); ++k) {
      const Point3 S = point_at(trim_t[k]);
      if (k > 0) {
        const int pieces = std::clamp(static_cast<int>(std::ceil((S - previous).norm() / max_chord)), 1, 1000);
        for (int m = 1; m < pieces; ++m) {
          const double tm = trim_t[k - 1] + (trim_t[k] - trim_t[k - 1]) * m / pieces;
          add_sample(tm, point_at(tm));
        }
      }
      add_sample(trim_t[k], S);
      previous = S;
    }
  }
  b->tree = std::make_unique<geometry::PointTree>(3, b->cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  b->tree->buildIndex();
  boundary_ = std::move(b);
}

std::vector<Point3> TrimmedFaceLocator::sample_points() const {
  std::vector<Point3> out = solver_.seed_points_in_region();
  if (boundary_) out.insert(out.end(), boundary_->cloud.points.begin(), boundary_->cloud.points.end());
  return out;
}

ClosestPointResult TrimmedFaceLocator::closest_point_on_boundary(const Point3& query, double limit) const {
  ClosestPointResult best;
  if (!boundary_ || boundary_->cloud.points.empty()) return best;
  const Boundary& b = *boundary_;
  const double q[3] = {query.x(), query.y(), query.z()};
  // The nearest boundary point lies within one chord (along the curve) of some sample, which is then within
  // its distance plus that arc; 1.5 chords covers the arc's excess over the chord on curved boundaries. Given
  // a limit, only samples within it plus that margin matter; without one, the nearest sample fixes the reach.
  double reach = limit + 1.5 * b.max_gap;
  if (!std::isfinite(limit)) {
    std::uint32_t nearest = 0;
    double nearest_sq = 0.0;  // squared (nanoflann)
    nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(1);
    knn.init(&nearest, &nearest_sq);
    b.tree->findNeighbors(knn, q, nanoflann::SearchParams());
    reach = std::sqrt(nearest_sq) + 1.5 * b.max_gap;
  }
  thread_local std::vector<std::pair<std::uint32_t, double>> found;  // (sample, squared distance)
  nanoflann::RadiusResultSet<double, std::uint32_t> within(reach * reach, found);
  b.tree->findNeighbors(within, q, nanoflann::SearchParams());
  if (found.empty()) return best;
  // Nearest first, so that the best point found tightens the filter below early; ties by sample for determinism.
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) {
    return a.second < b.second || (a.second == b.second && a.first < b.first);
  });

  const auto& curves = face_->trim->curves();
  CurvePoint best_point{0, 0, 0, std::numeric_limits<double>::infinity(), Point3::Zero()};
  for (const auto& [id, dist_sq] : found) {
    const auto [c, k] = b.where[id];
    // The arcs next to this sample are within its distance less its longest chord (1.5: arc over chord).
    if (std::sqrt(dist_sq) - 1.5 * b.gap[id] > std::min(limit, std::sqrt(best_point.f))) continue;
    const std::vector<double>& t = b.t[c];
    const double ta = t[k == 0 ? 0 : k - 1];
    const double tb = t[std::min<std::size_t>(k + 1, t.size() - 1)];
    const CurvePoint p = refine_on_curve(face_->surface, curves[c].uv, query, t[k], ta, tb);
    if (p.f < best_point.f) best_point = p;
  }
  best.status = ClosestPointStatus::OnBoundary;
  best.u = best_point.u;
  best.v = best_point.v;
  best.point = best_point.S;
  best.distance = std::sqrt(best_point.f);
  return best;
}

ClosestPointResult TrimmedFaceLocator::closest_point(const Point3& query, double limit, bool& on_trim_edge,
                                                     const ClosestPointResult* known) const {
  on_trim_edge = false;
  if (face_->analytic) {
    // The closed form gives the one minimum over the whole domain (the elementary surfaces have no other local
    // minimum of the distance: the other critical points are maxima or saddles). Inside the trim it is the
    // face's closest point; outside, the face's closest point lies on the trim's boundary.
    const ClosestPointResult r = face_->analytic->closest_point(query);
    if (!(r.distance < limit)) return none_nearer_than(limit);
    if (!face_->trimmed() || face_->trim->contains(r.u, r.v)) return r;
    const ClosestPointResult edge = closest_point_on_boundary(query, limit);
    if (!(edge.distance < limit)) return none_nearer_than(limit);
    on_trim_edge = true;
    return edge;
  }
  ClosestPointResult bound = none_nearer_than(limit);
  if (face_->trimmed()) {
    const ClosestPointResult edge = closest_point_on_boundary(query, limit);
    if (edge.distance < limit) bound = edge;
  }
  ClosestPointResult r = solver_.closest_point(query, bound, known);
  on_trim_edge = face_->trimmed() && !none_nearer(r) && r.u == bound.u && r.v == bound.v && r.distance == bound.distance;
  return r;
}

struct ModelLocator::Samples {
  geometry::PointCloud cloud;
  std::vector<int> face;  // the face each sample lies on
  std::unique_ptr<geometry::PointTree> tree;
};

ModelLocator::ModelLocator(const Model& model) : model_(&model) {
  const std::size_t n = model.faces.size();
  faces_.resize(n);
  boxes_.resize(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t k) {
    faces_[k] = std::make_unique<TrimmedFaceLocator>(model.faces[k]);
    boxes_[k] = nurbs::bounding_box(model.faces[k].surface);
  });
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0);
  if (n > 0) build(0, static_cast<int>(n));
  samples_ = std::make_unique<Samples>();
  for (std::size_t k = 0; k < n; ++k) {
    for (const Point3& p : faces_[k]->sample_points()) {
      samples_->cloud.points.push_back(p);
      samples_->face.push_back(static_cast<int>(k));
    }
  }
  samples_->tree = std::make_unique<geometry::PointTree>(3, samples_->cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  samples_->tree->buildIndex();
}

ModelLocator::~ModelLocator() = default;

// Median split along the longest axis of the box centres, down to leaves of a few faces.
int ModelLocator::build(int first, int count) {
  constexpr int kLeafFaces = 2;
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back({});
  BoundingBox box;
  BoundingBox centres;
  for (int k = first; k < first + count; ++k) {
    const BoundingBox& b = boxes_[static_cast<std::size_t>(order_[static_cast<std::size_t>(k)])];
    box.extend(b.min);
    box.extend(b.max);
    centres.extend(0.5 * (b.min + b.max));
  }
  nodes_[static_cast<std::size_t>(id)].box = box;
  if (count <= kLeafFaces) {
    nodes_[static_cast<std::size_t>(id)].first = first;
    nodes_[static_cast<std::size_t>(id)].count = count;
    return id;
  }
  int axis = 0;
  (centres.max - centres.min).maxCoeff(&axis);
  const int half = count / 2;
  auto begin = order_.begin() + first;
  std::nth_element(begin, begin + half, begin + count, [&](int a, int b) {
    const double ca = boxes_[static_cast<std::size_t>(a)].min[axis] + boxes_[static_cast<std::size_t>(a)].max[axis];
    const double cb = boxes_[static_cast<std::size_t>(b)].min[axis] + boxes_[static_cast<std::size_t>(b)].max[axis];
    return ca < cb || (ca == cb && a < b);
  });
  const int left = build(first, half);
  const int right = build(first + half, count - half);
  nodes_[static_cast<std::size_t>(id)].left = left;
  nodes_[static_cast<std::size_t>(id)].right = right;
  return id;
}

Vector3 ModelLocator::outward_normal(int face, double u, double v) const {
  const Face& f = model_->faces[static_cast<std::size_t>(face)];
  const nurbs::UnitNormal n = nurbs::unit_normal(f.surface, u, v);
  return static_cast<double>(f.outward) * n.n;
}

void ModelLocator::visit_face(const Point3& query, int f, ModelPoint& best, const ClosestPointResult* known) const {
  if (box_distance(boxes_[static_cast<std::size_t>(f)], query) > std::abs(best.distance)) return;
  bool on_edge = false;
  const ClosestPointResult r =
      faces_[static_cast<std::size_t>(f)]->closest_point(query, std::abs(best.distance), on_edge, known);
  if (TrimmedFaceLocator::none_nearer(r)) return;
  if (!r.ok()) {
    if (best.face < 0) best.status = r.status;
    return;
  }
  best = make_point(query, f, r, on_edge);  // the face was asked only for points nearer than the best so far
}

ModelPoint ModelLocator::make_point(const Point3& query, int f, const ClosestPointResult& r, bool on_edge) const {
  ModelPoint m;
  m.status = r.status;
  m.face = f;
  m.u = r.u;
  m.v = r.v;
  m.point = r.point;
  if (r.Su.isZero() && r.Sv.isZero()) {
    m.normal = outward_normal(f, r.u, r.v);
  } else {
    // Newton's own tangents: one evaluation fewer for every point.
    const Face& face = model_->faces[static_cast<std::size_t>(f)];
    m.normal = static_cast<double>(face.outward) * nurbs::unit_normal(face.surface, r.u, r.v, r.Su, r.Sv).n;
  }
  m.on_trim_edge = on_edge;
  const double side = (query - r.point).dot(m.normal);
  m.distance = side < 0.0 ? -r.distance : r.distance;
  return m;
}

void ModelLocator::search(const Point3& query, ModelPoint& best, int searched) const {
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[static_cast<std::size_t>(stack[--top])];
    if (box_distance(node.box, query) > std::abs(best.distance)) continue;
    if (node.left < 0) {
      for (int k = node.first; k < node.first + node.count; ++k) {
        const int f = order_[static_cast<std::size_t>(k)];
        if (f != searched) visit_face(query, f, best);
      }
      continue;
    }
    const Node& l = nodes_[static_cast<std::size_t>(node.left)];
    const Node& r = nodes_[static_cast<std::size_t>(node.right)];
    const bool left_first = box_distance(l.box, query) <= box_distance(r.box, query);
    stack[top++] = left_first ? node.right : node.left;
    stack[top++] = left_first ? node.left : node.right;
  }
}

ModelPoint ModelLocator::closest_point(const Point3& query) const {
  ModelPoint best;
  best.distance = std::numeric_limits<double>::infinity();
  if (nodes_.empty()) return best;
  if (!query.allFinite()) {
    best.status = ClosestPointStatus::NumericalError;
    return best;
  }
  if (!samples_->cloud.points.empty()) {
    // The nearest sample lies on its face, inside the trim: that face holds a point at most this far, so it
    // is searched first, and every other face only for points nearer than what it gives. The margin keeps
    // the sample's own point (a cell centre, where Newton starts) from being lost to rounding.
    const double q[3] = {query.x(), query.y(), query.z()};
    std::uint32_t nearest = 0;
    double nearest_sq = 0.0;  // squared (nanoflann)
    nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(1);
    knn.init(&nearest, &nearest_sq);
    samples_->tree->findNeighbors(knn, q, nanoflann::SearchParams());
    const int first = samples_->face[nearest];
    best.distance = std::sqrt(nearest_sq) * (1.0 + 1e-12) + 1e-12;
    visit_face(query, first, best);
    search(query, best, first);
    if (best.face >= 0) return best;
    best = ModelPoint{};
    best.distance = std::numeric_limits<double>::infinity();
  }
  // No face found a point within the sample's distance (Newton left the trim, a rare case the face's own
  // search accepts): search without the bound.
  search(query, best, -1);
  return best;
}

ModelPoint ModelLocator::closest_point_on_other_faces(const Point3& query, int excluded, double limit) const {
  ModelPoint best;
  best.distance = limit;
  if (nodes_.empty() || !query.allFinite()) return best;
  search(query, best, excluded);
  return best;
}

ModelPoint ModelLocator::closest_point(const Point3& query, const ModelPoint& hint, HintedSearch mode) const {
  return closest_point(query, hint, mode, nullptr);
}

ModelPoint ModelLocator::closest_point(const Point3& query, const ModelPoint& hint, HintedSearch mode,
                                       nurbs::OsculatingPatch* patch) const {
  if (patch != nullptr) *patch = nurbs::OsculatingPatch::invalid();
  if (!hint.ok() || hint.face < 0 || hint.face >= static_cast<int>(faces_.size()) || !query.allFinite()) {
    return closest_point(query);
  }
  const Face& face = model_->faces[static_cast<std::size_t>(hint.face)];
  // An elementary face's closed form is its global minimum: inside the trim, nothing on the face is nearer.
  const ClosestPointResult local = face.analytic ? face.analytic->closest_point(query)
                                                 : nurbs::refine_closest_point(face.surface, query, hint.u, hint.v);
  if (!local.ok() || (face.trimmed() && !face.trim->contains(local.u, local.v))) return closest_point(query);
  // The local foot point bounds the answer. Its own face is searched again for anything strictly nearer
  // (another minimum, or its trim boundary), then every other face the hierarchy cannot rule out.
  ModelPoint best = make_point(query, hint.face, local, false);
  if (mode == HintedSearch::Exact && !face.analytic) visit_face(query, hint.face, best, &local);
  search(query, best, hint.face);
  // The patch from Newton's own derivatives when its foot stood.
  if (patch != nullptr && best.face == hint.face && best.u == local.u && best.v == local.v && local.Suu.allFinite()) {
    const nurbs::SurfaceD2 d{local.point, local.Su, local.Sv, local.Suu, local.Suv, local.Svv};
    *patch = nurbs::OsculatingPatch::at(d, best.normal);
  }
  return best;
}

std::vector<ModelPoint> ModelLocator::closest_points(std::span<const Point3> queries, std::span<const ModelPoint> hints,
                                                     HintedSearch mode) const {
  if (hints.size() != queries.size()) return closest_points(queries);
  return geometry::parallel_map<ModelPoint>(queries.size(), 64,
                                            [&](std::size_t i) { return closest_point(queries[i], hints[i], mode); });
}

void ModelLocator::update_closest_points(std::span<const Point3> queries, std::span<ModelPoint> feet,
                                         HintedSearch mode, std::span<nurbs::OsculatingPatch> patches) const {
  if (feet.size() != queries.size()) throw std::invalid_argument("update_closest_points: one foot per query expected");
  if (!patches.empty() && patches.size() != queries.size()) {
    throw std::invalid_argument("update_closest_points: one patch per query expected");
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, queries.size(), 64), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      feet[i] = closest_point(queries[i], feet[i], mode, patches.empty() ? nullptr : &patches[i]);
    }
  });
}

std::vector<ModelPoint> ModelLocator::closest_points(std::span<const Point3> queries) const {
  return geometry::parallel_map<ModelPoint>(queries.size(), 64, [&](std::size_t i) { return closest_point(queries[i]); });
}

}  // namespace probecomp::cad
