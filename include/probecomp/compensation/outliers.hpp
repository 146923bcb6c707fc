#pragma once
// Gross outliers among one face's points, decided against the face's fitted surface, never against a fixed-degree
// local model: the fit follows real shape wherever several points show it (fitting/adaptive.hpp refines there, and
// its span test caps each point's say), so what it cannot follow is the point's alone.
//
// A point is an outlier when its residual is beyond `sigmas` of its own standard deviation under noise alone:
// σ̂·√(1 − h_k) for a point in the fit (h_k its leverage: a flexible fit absorbs part of a point's error, and the
// test allows for it), σ̂·√(1 + v_k) for a point left out (its residual is then a prediction error: the noise plus
// the fit's own uncertainty there). σ̂ is the fit's robust noise estimate; its floor, `min_residual`, keeps
// exact data from collapsing the bound to the fit's own model error.
//
// σ̂ is the face's noise, or the spread of the residuals around the point where that is larger
// (fitting::LocalSpread): where the fit cannot follow the shape (a feature the data support no more
// control points for, at low noise), its residuals are the shape's, several points deep, and a point that does not
// stand out from them is no gross error. But a fit with gross errors in it is pulled towards them over their
// neighbourhoods, whose spread they inflate enough to hide a smaller error nearby: a face's first fit is judged
// against its noise alone (Spread::Face), which leaves out every point the fit does not explain; the refits, made
// without those, judge against the local spread (Spread::Local) and take back the points that do not stand out.

#include <span>
#include <vector>

#include "probecomp/fitting/adaptive.hpp"

namespace probecomp::compensation {

struct OutlierTest {
  // Five standard deviations: a Gaussian exceeds it once in 1.7 million points.
  double sigmas = 5.0;
  // mm. On noise-free data the fit's own model error (a few tenths of a micrometre where refinement stopped) must
  // not read as outliers; 2 µm is below any gross error (a chip, a stuck probe: 0.1 mm and more) and above that
  // model error.
  double min_residual = 0.002;
};

// What a residual is measured against (see above).
enum class Spread {
  Face,   // the face's noise estimate
  Local,  // the larger of that and the spread of the residuals around the point
};

// Per point of `fit` (weights as given to it: zero for points left out), 1 where the point is an outlier.
[[nodiscard]] std::vector<char> outliers_against_fit(const fitting::AdaptiveFitResult& fit,
                                                     std::span<const double> weights, const OutlierTest& test = {},
                                                     Spread spread = Spread::Local);

// The bound |residual| must exceed for point k to be an outlier, mm.
[[nodiscard]] double outlier_bound(const fitting::AdaptiveFitResult& fit, double weight, std::size_t k,
                                   const OutlierTest& test = {}, Spread spread = Spread::Local);

}  // namespace probecomp::compensation
