#include "probecomp/geometry/neighbours.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <utility>

#include "probecomp/geometry/point_tree.hpp"

namespace probecomp::geometry {

namespace {

constexpr std::uint32_t kNoBlock = std::numeric_limits<std::uint32_t>::max();

// k-d trees over spatial blocks of the points, built in parallel: nanoflann 1.4 builds a tree on one thread (a
// million points: 0.27 s, a quarter of the fit's time). The blocks are halves of halves, each cut at the median of
// the longest side of its box, of at most kBlockPoints points, and at most half the points from kMinHalving points
// on (10 000 points: two trees of 5 000 built side by side, where one tree took 2.8 ms of the fit's 20). A query
// searches its own block's tree, then every other block whose box is nearer than its farthest neighbour so far: the
// same neighbours as one tree over all the points, up to the order of ties. The blocks depend on the points alone,
// not on the thread count. Fewer points than kMinHalving make one block: the one tree there always was. Non-finite
// points belong to no block: no finite point has them as a neighbour, and they find none.
class Forest {
 public:
  static constexpr std::size_t kBlockPoints = std::size_t{1} << 17;
  static constexpr std::size_t kMinHalving = 8192;

  explicit Forest(std::span<const Point3> points) : points_(points), block_of_(points.size(), kNoBlock) {
    std::vector<std::uint32_t> finite;
    finite.reserve(points.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (points[k].allFinite()) finite.push_back(static_cast<std::uint32_t>(k));
    }
    using Range = std::pair<std::size_t, std::size_t>;
    std::vector<Range> ranges{{0, finite.size()}};
    const std::size_t most =
        finite.size() >= kMinHalving ? std::min(kBlockPoints, (finite.size() + 1) / 2) : kBlockPoints;
    for (;;) {
      std::vector<Range> next;
      std::vector<std::size_t> cut;  // the ranges of `ranges` that are halved
      for (std::size_t r = 0; r < ranges.size(); ++r) {
        const auto [b, e] = ranges[r];
        if (e - b <= most) {
          next.push_back(ranges[r]);
          continue;
        }
        cut.push_back(r);
        next.emplace_back(b, b + (e - b) / 2);
        next.emplace_back(b + (e - b) / 2, e);
      }
      if (cut.empty()) break;
      tbb::parallel_for(std::size_t{0}, cut.size(), [&](std::size_t c) {
        const auto [b, e] = ranges[cut[c]];
        BoundingBox box;
        for (std::size_t i = b; i < e; ++i) box.extend(points[finite[i]]);
        int axis = 0;
        (box.max - box.min).maxCoeff(&axis);
        std::nth_element(finite.begin() + static_cast<std::ptrdiff_t>(b),
                         finite.begin() + static_cast<std::ptrdiff_t>(b + (e - b) / 2),
                         finite.begin() + static_cast<std::ptrdiff_t>(e), [&](std::uint32_t i, std::uint32_t j) {
                           const double a = points[i][axis], c2 = points[j][axis];
                           return a < c2 || (a == c2 && i < j);
                         });
      });
      ranges = std::move(next);
    }
    blocks_.resize(ranges.size());
    tbb::parallel_for(std::size_t{0}, ranges.size(), [&](std::size_t bl) {
      Block& block = blocks_[bl];
      const auto [b, e] = ranges[bl];
      // In input order within the block: with one block, the tree is the one over all the points.
      block.index.assign(finite.begin() + static_cast<std::ptrdiff_t>(b), finite.begin() + static_cast<std::ptrdiff_t>(e));
      std::sort(block.index.begin(), block.index.end());
      std::vector<Point3> own(block.index.size());
      for (std::size_t i = 0; i < own.size(); ++i) {
        own[i] = points[block.index[i]];
        block.box.extend(own[i]);
        block_of_[block.index[i]] = static_cast<std::uint32_t>(bl);
      }
      if (!own.empty()) block.tree = std::make_unique<OwnedPointTree>(std::move(own));
    });
    order_.reserve(points.size());
    for (const Block& block : blocks_) {
      if (!block.tree) continue;
      for (const auto local : block.tree->tree.vAcc) order_.push_back(block.index[local]);
    }
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (block_of_[k] == kNoBlock) order_.push_back(static_cast<std::uint32_t>(k));
    }
  }

  // The `wanted` nearest points to point k (itself among them), nearest first, as indices into the points with
  // their SQUARED distances (nanoflann's): how many were found (0 for a non-finite point).
  std::size_t nearest(std::size_t k, std::size_t wanted, std::uint32_t* index, double* dist_sq) const {
    const std::uint32_t own = block_of_[k];
    if (own == kNoBlock || wanted == 0) return 0;
    const double q[3] = {points_[k].x(), points_[k].y(), points_[k].z()};
    std::size_t found = search(blocks_[own], q, wanted, index, dist_sq);
    thread_local std::vector<std::uint32_t> more_index;
    thread_local std::vector<double> more_dist;
    more_index.resize(wanted);
    more_dist.resize(wanted);
    for (std::size_t bl = 0; bl < blocks_.size(); ++bl) {
      if (bl == own || !blocks_[bl].tree) continue;
      if (found == wanted && !(blocks_[bl].box.squared_distance(points_[k]) < dist_sq[found - 1])) continue;
      const std::size_t more = search(blocks_[bl], q, wanted, more_index.data(), more_dist.data());
      for (std::size_t i = 0; i < more; ++i) {
        // Insertion into the sorted list, keeping at most `wanted`.
        if (found == wanted && !(more_dist[i] < dist_sq[found - 1])) break;
        std::size_t at = found < wanted ? found++ : found - 1;
        while (at > 0 && dist_sq[at - 1] > more_dist[i]) {
          dist_sq[at] = dist_sq[at - 1];
          index[at] = index[at - 1];
          --at;
        }
        dist_sq[at] = more_dist[i];
        index[at] = more_index[i];
      }
    }
    return found;
  }

