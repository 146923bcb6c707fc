#pragma once
// One result per item, computed in parallel (oneTBB): each item is independent and written to its own slot, so
// the results do not depend on the partition or the thread count.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>
#include <vector>

namespace probecomp::geometry {

// {f(0), f(1), ..., f(n − 1)}; `grain` items at least per task (a few microseconds of work or more).
template <class Result, class F>
[[nodiscard]] std::vector<Result> parallel_map(std::size_t n, std::size_t grain, F&& f) {
  std::vector<Result> out(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) out[i] = f(i);
  });
  return out;
}

}  // namespace probecomp::geometry
