#pragma once
// The reference the product's fit is measured against (issue 48): the same raw centres, registered by the same
// transform, compensated through a plain tensor-product P-spline of their height above the nominal surface with its
// penalties chosen by GCV (tests/support/reference_smoother.hpp, written apart from src/fitting), offset by r along
// the normal of that smoothed centre surface. Scored against the same actual part.

#include "probecomp/studies/shape_suite_study.hpp"

namespace probecomp::bench {

struct ReferenceScore {
  int points = 0;         // the rows the product trusted (ok): the same rows are scored
  double std = 0.0, mean = 0.0, max_abs = 0.0;  // mm
  double log10_lambda_s = 0.0, log10_lambda_t = 0.0, edf = 0.0;
};

[[nodiscard]] ReferenceScore score_reference(const studies::ShapeCaseResult& s, bool adaptive = false);

}  // namespace probecomp::bench
