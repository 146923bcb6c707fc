#pragma once
// The penalised fit's penalty (penalty.cpp): the thin-plate energy of the control net's displacement as band
// matrices, and each knot span's energy of a displacement. Private to fitting/.

#include <span>
#include <vector>

#include "probecomp/nurbs/surface.hpp"

#include "band.hpp"

namespace probecomp::fitting {
struct HierarchicalBasis;
}

namespace probecomp::fitting::detail {

// The thin-plate energy's three terms, each a band matrix: G(θ) = θ·G_ss + G_st + G_tt/θ (θ = 1: the isotropic
// energy). θ < 1 lets the fit bend along s more readily than along t: a wave or crease running across the face
// along t is followed without the freedom to wiggle along it as well.
struct ThinPlateTerms {
  Band uu, uv, vv;
  [[nodiscard]] Band combined(double theta) const {
    Band G = uv;
    G.add(uu, theta);
    G.add(vv, 1.0 / theta);
    return G;
  }
};

// The surface's mean speeds |S_u| and |S_v| (millimetres per unit of u and of v), from 9 × 9 samples: the scale
// from parameters to lengths along the surface that the energy and the refinement's span lengths use.
struct MeanSpeeds {
  double u = 0.0, v = 0.0;
};
[[nodiscard]] MeanSpeeds mean_speeds(const nurbs::Surface& s);

// The thin-plate energy's three terms for the unknowns in `order` (half-bandwidth b), each span weighted by
// span_weights (none: 1); with `D`, each span's isotropic energy Dᵀ G_span D of D in `span_energy` instead,
// unweighted (penalty.cpp; D on s's own control net, in `order`). With `thb` (s its output surface), the terms are
// for the THB unknowns instead: each basis row mapped to them (hierarchical.hpp).
ThinPlateTerms thin_plate_energy(const nurbs::Surface& s, const Ordering& order, int b,
                                 std::span<const double> span_weights, const std::vector<double>* D = nullptr,
                                 std::vector<double>* span_energy = nullptr, const HierarchicalBasis* thb = nullptr);

}  // namespace probecomp::fitting::detail
