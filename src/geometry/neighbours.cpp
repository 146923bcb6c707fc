#include "probecomp/geometry/neighbours.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "probecomp/geometry/point_tree.hpp"

namespace probecomp::geometry {

namespace {

// `tree` over `points`; null when there are fewer than 2. `within`, when given, is set for each point that has
// another within `tolerance` (mm) among the neighbours found.
std::vector<std::uint32_t> nearest_others_in(const PointTree* tree, std::span<const Point3> points, int count,
                                             std::vector<char>* within = nullptr, double tolerance = 0.0) {
  const std::size_t n = points.size(), m = static_cast<std::size_t>(std::max(count, 0));
  std::vector<std::uint32_t> out(n * m, 0);
  if (n == 0 || m == 0) return out;
  if (n == 1) return out;  // a point alone lists itself
  const std::size_t wanted = std::min(m + 1, n);
  if (within != nullptr) within->assign(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
    std::vector<std::uint32_t> index(wanted);
    std::vector<double> dist_sq(wanted);  // squared distances (nanoflann's L2 adaptor)
    for (std::size_t pos = range.begin(); pos != range.end(); ++pos) {
      const std::size_t k = tree->vAcc[pos];  // the tree's leaf order: neighbouring queries share cached nodes
      nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(wanted);
      knn.init(index.data(), dist_sq.data());
      const double q[3] = {points[k].x(), points[k].y(), points[k].z()};
      tree->findNeighbors(knn, q, nanoflann::SearchParams());
      // Fewer than asked only for a point with a non-finite coordinate: then the first slots alone are this
      // query's.
      const std::size_t found = std::max<std::size_t>(knn.size(), 1);
      if (knn.size() == 0) index[0] = static_cast<std::uint32_t>(k);
      // The point itself is normally first; with duplicates at distance zero it may come later, or (ties) not at
      // all: drop it where it is, else the farthest.
      std::size_t skip = found - 1;
      for (std::size_t i = 0; i < found; ++i) {
        if (index[i] == k) {
          skip = i;
          break;
        }
      }
      std::size_t j = 0;
      for (std::size_t i = 0; i < found && j < m; ++i) {
        if (i != skip) out[k * m + j++] = index[i];
      }
      // A point whose search found nothing but itself (a non-finite one) lists itself, as a point alone does.
      if (j == 0) out[k * m + j++] = static_cast<std::uint32_t>(k);
      for (; j < m; ++j) out[k * m + j] = out[k * m + j - 1];
      if (within != nullptr) {
        for (std::size_t i = 0; i < knn.size(); ++i) {
          if (index[i] != k && dist_sq[i] <= tolerance * tolerance) (*within)[k] = 1;  // squared, as nanoflann's
        }
      }
    }
  });
  return out;
}

// `candidates`, when given, marks the only points that can have another within the tolerance (the others are their
// own first without a search).
std::vector<std::uint32_t> first_at_same_position_in(const PointTree* tree, std::span<const Point3> points,
                                                     double tolerance, const std::vector<char>* candidates = nullptr) {
  const std::size_t n = points.size();
  std::vector<std::uint32_t> first(n);
  for (std::size_t k = 0; k < n; ++k) first[k] = static_cast<std::uint32_t>(k);
  if (n < 2) return first;
  // nanoflann's radius is a squared distance; a point's search always finds itself, so the lowest index found is
  // at most its own.
  const double radius_sq = tolerance * tolerance;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
    std::vector<std::pair<std::uint32_t, double>> found;
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      if (!points[k].allFinite() || (candidates != nullptr && !(*candidates)[k])) continue;
      found.clear();
      const double q[3] = {points[k].x(), points[k].y(), points[k].z()};
      tree->radiusSearch(q, radius_sq, found, nanoflann::SearchParams(32, 0.0, false));
      for (const auto& [j, d_sq] : found) first[k] = std::min(first[k], j);
    }
  });
  // A chain of points each within the tolerance of the next (never at a tolerance far below the data's
  // resolution) still names one first point per group: the first point's own first.
  for (std::size_t k = 0; k < n; ++k) first[k] = first[first[k]];
  return first;
}

}  // namespace

std::vector<std::uint32_t> nearest_others(std::span<const Point3> points, int count) {
  if (points.size() < 2 || count <= 0) return nearest_others_in(nullptr, points, count);
  const OwnedPointTree t(std::vector<Point3>(points.begin(), points.end()));
  return nearest_others_in(&t.tree, points, count);
}

std::vector<std::uint32_t> first_at_same_position(std::span<const Point3> points, double tolerance) {
  if (points.size() < 2) return first_at_same_position_in(nullptr, points, tolerance);
  const OwnedPointTree t(std::vector<Point3>(points.begin(), points.end()));
  return first_at_same_position_in(&t.tree, points, tolerance);
}

NearestAndFirst nearest_other_and_first(std::span<const Point3> points, double tolerance) {
  if (points.size() < 2) return {nearest_others_in(nullptr, points, 1), first_at_same_position_in(nullptr, points, tolerance)};
  const OwnedPointTree t(std::vector<Point3>(points.begin(), points.end()));
  // The nearest other tells which points may repeat another: only those are searched around (a million distinct
  // points: no radius search at all).
  std::vector<char> within;
  std::vector<std::uint32_t> nearest = nearest_others_in(&t.tree, points, 1, &within, tolerance);
  return {std::move(nearest), first_at_same_position_in(&t.tree, points, tolerance, &within)};
}

}  // namespace probecomp::geometry
