#pragma once
// The paper's free-form comparison (§7.3, Table 2) end to end: the built-in case (simulation/freeform_case.hpp)
// run through the paper's simulation protocol (studies/comparison.hpp).

#include <array>
#include <cstdint>
#include <vector>

#include "probecomp/simulation/freeform_case.hpp"
#include "probecomp/studies/comparison.hpp"

namespace probecomp::studies {

struct FreeformStudyOptions {
  int random_points = 0;        // > 0: this many points at random (u, v) instead of the 120 × 60 grid
  bool shuffle = false;         // the points in random order
  bool approach_normals = true; // false: the CAD method runs without i,j,k (the conventional still uses them)
  bool reversed = false;        // the CAD surface's S_u × S_v points into the material
  std::uint64_t seed = 1;       // noise, random points and shuffling
  double noise_sigma = -1.0;    // >= 0: replaces the case's σ (mm)
  bool steep_dent = false;      // the dent narrowed to a Gaussian width of 1.75 mm: flanks sloping up to 19°
  // This fraction of the points (chosen at random) measured twice in a row: as a repeated reading (the same
  // numbers twice, as a scanner's repeated sample) or, with exact_repeats false, as a second touch with its own
  // noise.
  double repeated_fraction = 0.0;
  bool exact_repeats = true;
  // > 0: two styli. The points on the panel's side of larger x (beyond its middle) are measured with a tip of this
  // radius (mm); the rest with the case's 1 mm tip.
  double second_probe_radius = 0.0;
  compensation::CompensateOptions compensate;  // method and probe radius are set by the study
};

// The scattered-points variant: n points at random (u, v), in random order, without approach normals for the CAD
// method (a scan's points rather than a part program's). Everything else as the defaults.
[[nodiscard]] FreeformStudyOptions scattered_points(int n);

struct FreeformStudyResult : MethodComparison {
  simulation::FreeformCase freeform;
  std::vector<simulation::ProgrammedPoint> plan;  // in measurement order
  // The CAD method's per-point uncertainty u against the true errors (cad_error), over its trusted (ok) points:
  // their mean u, mm, and the share whose |error| ≤ 2u over the panel and in the worst of a 4 × 4 grid of regions
  // over it (by the programmed points' x and y). About 95 % is what a k = 1 uncertainty promises.
  double mean_uncertainty = 0.0;
  double coverage_2u = 0.0, worst_region_coverage_2u = 0.0;
  // Per region (a · 4 + b, a along x): ok points, and those of them within ±2u.
  std::array<int, 16> region_ok{}, region_covered{};
  int flagged = 0;  // the CAD method's rows not ok
};

[[nodiscard]] FreeformStudyResult run_freeform_study(const FreeformStudyOptions& options = {});

// The paper's Table 2 (mm): conventional and proposed std, mean, min, max.
struct PaperTable2 {
  ErrorSummary conventional, proposed;
};
[[nodiscard]] PaperTable2 paper_table2();

}  // namespace probecomp::studies
