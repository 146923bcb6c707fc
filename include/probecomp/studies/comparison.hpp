#pragma once
// The paper's simulation protocol (§7; DESIGN.md §3) for any nominal part: simulate the measurement of the
// actual (deformed, misaligned) part, compensate the raw centres by both methods through the same code as
// `probecomp compensate`, and take each compensated point's signed distance from the actual part (+ outside the
// material) as its error. The cylinder and free-form studies are this with their own parts.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "probecomp/cad/locator.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/geometry/rigid.hpp"
#include "probecomp/simulation/deformation.hpp"
#include "probecomp/simulation/measure.hpp"
#include "probecomp/simulation/pretravel.hpp"

namespace probecomp::studies {

struct ErrorSummary {
  int points = 0;  // trusted points (status ok) the figures are over
  double std = 0.0, mean = 0.0, min = 0.0, max = 0.0;  // mm
  [[nodiscard]] double max_abs() const { return std::max(std::abs(min), std::abs(max)); }
};
[[nodiscard]] ErrorSummary summarise(const std::vector<double>& errors);  // NaNs are left out

struct SimulatedMeasurement {
  cad::Model nominal;                       // CAD frame
  simulation::Deformation deformation;      // of the actual part, along the nominal outward normal
  geometry::RigidTransform placement = geometry::RigidTransform::Identity();  // CAD to machine
  std::vector<simulation::ProgrammedPoint> plan;  // in measurement order
  double probe_radius = 1.0;                // mm
  std::vector<double> probe_radii{};        // per programmed point (mm), several tips; empty: probe_radius
  double noise_sigma = 0.0;                 // mm, on each coordinate of the centre
  std::uint64_t seed = 1;                   // the noise
  simulation::Pretravel pretravel{};        // the probe's switch (none: the reported centre is the touched one)
  // A programmed point equal to the one before it (point and normal) is a sample the probe recorded twice: the
  // same reading written again (a scanner's repeated sample), not a new touch with its own noise.
  bool repeats_are_copies = false;
};

struct ComparisonOptions {
  bool approach_normals = true;  // false: the CAD method runs without i,j,k (the conventional one needs them)
  compensation::CompensateOptions compensate{};  // method and probe radius are set by the comparison
};

struct MethodComparison {
  std::vector<simulation::Touch> touches;  // one per programmed point
  compensation::CompensationResult cad, conventional;
  // Per point: signed distance of the compensated point from the actual part, mm; NaN where the method did not
  // trust or compute the point.
  std::vector<double> cad_error, conventional_error;
  ErrorSummary cad_summary, conventional_summary;
  double simulate_seconds = 0.0, cad_seconds = 0.0, conventional_seconds = 0.0;
};

// The touches the probe records on the actual part (its nominal deformed and placed), one per programmed point,
// before any method sees them. Throws InputError if a programmed point misses the actual part: a study's plan must
// keep the tip on its faces.
[[nodiscard]] std::vector<simulation::Touch> simulate_measurement(const SimulatedMeasurement& m);

// simulate_measurement's touches, compensated by both methods and scored against the actual part (throws as it).
[[nodiscard]] MethodComparison compare_methods(const SimulatedMeasurement& m, const ComparisonOptions& options = {});

// Signed distance of each trusted (status ok) compensated point from the part; NaN for the others.
[[nodiscard]] std::vector<double> errors_against(const cad::ModelLocator& part, const compensation::CompensationResult& r);

}  // namespace probecomp::studies
