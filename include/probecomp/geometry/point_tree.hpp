#pragma once
// A k-d tree (nanoflann) over 3-D points, for seeds and boundary samples. nanoflann's L2 adaptor works with
// SQUARED distances: every distance a PointTree returns or takes is squared.

#include <cstdint>
#include <utility>
#include <vector>
// GCC 12 flags nanoflann's KNN insertion loop with -Warray-bounds for k = 1 although it checks capacity first.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Warray-bounds"
#include <nanoflann.hpp>
#pragma GCC diagnostic pop

#include "probecomp/geometry/types.hpp"

namespace probecomp::geometry {

struct PointCloud {
  std::vector<Point3> points;
  [[nodiscard]] std::size_t kdtree_get_point_count() const { return points.size(); }
  [[nodiscard]] double kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][static_cast<int>(dim)]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};

using PointTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointCloud>, PointCloud, 3, std::uint32_t>;

// A k-d tree over its own copy of the points (the tree refers to them: built in place, never moved).
struct OwnedPointTree {
  PointCloud cloud;
  PointTree tree;
  explicit OwnedPointTree(std::vector<Point3> points)
      : cloud{std::move(points)}, tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
    tree.buildIndex();
  }
};

}  // namespace probecomp::geometry
