#pragma once
// The paper's cylinder studies (§7.1–7.2, Figs 8 and 9; DESIGN.md §3): part of a cylinder, an exact rational
// NURBS, measured on a 100 × 100 grid with a 1 mm tip at noise σ from 0 to 40 µm, (a) misaligned by 2 mm,
// (b) with a local sinusoidal deformation of peak 0.5, 1.0 and 1.5 mm. Mean and std of the compensation error
// of both methods at each σ (studies/comparison.hpp).
//
// The paper gives neither the cylinder's size nor the deformation's shape; ours: radius 10 mm (the cylinder of
// its §2 experiment), a 120° arc about +z, 30 mm along the axis (x), points planned on the middle 90° of the
// arc so that no touch reaches an edge. Misalignment: 2 mm along z (radial at the arc's middle, 45° off
// the normal at the planned points' ends). Deformation: a crest of the given peak at the arc's middle, a
// sinusoid of wavelength 20 mm along the axis under a Gaussian window of 8 mm (slopes up to about 21° at
// 1.5 mm; the trough's curvature radius stays above the tip radius, so the tip can reach every point).

#include <cstdint>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/simulation/deformation.hpp"
#include "probecomp/simulation/measure.hpp"
#include "probecomp/studies/comparison.hpp"

namespace probecomp::studies {

struct CylinderPart {
  double radius = 10.0;   // mm
  double arc_start = 30.0, arc_end = 150.0;  // degrees from +y towards +z, about the x axis
  double length = 30.0;   // mm along x, centred on x = 0
};
// One face, outward away from the axis (material inside), material side not stated (a lone surface).
[[nodiscard]] cad::Model cylinder_part(const CylinderPart& part = {});

struct CylinderStudyOptions {
  CylinderPart part;
  double probe_radius = 1.0;                                         // mm
  int grid = 100;                                                    // grid × grid points
  simulation::PlanMargin margin{.u = 0.125, .v = 0.04};              // u: around the arc (15° each end)
  std::vector<double> sigmas{0.0, 0.005, 0.010, 0.020, 0.030, 0.040};  // mm
  double misalignment = 2.0;                                         // mm along z (misalignment study)
  std::vector<double> peaks{0.5, 1.0, 1.5};                          // mm (deformation study)
  double wavelength = 20.0, window = 8.0;                            // mm (deformation study)
  std::uint64_t seed = 1;                                            // the noise of row k uses seed + k
};

// The deformation of the deformation study with the given peak (mm).
[[nodiscard]] simulation::Deformation cylinder_deformation(const CylinderStudyOptions& o, double peak);

struct CylinderStudyRow {
  double sigma = 0.0;          // mm
  double peak = 0.0;           // deformation peak, mm (0 in the misalignment study)
  double misalignment = 0.0;   // mm along z (0 in the deformation study)
  int points = 0;              // measured
  ErrorSummary cad, conventional;
  int cad_untrusted = 0;       // points the CAD method flagged (outlier, edge, ...): not in its figures
  double seconds = 0.0;        // simulation and both compensations
};

struct CylinderStudyResult {
  std::vector<CylinderStudyRow> rows;
  // The study's claims (§7): the CAD method's |mean| and std below the conventional's in every row, and its
  // std below σ in every row with σ ≥ 10 µm.
  [[nodiscard]] bool cad_better_everywhere() const;
  [[nodiscard]] bool cad_smooths_noise() const;
};

[[nodiscard]] CylinderStudyResult run_cylinder_misalignment_study(const CylinderStudyOptions& options = {});
[[nodiscard]] CylinderStudyResult run_cylinder_deformation_study(const CylinderStudyOptions& options = {});

}  // namespace probecomp::studies
