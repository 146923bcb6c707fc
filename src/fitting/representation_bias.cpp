#include "representation_bias.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "probecomp/fitting/penalized.hpp"
#include "probecomp/fitting/spans.hpp"

#include "nets.hpp"

namespace probecomp::fitting::detail {

namespace {

// The finer net has about this many times the fit's control points. Measured on 94 faces (the shape suite and sets
// 200–500, --no-reference): faces with a region whose ±2u coverage is under 88 %, 33 -> 27 at 2, 25 at 4; the
// lowest overall coverage 92.6 -> 96.0 % at 2; BM_Compensate10k 182 -> 218 ms at 2, 283 ms at 4.
constexpr double kFinerNetFactor = 2.0;
// Nor more than this many (a band of a few tens of MB): a face of a million points (BM_Compensate1M20x20's fit: 9 700
// control points) goes without the check rather than double its memory.
constexpr double kMaxFinerNetControlPoints = 8192.0;

}  // namespace

// Where the adaptive fit stops, its spans' χ² tests (at 1 % over the whole face) and cross-validation (a face's
// prediction error, in which a few points' bias weighs little) can both accept a net that misses a feature's
// change of curvature by several σ̂ at a few points: on the paper's grid at σ = 2.5 µm, a dent's rim 4.0 µm off at
// u = 1.0 µm, whatever λ (1 and 2 decades lower: the same), seen by no estimate from the fit's own residuals. A fit
// on a finer net follows it. The two fits' difference d_k = r_k − r'_k has variance σ̂²(v'_k − v_k) from noise (v:
// the variance factors; nested fits, the finer one's extra freedom); its mean square beyond that, pooled over the
// span and its eight neighbours like the residuals' bias estimate (fitting/adaptive.cpp), is the coarser fit's
// bias there as far as the finer net sees it. The finer fit has the same absolute λ and each of its spans its parent
// span's weight: the same penalty on more freedom.
void add_representation_bias(AdaptiveFitResult& fit, const nurbs::Surface& start, std::span<const Point3> points,
                             std::span<const double> weights, const AdaptiveFitOptions& options) {
  if (fit.span_weight.empty() || !(fit.noise_sigma > options.noise_floor) || !(fit.lambda > 0.0)) return;
  const nurbs::Surface coarse = on_net_of(start, fit.surface);
  const double coarse_count = static_cast<double>(coarse.num_u()) * coarse.num_v();
  // The spans halved in the direction whose spans are longer: a factor just under 2, as a second halving would pass
  // the cap.
  const double cap = std::min(1.01 * kFinerNetFactor * coarse_count, kMaxFinerNetControlPoints);
  const nurbs::Surface fine = uniformly_refined(coarse, kFinerNetFactor * coarse_count, cap);
  if (static_cast<double>(fine.num_u()) * fine.num_v() < 1.5 * coarse_count) return;
  const std::vector<double> cu = coarse.U().breakpoints(), cv = coarse.V().breakpoints();
  const std::vector<double> fu = fine.U().breakpoints(), fv = fine.V().breakpoints();
  const std::size_t nsu = cu.size() - 1, nsv = cv.size() - 1;
  if (fit.span_weight.size() != nsu * nsv) return;
  std::vector<double> w((fu.size() - 1) * (fv.size() - 1));
  for (std::size_t a = 0; a + 1 < fu.size(); ++a) {
    for (std::size_t b = 0; b + 1 < fv.size(); ++b) {
      const auto pa = static_cast<std::size_t>(span_of(cu, 0.5 * (fu[a] + fu[a + 1])));
      const auto pb = static_cast<std::size_t>(span_of(cv, 0.5 * (fv[b] + fv[b + 1])));
      w[a * (fv.size() - 1) + b] = fit.span_weight[pa * nsv + pb];
    }
  }
  PenalizedFitOptions o = options.fit;
  o.lambda = fit.lambda;
  o.log10_anisotropy = fit.log10_anisotropy;
  const PenalizedFitResult finer = fit_penalized(fine, points, fit.params, weights, o, w);
  if (!finer.ok()) return;
  const std::vector<double> r = along_normal(finer.surface, points, fit.params, {}).residual;
  const double s2 = fit.noise_sigma * fit.noise_sigma;
  std::vector<double> excess(nsu * nsv, 0.0);
  std::vector<int> count(nsu * nsv, 0);
  std::vector<std::uint32_t> span(points.size());
  for (std::size_t k = 0; k < points.size(); ++k) {
    span[k] = static_cast<std::uint32_t>(span_at(cu, cv, fit.params[k].u, fit.params[k].v));
    if (!weights.empty() && !(weights[k] > 0.0)) continue;
    const double d = fit.residuals[k] - r[k];
    excess[span[k]] += d * d - s2 * std::max(finer.variance_factor[k] - fit.variance_factor[k], 0.0);
    ++count[span[k]];
  }
  std::vector<double> bias(nsu * nsv, 0.0);
  for (std::size_t a = 0; a < nsu; ++a) {
    for (std::size_t b = 0; b < nsv; ++b) {
      double e = 0.0;
      int n = 0;
      for_each_around(a, b, nsu, nsv, [&](std::size_t s) {
        e += excess[s];
        n += count[s];
      });
      if (n > 0) bias[a * nsv + b] = std::sqrt(std::max(e / n, 0.0));
    }
  }
  for (std::size_t k = 0; k < points.size(); ++k) fit.misfit[k] = std::max(fit.misfit[k], bias[span[k]]);
}

}  // namespace probecomp::fitting::detail
