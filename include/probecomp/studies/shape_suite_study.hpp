#pragma once
// A case of the shape suite (simulation/shape_suite.hpp) run through the paper's protocol (studies/comparison.hpp)
// and scored the way issue 48 asks: the CAD method's errors against the actual part, how often ±2u holds them,
// overall and in the worst of 6 × 6 regions of the face, and how far the fitted centre surface (what `fit` writes)
// is from the true one.

#include <array>
#include <vector>

#include "probecomp/simulation/shape_suite.hpp"
#include "probecomp/studies/comparison.hpp"

namespace probecomp::studies {

inline constexpr int kSuiteRegions = 6;  // per direction of the face's domain
// Fewer ok rows than this in a region make its coverage a matter of a point or two: it is not scored.
inline constexpr int kSuiteMinRegionRows = 20;

struct ShapeCaseResult : MethodComparison {
  simulation::ShapeCase shape;
  cad::Model nominal;
  std::vector<simulation::ProgrammedPoint> plan;  // in measurement order
  // Per point: its region of the face's domain (a · kSuiteRegions + b, a along u), from the programmed point.
  std::vector<int> region;
  int flagged = 0;            // the CAD method's rows not ok
  double coverage_2u = 0.0;   // share of ok rows whose |error| ≤ 2u
  double worst_region_coverage_2u = 0.0;  // the lowest such share over regions holding ≥ 20 ok rows
  int worst_region = -1;
  double mean_uncertainty = 0.0;  // mm, ok rows
  // The rms distance of the true probe centres from the fitted centre surface, mm (NaN if the face was not fitted).
  double fit_rms = 0.0;
};

[[nodiscard]] ShapeCaseResult run_shape_case(const simulation::ShapeCase& c,
                                             const compensation::CompensateOptions& options = {});

}  // namespace probecomp::studies
