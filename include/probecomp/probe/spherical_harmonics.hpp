#pragma once
// Real spherical harmonics of a direction, fully normalised as in geodesy: each has mean square 1 over the sphere
// (Y₀₀ = 1), so a coefficient is the rms of its term, in the unit of the function modelled. Degree l has 2l + 1 of
// them, m = −l..l: m ≥ 0 the cos(mφ) ones, m < 0 the sin(|m|φ) ones; θ from the machine's +z, φ from its +x. A
// degree's span does not depend on the frame (rotations mix functions of one degree only), so a model of degrees
// 0..L is the same model whatever axes it is written in.

#include <vector>

#include "probecomp/geometry/types.hpp"

namespace probecomp::probe {

struct HarmonicIndex {
  int l = 0, m = 0;
};

// Y_lm of the unit vector along `direction` for every (l, m) in `terms`, in that order. Fully normalised associated
// Legendre functions by the standard stable recurrences (Holmes & Featherstone 2002, J. Geodesy 76, eq. 11–13), in
// double precision exact to ~1e-14 for the low degrees used here.
[[nodiscard]] std::vector<double> real_harmonics(const Vector3& direction, const std::vector<HarmonicIndex>& terms);

// Every (l, m) of the degrees 0..degree, without degree 1 when `skip_degree_one` (see qualification.hpp: degree 1 of
// an effective radius is a shift of the sphere's centre).
[[nodiscard]] std::vector<HarmonicIndex> harmonic_terms(int degree, bool skip_degree_one);

}  // namespace probecomp::probe
