#pragma once
// Robust weights for iteratively reweighted least squares (ICP's estimation step), with the scale estimated
// from the residuals themselves (geometry::robust_scale: σ̂ = 1.4826 · median |r|, consistent for Gaussian noise
// and unmoved by up to half the points being gross outliers).

#include <span>

namespace probecomp::registration {

enum class RobustLoss {
  None,     // plain least squares (the paper's): every point weight 1
  Huber,    // w = min(1, k/|r|), k = 1.345 σ̂: 95 % efficiency on Gaussian noise, outliers keep a little pull
  Cauchy,   // w = 1 / (1 + (r/c)²), c = 2.3849 σ̂: 95 % efficiency, a gross outlier's pull fades to zero
  Trimmed,  // w = 1 for |r| ≤ 3 σ̂, else 0: hard rejection
};

[[nodiscard]] const char* to_string(RobustLoss loss);

struct RobustKernel {
  RobustLoss loss = RobustLoss::Cauchy;
  // The scale never drops below this (mm). Noise-free data converge to residuals of rounding size; a scale
  // that followed them down would weight points by their rounding errors. 1e-6 mm is far below any CMM's
  // noise and far above double rounding on part coordinates (1e-13 mm).
  double min_scale = 1e-6;
};

// The IRLS weight of a residual r at scale σ̂ (> 0).
[[nodiscard]] double robust_weight(RobustLoss loss, double r, double scale);

// Residuals beyond this many σ̂ are reported as outliers, whatever the loss (a 0.3 % false alarm rate on
// Gaussian noise).
inline constexpr double kOutlierSigmas = 3.0;

}  // namespace probecomp::registration
