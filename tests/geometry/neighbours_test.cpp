// nearest_others and first_at_same_position against lists worked out by hand.

#include "probecomp/geometry/neighbours.hpp"
#include "probecomp/simulation/random.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace probecomp::geometry {
namespace {

// Both neighbour lists of one point set, as the tests compare them.
struct NearestAndFirst {
  std::vector<std::uint32_t> nearest, first;
};

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
TEST(FirstAtSamePosition, NamesEachGroupByItsFirstPoint) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(-50.0, 50.0);
  std::vector<Point3> p;
  for (int k = 0; k < 3000; ++k) p.push_back(simulation::draw_vector(x, rng).cwiseProduct(Vector3(1.0, 1.0, 0.01)));
  for (int k = 0; k < 300; ++k) p.push_back(p[static_cast<std::size_t>(k * 7)]);
  for (int k = 0; k < 50; ++k) p.push_back(p[static_cast<std::size_t>(k * 11)] + Point3(5e-10, 0, 0));
  p.push_back({nan, 0, 0});
  p.push_back({100, 0, 0});
  p.push_back({100 + 0.6e-9, 0, 0});
  p.push_back({100 + 1.2e-9, 0, 0});
  const NearestAndFirst both{nearest_others(p, 1), first_at_same_position(p, 1e-9)};
  EXPECT_EQ(both.nearest[3350], 3350u);  // the non-finite point lists itself
  EXPECT_EQ(both.first[3350], 3350u);
  // The chain at x = 100 is one group, named by its first point.
  const std::size_t n = p.size();
  EXPECT_EQ(both.first[n - 1], n - 3);
  EXPECT_EQ(both.first[n - 2], n - 3);
  std::size_t repeats = 0;
  for (std::size_t k = 0; k < n; ++k) repeats += both.first[k] != k;
  EXPECT_EQ(repeats, 352u);
}

// Checked against brute force for the points nearest the blocks' cuts (within `slab` mm of `cuts`, the x where
// points spread along x are cut) and a random sample, with repeats across the cuts, a non-finite point, and more
// neighbours than one.
void expect_brute_force_neighbours(int points, const std::vector<double>& cuts, double slab) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> x(-100.0, 100.0), y(-40.0, 40.0), z(-1.0, 1.0);
  std::vector<Point3> p;
  for (int k = 0; k < points; ++k) {
    const double pz = z(rng), py = y(rng), px = x(rng);  // as gcc drew them as the call's arguments
    p.emplace_back(px, py, pz);
  }
  // Repeats of points next to the cuts, some of them on the other side of one.
  std::vector<std::size_t> near_cut;
  for (std::size_t k = 0; k < p.size(); ++k) {
    for (const double c : cuts) {
      if (std::abs(p[k].x() - c) < slab) {
        near_cut.push_back(k);
        break;
      }
    }
  }
  ASSERT_GT(near_cut.size(), 200u);
  for (std::size_t i = 0; i < 100; ++i) p.push_back(p[near_cut[i]]);
  p.push_back({nan, 0, 0});
  const std::size_t n = p.size();
  std::vector<std::size_t> check = near_cut;
  std::uniform_int_distribution<std::size_t> any(0, n - 2);
  for (int k = 0; k < 300; ++k) check.push_back(any(rng));
  for (std::size_t i = static_cast<std::size_t>(points); i < n - 1; ++i) check.push_back(i);

  constexpr int kCount = 3;
  const std::vector<std::uint32_t> three = nearest_others(p, kCount);
  const NearestAndFirst both{nearest_others(p, 1), first_at_same_position(p, 1e-9)};
  EXPECT_EQ(both.nearest[n - 1], n - 1);  // the non-finite point lists itself
  EXPECT_EQ(both.first[n - 1], n - 1);
  for (const std::size_t k : check) {
    // Brute force: the squared distances to every other finite point, the three smallest.
    std::vector<std::pair<double, std::size_t>> d;
    d.reserve(n);
    for (std::size_t j = 0; j + 1 < n; ++j) {
      if (j != k) d.emplace_back((p[j] - p[k]).squaredNorm(), j);
    }
    std::partial_sort(d.begin(), d.begin() + kCount, d.end());
    for (int i = 0; i < kCount; ++i) {
      // By distance: with repeats, which of two points at the same distance comes first is a tie.
      EXPECT_EQ((p[three[k * kCount + static_cast<std::size_t>(i)]] - p[k]).squaredNorm(), d[static_cast<std::size_t>(i)].first)
          << "point " << k << ", neighbour " << i;
    }
    EXPECT_EQ((p[both.nearest[k]] - p[k]).squaredNorm(), d[0].first) << "point " << k;
    std::size_t first = k;
    for (const auto& [dist_sq, j] : d) {
      if (dist_sq <= 1e-18) first = std::min(first, j);
    }
    EXPECT_EQ(both.first[k], first) << "point " << k;
  }
  std::size_t repeats = 0;
  for (std::size_t k = 0; k < n; ++k) repeats += both.first[k] != k;
  EXPECT_EQ(repeats, 100u);
}

// Over 131 072 points the search runs over several k-d trees (blocks cut at the median of the longest side, built in
// parallel): the first cut about x = 0 (points spread along x), the next ones about x = ±50.
TEST(NearestOthers, ACloudOfSeveralBlocksFindsWhatBruteForceFinds) {
  expect_brute_force_neighbours(300000, {0.0, -50.0, 50.0}, 0.05);
}

// From 8 192 points on, the points are halved at least once (two trees built side by side): 10 000 points, cut
// about x = 0.
TEST(NearestOthers, TenThousandPointsInTwoBlocksFindWhatBruteForceFinds) {
  expect_brute_force_neighbours(10000, {0.0}, 3.0);
}

}  // namespace
}  // namespace probecomp::geometry
