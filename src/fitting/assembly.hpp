#pragma once
// What the least-squares fitters (least_squares.cpp, penalized.cpp) share when they assemble their normal
// equations from the points: which points are in the surface's domain, and the chunks the sums run in. Private to
// fitting/.

#include <algorithm>
#include <cstddef>

#include "probecomp/fitting/least_squares.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::fitting::detail {

// Points per assembly chunk. Chunks are fixed by the number of points alone and summed in order, so the sums (and
// the fit) do not depend on how many threads ran them.
inline constexpr std::size_t kChunkPoints = 16384;
// Memory cap for the chunks' private normal matrices.
inline constexpr std::size_t kChunkMemoryBytes = std::size_t{64} << 20;

// How many chunks `points` points are summed in, each chunk's private normal matrix taking `bytes_per_chunk`.
[[nodiscard]] inline std::size_t chunk_count(std::size_t points, std::size_t bytes_per_chunk) {
  const std::size_t max_chunks =
      std::max<std::size_t>(1, kChunkMemoryBytes / std::max<std::size_t>(bytes_per_chunk, 1));
  return std::clamp<std::size_t>((points + kChunkPoints - 1) / kChunkPoints, 1, max_chunks);
}

// Whether t lies in the domain d, its edges included.
[[nodiscard]] inline bool inside(const nurbs::Domain& d, const SurfaceParameter& t) {
  return t.u >= d.u0 && t.u <= d.u1 && t.v >= d.v0 && t.v <= d.v1;
}

}  // namespace probecomp::fitting::detail
