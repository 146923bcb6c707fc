#pragma once
// A case of the shape suite (simulation/shape_suite.hpp) run through the paper's protocol (studies/comparison.hpp)
// and scored the way issue 48 asks: the CAD method's errors against the actual part, how often ±2u holds them,
// overall and in the worst of 6 × 6 regions of the face, and how far the fitted centre surface (what `fit` writes)
// is from the true one.

#include <array>
#include <limits>
#include <span>
#include <vector>

#include "probecomp/simulation/shape_suite.hpp"
#include "probecomp/studies/comparison.hpp"

namespace probecomp::studies {

inline constexpr int kSuiteRegions = 6;  // per direction of the face's domain
// Fewer ok rows than this in a region make its coverage a matter of a point or two: it is not scored.
inline constexpr int kSuiteMinRegionRows = 20;

// Per region (a · kSuiteRegions + b): the share of its rows with a finite error whose |error| ≤ 2u; NaN where
// fewer than kSuiteMinRegionRows such rows are scored.
using RegionShares = std::array<double, kSuiteRegions * kSuiteRegions>;
[[nodiscard]] RegionShares region_coverage_2u(std::span<const double> error, std::span<const double> u,
                                              std::span<const int> region);

struct ShapeCaseResult : MethodComparison {
  simulation::ShapeCase shape;
  cad::Model nominal;
  std::vector<simulation::ProgrammedPoint> plan;  // in measurement order
  // Per point: its region of the face's domain (a · kSuiteRegions + b, a along u), from the programmed point.
  std::vector<int> region;
  int flagged = 0;            // the CAD method's rows not ok
  double coverage_2u = 0.0;   // share of ok rows whose |error| ≤ 2u
  RegionShares region_coverage{};         // each region's (region_coverage_2u of the ok rows)
  double worst_region_coverage_2u = 0.0;  // the lowest of them
  int worst_region = -1;
  double mean_uncertainty = 0.0;  // mm, ok rows
  // The rms distance of the true probe centres from the fitted centre surface, mm (NaN if the face was not fitted).
  double fit_rms = 0.0;
};

// The case's measurement as simulated: its base part, plan, deformation, placement, tip and noise (the seed of its
// noise draw: ShapeCase::noise_draw).
[[nodiscard]] SimulatedMeasurement shape_case_measurement(const simulation::ShapeCase& c);

[[nodiscard]] ShapeCaseResult run_shape_case(const simulation::ShapeCase& c,
                                             const compensation::CompensateOptions& options = {});

// A case over `draws` draws of its noise (ShapeCase::noise_draw 0, 1, …), to tell what u promises a region on
// average from what one draw happens to give.
struct ReplicatedShapeCase {
  // Per draw: the CAD method's std (mm), ±2u coverage overall and in the worst region (shares).
  std::vector<double> stds, coverages, worst_regions;
  // Per draw: the worst region's coverage had each point's u been its rms error over all the draws (its true bias
  // and variance as far as the draws tell them). That flatters it (each draw's own error is one of the terms): a
  // bound on what a sound u can reach in the worst region of one draw, not a figure to match.
  std::vector<double> oracle_worst_regions;
  // The lowest over regions scored in every draw of the region's coverage averaged over the draws (NaN if none).
  double lowest_region_mean = std::numeric_limits<double>::quiet_NaN();
  // Over rows ok in every draw (mm): the rms of each row's mean error over the draws, less its scatter's share
  // (the error's bias), the rms of its standard deviation over the draws (its scatter), and the rms of its u over
  // the draws. Which part of the error u misses, where it misses.
  double bias_rms = 0.0, scatter_rms = 0.0, u_rms = 0.0;
};
[[nodiscard]] ReplicatedShapeCase replicate_shape_case(simulation::ShapeCase c, int draws,
                                                       const compensation::CompensateOptions& options = {});

}  // namespace probecomp::studies
