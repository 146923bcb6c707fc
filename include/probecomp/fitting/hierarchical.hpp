#pragma once
// A truncated hierarchical B-spline (THB) space over a start surface, for local refinement of the penalised fit
// (issue 48; docs/local-refinement-plan.md). Level 0 is the start's tensor space (degrees p, q, knots U⁰, V⁰,
// weights w fixed); level l halves every span of level l − 1 (Uˡ, Vˡ). Over nested regions Ω¹ ⊇ Ω² ⊇ …, each a
// union of cells of the level above, the level-l B-splines whose support lies in Ωˡ but not in Ωˡ⁺¹ are active,
// and every active function is truncated: its components along the finer levels' B-splines inside their Ωᵏ are
// taken out (Giannelli, Jüttler & Speleers, "THB-splines: the truncated basis for hierarchical splines", CAGD 29,
// 2012). The functions stay ≥ 0 and sum to 1, and with the start's weights (R_τ = ŵ_τ T_τ / W, ŵ_τ the weight
// function's coefficient at τ's level) a rational face keeps its weights and its displacement stays in millimetres.
//
// Control points are added only where the Ωˡ are, not along knot lines across the whole face. Each THB function is
// held as a combination of the B-splines of one tensor space that contains them all: the start refined to
// U^out = U⁰ ∪ {level-l knots inside the u-projection of Ωˡ, every l} and V^out likewise. That surface is the fit's
// output, and exactly (no approximation) the displacement of its control net is the THB one mapped through
// `coefficient`.

#include <cstdint>
#include <span>
#include <vector>

#include "probecomp/nurbs/surface.hpp"

namespace probecomp::fitting {

struct HierarchicalBasis {
  // The start refined to U^out, V^out: every THB function is a combination of its rational basis functions R^out_J.
  nurbs::Surface surface;
  int unknowns = 0;         // THB functions, in their unknown order (Greville points, the shorter direction inner)
  int refined_unknowns = 0; // of which functions of level 1 or finer
  int levels = 1;           // L: level 0 and the refined levels built
  // R_τ = Σ_J coefficient · R^out_J: for control point J of `surface` (i·num_v + j), its entries
  // [first[J], first[J + 1]) of (unknown, coefficient).
  std::vector<int> first;
  std::vector<int> unknown;
  std::vector<double> coefficient;
  // Per knot span of `surface`, keyed by the span's first control point (i0, j0) = (su − p, sv − q) at
  // i0·num_v + j0: the THB functions non-zero there, sorted, entries [cell_first[c], cell_first[c + 1]) of
  // cell_unknowns (empty for a key that starts no span).
  std::vector<int> cell_first;
  std::vector<int> cell_unknowns;
  int bandwidth = 0;        // max over spans of (largest − smallest unknown non-zero there)
  int max_row = 0;          // max over spans of the number of THB functions non-zero there
};

// The THB space of `start` refined over the level-0 cells marked in `refine` (span (a, b) of start's breakpoints at
// a·(V spans) + b; non-zero: refine) grown by `ring` cells all round: a level-1 bicubic needs 2 × 2 level-0 cells
// inside Ω¹, so without a ring a band of marked cells gains almost nothing. No cell marked: the start's tensor
// space, with the unknowns in Ordering's order. Throws std::invalid_argument if `refine` has the wrong size.
[[nodiscard]] HierarchicalBasis hierarchical_basis(const nurbs::Surface& start, std::span<const std::uint8_t> refine,
                                                   int ring = 1);

// The THB space of `start` over nested domains Ω¹ ⊇ Ω² ⊇ … ⊇ Ω^(L−1), L = domains.size() + 1. Level l halves every
// span of level l − 1; Ωˡ is a union of level-(l − 1) cells, flagged in domains[l − 1]: cell (a, b) of the
// (nsu·2^(l−1)) × (nsv·2^(l−1)) cells at a·(nsv·2^(l−1)) + b (nsu, nsv: start's knot spans). Each function is
// truncated level by level (Giannelli, Jüttler & Speleers 2012). No admissibility is imposed: a cell may meet
// functions of any number of levels. Throws std::invalid_argument for a flag vector of the wrong size or domains
// that are not nested.
[[nodiscard]] HierarchicalBasis hierarchical_basis(const nurbs::Surface& start,
                                                   std::span<const std::vector<std::uint8_t>> domains);

// The THB functions non-zero at (u, v) and their values R_τ(u, v), as (unknown, value) pairs in unknown order.
struct HierarchicalRow {
  std::vector<int> unknown;
  std::vector<double> value;
};
[[nodiscard]] HierarchicalRow hierarchical_row(const HierarchicalBasis& basis, double u, double v);

// The displacement of each of `basis.surface`'s control points (i·num_v + j, mm) that the THB displacement D makes
// (unknowns × 3, mm, in unknown order): Σ_τ coefficient · D_τ.
[[nodiscard]] std::vector<Vector3> control_net_displacement(const HierarchicalBasis& basis, std::span<const double> D);

// The surface whose control net is `basis.surface`'s moved by that displacement: S = S⁰ + Σ_τ R_τ D_τ, exactly.
[[nodiscard]] nurbs::Surface to_nurbs(const HierarchicalBasis& basis, std::span<const double> D);

}  // namespace probecomp::fitting