  // The points within sqrt(radius_sq) of point k (itself too), as indices into the points, in `found`.
  void within(std::size_t k, double radius_sq, std::vector<std::uint32_t>& found) const {
    found.clear();
    if (block_of_[k] == kNoBlock) return;
    const double q[3] = {points_[k].x(), points_[k].y(), points_[k].z()};
    thread_local std::vector<std::pair<std::uint32_t, double>> hits;
    for (const Block& block : blocks_) {
      if (!block.tree || block.box.squared_distance(points_[k]) > radius_sq) continue;
      hits.clear();
      block.tree->tree.radiusSearch(q, radius_sq, hits, nanoflann::SearchParams(32, 0.0, false));
      for (const auto& [local, d_sq] : hits) found.push_back(block.index[local]);
    }
  }

  // Every point once: block by block, each in its tree's leaf order (neighbouring queries then share cached nodes),
  // the non-finite points last.
  [[nodiscard]] const std::vector<std::uint32_t>& order() const { return order_; }

 private:
  struct Block {
    std::unique_ptr<OwnedPointTree> tree;
    std::vector<std::uint32_t> index;  // the tree's points as indices into the points
    BoundingBox box;
  };

  // nanoflann's k nearest in one block, mapped to indices into the points.
  static std::size_t search(const Block& block, const double* q, std::size_t wanted, std::uint32_t* index,
                            double* dist_sq) {
    nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(static_cast<std::uint32_t>(wanted));
    knn.init(index, dist_sq);
    block.tree->tree.findNeighbors(knn, q, nanoflann::SearchParams());
    const std::size_t found = knn.size();
    for (std::size_t i = 0; i < found; ++i) index[i] = block.index[index[i]];
    return found;
  }

  std::span<const Point3> points_;
  std::vector<Block> blocks_;
  std::vector<std::uint32_t> block_of_;  // kNoBlock for a non-finite point
  std::vector<std::uint32_t> order_;
};

// Over `forest`; null when there are fewer than 2 points. `within`, when given, is set for each point that has
// another within `tolerance` (mm) among the neighbours found.
std::vector<std::uint32_t> nearest_others_in(const Forest* forest, std::span<const Point3> points, int count,
                                             std::vector<char>* within = nullptr, double tolerance = 0.0) {
  const std::size_t n = points.size(), m = static_cast<std::size_t>(std::max(count, 0));
  std::vector<std::uint32_t> out(n * m, 0);
  if (n == 0 || m == 0) return out;
  if (n == 1) return out;  // a point alone lists itself
  const std::size_t wanted = std::min(m + 1, n);
  if (within != nullptr) within->assign(n, 0);
  const std::vector<std::uint32_t>& order = forest->order();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
    std::vector<std::uint32_t> index(wanted);
    std::vector<double> dist_sq(wanted);  // squared distances (nanoflann's L2 adaptor)
    for (std::size_t pos = range.begin(); pos != range.end(); ++pos) {
      const std::size_t k = order[pos];
      const std::size_t searched = forest->nearest(k, wanted, index.data(), dist_sq.data());
      // Fewer than asked only for a point with a non-finite coordinate: then the first slots alone are this
      // query's.
      const std::size_t found = std::max<std::size_t>(searched, 1);
      if (searched == 0) index[0] = static_cast<std::uint32_t>(k);
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
        for (std::size_t i = 0; i < searched; ++i) {
          if (index[i] != k && dist_sq[i] <= tolerance * tolerance) (*within)[k] = 1;  // squared, as nanoflann's
        }
      }
    }
  });
  return out;
}

// `candidates`, when given, marks the only points that can have another within the tolerance (the others are their
// own first without a search).
std::vector<std::uint32_t> first_at_same_position_in(const Forest* forest, std::span<const Point3> points,
                                                     double tolerance, const std::vector<char>* candidates = nullptr) {
  const std::size_t n = points.size();
  std::vector<std::uint32_t> first(n);
  for (std::size_t k = 0; k < n; ++k) first[k] = static_cast<std::uint32_t>(k);
  if (n < 2) return first;
  // The radius is a squared distance (nanoflann's); a point's search always finds itself, so the lowest index found
  // is at most its own.
  const double radius_sq = tolerance * tolerance;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
    std::vector<std::uint32_t> found;
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      if (!points[k].allFinite() || (candidates != nullptr && !(*candidates)[k])) continue;
      forest->within(k, radius_sq, found);
      for (const std::uint32_t j : found) first[k] = std::min(first[k], j);
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
  const Forest forest(points);
  return nearest_others_in(&forest, points, count);
}

std::vector<std::uint32_t> first_at_same_position(std::span<const Point3> points, double tolerance) {
  if (points.size() < 2) return first_at_same_position_in(nullptr, points, tolerance);
  const Forest forest(points);
  // The nearest other tells which points may repeat another: only those are searched around (a million distinct
  // points: no radius search at all).
  std::vector<char> within;
  (void)nearest_others_in(&forest, points, 1, &within, tolerance);
  return first_at_same_position_in(&forest, points, tolerance, &within);
}

}  // namespace probecomp::geometry
