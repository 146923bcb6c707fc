#pragma once
// Where the adaptive fit (adaptive.cpp) asks a THB hierarchy over a tensor surface for finer levels: marks[l] flags
// the level-l cells (the surface's knot spans halved l times, spans.hpp's `halved`; cell (a, b) at a·(columns of level l) + b) that level
// l + 1 should cover, and from them the nested domains hierarchical_basis takes. Private to fitting/.

#include <cstdint>
#include <vector>

#include "probecomp/fitting/spans.hpp"

namespace probecomp::fitting::detail {

using LevelFlags = std::vector<std::vector<std::uint8_t>>;

// Ω¹ ⊇ Ω² ⊇ …: level l's marks grown by `ring` cells of level l all round (eight neighbours a step), kept inside
// the domain above (Ωˡ, for l ≥ 1); levels with nothing marked at the end left out.
[[nodiscard]] LevelFlags nested_domains(const LevelFlags& marks, const std::vector<double>& bu,
                                        const std::vector<double>& bv, int ring);

// The finest level whose domain holds (u, v): 0 where no domain does.
[[nodiscard]] int depth_at(const LevelFlags& domains, const std::vector<double>& bu, const std::vector<double>& bv,
                           double u, double v);

// Marks the level-`level` cell that holds (u, v) for level + 1.
void mark_at(LevelFlags& marks, int level, const std::vector<double>& bu, const std::vector<double>& bv, double u,
             double v);

// The marks carried from the cells over (bu, bv) to those over (nbu, nbv), breakpoints that hold them all: each
// new cell takes the mark of the old cell of its level that holds its midpoint.
[[nodiscard]] LevelFlags carried(const LevelFlags& marks, const std::vector<double>& bu, const std::vector<double>& bv,
                                 const std::vector<double>& nbu, const std::vector<double>& nbv);

}  // namespace probecomp::fitting::detail
