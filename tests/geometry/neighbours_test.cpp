// nearest_others and first_at_same_position against lists worked out by hand.

#include "probecomp/geometry/neighbours.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <vector>

namespace probecomp::geometry {
namespace {

TEST(NearestOthers, OnALineTheyAreTheClosestPointsOtherThanItself) {
  // x = 0, 1, 3, 7: distances 1, 2, 4 apart.
  const std::vector<Point3> p = {{0, 0, 0}, {1, 0, 0}, {3, 0, 0}, {7, 0, 0}};
  const std::vector<std::uint32_t> n = nearest_others(p, 2);
  const std::vector<std::uint32_t> expected = {1, 2, 0, 2, 1, 0, 2, 1};
  EXPECT_EQ(n, expected);
}

TEST(NearestOthers, ADuplicateIsAnotherPointAndNeverThePointItself) {
  const std::vector<Point3> p = {{0, 0, 0}, {0, 0, 0}, {5, 0, 0}};
  const std::vector<std::uint32_t> n = nearest_others(p, 1);
  EXPECT_EQ(n[0], 1u);
  EXPECT_EQ(n[1], 0u);
  EXPECT_TRUE(n[2] == 0u || n[2] == 1u);  // either duplicate, at the same distance
}

TEST(NearestOthers, FewerPointsThanAskedRepeatTheFarthest) {
  const std::vector<Point3> p = {{0, 0, 0}, {1, 0, 0}};
  EXPECT_EQ(nearest_others(p, 3), (std::vector<std::uint32_t>{1, 1, 1, 0, 0, 0}));
  EXPECT_EQ(nearest_others(std::vector<Point3>{{2, 2, 2}}, 2), (std::vector<std::uint32_t>{0, 0}));
  EXPECT_TRUE(nearest_others({}, 4).empty());
}

TEST(FirstAtSamePosition, EachPointNamesTheFirstPointAtItsPosition) {
  const std::vector<Point3> p = {{1, 0, 0}, {2, 0, 0}, {1, 0, 0}, {1, 0, 1e-12}, {2, 0, 0}, {3, 0, 0}, {1, 0, 1e-6}};
  // 1e-12 apart is one position at a tolerance of 1e-9; 1e-6 is not.
  EXPECT_EQ(first_at_same_position(p, 1e-9), (std::vector<std::uint32_t>{0, 1, 0, 0, 1, 5, 6}));
}

TEST(FirstAtSamePosition, AChainWithinTheToleranceIsOneGroupAndNonFinitePointsStandAlone) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Point3> p = {{0, 0, 0}, {0.6, 0, 0}, {1.2, 0, 0}, {nan, 0, 0}, {nan, 0, 0}};
  EXPECT_EQ(first_at_same_position(p, 1.0), (std::vector<std::uint32_t>{0, 0, 0, 3, 4}));
  EXPECT_TRUE(first_at_same_position({}, 1.0).empty());
}

// From one tree, and with the radius search only where the nearest other point is within the tolerance, the same
// lists as the two functions apart: random points, exact repeats, near repeats (5e-10 mm off), a chain and
// non-finite points.
TEST(NearestOtherAndFirst, EqualsBothFunctionsApart) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(-50.0, 50.0);
  std::vector<Point3> p;
  for (int k = 0; k < 3000; ++k) p.emplace_back(x(rng), x(rng), 0.01 * x(rng));
  for (int k = 0; k < 300; ++k) p.push_back(p[static_cast<std::size_t>(k * 7)]);
  for (int k = 0; k < 50; ++k) p.push_back(p[static_cast<std::size_t>(k * 11)] + Point3(5e-10, 0, 0));
  p.push_back({nan, 0, 0});
  p.push_back({100, 0, 0});
  p.push_back({100 + 0.6e-9, 0, 0});
  p.push_back({100 + 1.2e-9, 0, 0});
  const NearestAndFirst both = nearest_other_and_first(p, 1e-9);
  EXPECT_EQ(both.nearest, nearest_others(p, 1));
  EXPECT_EQ(both.nearest[3350], 3350u);  // the non-finite point lists itself
  EXPECT_EQ(both.first, first_at_same_position(p, 1e-9));
  // The chain at x = 100 is one group, named by its first point.
  const std::size_t n = p.size();
  EXPECT_EQ(both.first[n - 1], n - 3);
  EXPECT_EQ(both.first[n - 2], n - 3);
  std::size_t repeats = 0;
  for (std::size_t k = 0; k < n; ++k) repeats += both.first[k] != k;
  EXPECT_EQ(repeats, 352u);
}

}  // namespace
}  // namespace probecomp::geometry
