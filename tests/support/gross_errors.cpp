#include "support/gross_errors.hpp"

#include <algorithm>
#include <random>

namespace probecomp::testing {

std::vector<char> move_one_percent(std::vector<Point3>& points, const std::vector<simulation::ProgrammedPoint>& plan,
                                   std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::size_t> order(points.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<char> moved(points.size(), 0);
  std::uniform_real_distribution<double> size(0.1, 5.0);
  for (std::size_t k = 0; k < points.size() / 100; ++k) {
    const std::size_t i = order[k];
    moved[i] = 1;
    points[i] += (rng() % 2 ? 1.0 : -1.0) * size(rng) * plan[i].normal;
  }
  return moved;
}

}  // namespace probecomp::testing
