#pragma once
// The paper's free-form comparison (§7.3, Table 2) end to end: the built-in case (simulation/freeform_case.hpp)
// is measured by the simulator, compensated by both methods through the same code as `probecomp compensate`,
// and each compensated point's error is its signed distance from the actual surface (+ outside the material).

#include <cstdint>
#include <vector>

#include "compensation/pipeline.hpp"
#include "simulation/freeform_case.hpp"

namespace probecomp::studies {

struct FreeformStudyOptions {
  int random_points = 0;        // > 0: this many points at random (u, v) instead of the 120 × 60 grid
  bool shuffle = false;         // the points in random order
  bool approach_normals = true; // false: the CAD method runs without i,j,k (the conventional still uses them)
  bool reversed = false;        // the CAD surface's S_u × S_v points into the material
  std::uint64_t seed = 1;       // noise, random points and shuffling
  double noise_sigma = -1.0;    // >= 0: replaces the case's σ (mm)
  compensation::CompensateOptions compensate;  // method and probe radius are set by the study
};

struct ErrorSummary {
  int points = 0;  // trusted points (status ok) the figures are over
  double std = 0.0, mean = 0.0, min = 0.0, max = 0.0;  // mm
  [[nodiscard]] double max_abs() const { return std::max(std::abs(min), std::abs(max)); }
};
[[nodiscard]] ErrorSummary summarise(const std::vector<double>& errors);  // NaNs are left out

struct FreeformStudyResult {
  simulation::FreeformCase freeform;
  std::vector<simulation::ProgrammedPoint> plan;    // in measurement order
  std::vector<simulation::Touch> touches;
  compensation::CompensationResult cad, conventional;
  // Per point: signed distance of the compensated point from the actual surface, mm; NaN where the method did
  // not trust or compute the point.
  std::vector<double> cad_error, conventional_error;
  ErrorSummary cad_summary, conventional_summary;
  double simulate_seconds = 0.0, cad_seconds = 0.0, conventional_seconds = 0.0;
};

[[nodiscard]] FreeformStudyResult run_freeform_study(const FreeformStudyOptions& options = {});

// The paper's Table 2 (mm): conventional and proposed std, mean, min, max.
struct PaperTable2 {
  ErrorSummary conventional, proposed;
};
[[nodiscard]] PaperTable2 paper_table2();

}  // namespace probecomp::studies
