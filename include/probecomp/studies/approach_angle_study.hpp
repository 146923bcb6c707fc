#pragma once
// The paper's Fig. 3 with the probe as it really is (§2.2; issue 52; DESIGN.md §3 and §8). The paper touched a
// cylinder section (R = 10 mm, misaligned by dy = 2 mm, r = 1 mm) at 500 approach angles from 0° to 180° and saw,
// beside conventional compensation's error, "a second component of systematic error" from the probe's switch.
// Here the section is touched by a probe whose pre-travel has three lobes about its vertical stylus and differs
// between vertical and horizontal touches (simulation::Pretravel); the stylus is first qualified on a reference
// sphere, and the same touches are compensated three ways: conventional (the nominal r along the programmed
// normal), the CAD method with the nominal r, and the CAD method with the qualification's effective radius by
// direction. Each error is the compensated point's signed distance from the actual part (+ outside), binned by
// approach angle; the CAD method's deviations are binned too. The part is moved rigidly and not deformed, so each
// true deviation is zero and the deviation is the error as the inspection reports it: relative to the registered
// part, without the one translation of all the stylus's points that the qualification cannot see (its radius
// model's degree 1, which the sphere fit puts into the sphere's centre: probe/qualification.hpp). How large that
// translation is depends on how far below the sphere's equator the qualification reaches (sphere_lowest_deg). Beside it, ISO 10360-5's probing test on a second sphere: 25 touches, the form error P_FTU and
// the size error P_STU of the contact points with the sphere fit's one radius and with the model's.
//
// Frame: the cylinder's axis is x; the approach angle θ runs from +y (a horizontal touch, travel −y) through +z
// (from above, travel −z, along the stylus) to −y. The actual part is displaced by dy along +z (the paper's y).

#include <cstdint>
#include <vector>

#include "probecomp/probe/qualification.hpp"
#include "probecomp/simulation/pretravel.hpp"
#include "probecomp/studies/comparison.hpp"

namespace probecomp::studies {

struct ApproachAngleStudyOptions {
  double cylinder_radius = 10.0, probe_radius = 1.0;  // mm: the paper's experiment
  double misalignment = 2.0;                          // dy, mm along +z
  double length = 30.0;                               // of the section along its axis, mm
  int angles = 100;    // approach angles per section, evenly from 0° to 180°
  int sections = 5;    // sections across the axis, evenly over its middle 80 %: angles × sections touches
  int bins = 18;       // of the approach angle, each 180° / bins wide
  simulation::Pretravel probe = simulation::lobing_probe();
  double part_noise = 0.001, sphere_noise = 0.0003;   // σ on each coordinate of a centre, mm
  double sphere_diameter = 25.0;                      // the reference sphere's, mm
  int sphere_touches = 120;                           // qualification: a spiral from the top down to
  double sphere_lowest_deg = 10.0;                    //   this far below the equator (degrees)
  std::uint64_t seed = 1;                             // the part's noise; the spheres' draw from seed + 1, seed + 2
};

struct ApproachAngleTouch {
  double theta_deg = 0.0;
  double pretravel = 0.0;  // p(d) of this touch, mm
  double analytic = 0.0;   // conventional compensation's error in closed form without pre-travel (eqs (1)–(4)), mm
  // Errors, mm; NaN where the method did not trust the point.
  double conventional = 0.0, cad = 0.0, qualified = 0.0;
  // The CAD method's deviations (true deviation 0), mm; NaN where it did not trust the point.
  double cad_deviation = 0.0, qualified_deviation = 0.0;
};

struct ApproachAngleBin {
  double theta_from = 0.0, theta_to = 0.0;  // degrees
  ErrorSummary conventional, cad, qualified;
  ErrorSummary cad_deviation, qualified_deviation;
  double analytic = 0.0, pretravel = 0.0;   // their means over the bin's touches, mm
};

// ISO 10360-5's probing test: the sphere fitted to the 25 contact points (centre − r_eff·n).
struct ProbingTest {
  int touches = 0;
  double form_plain = 0.0, size_plain = 0.0;  // P_FTU (range of radial residuals), P_STU (diameter error), mm
  double form_model = 0.0, size_model = 0.0;  // the same with the effective radius by direction
};

struct ApproachAngleStudyResult {
  probe::StylusQualification qualification;
  std::vector<ApproachAngleTouch> touches;  // in plan order: section by section, θ rising
  std::vector<ApproachAngleBin> bins;
  ProbingTest probing;
  int cad_untrusted = 0, qualified_untrusted = 0;  // points the CAD method flagged, without and with qualification
  double seconds = 0.0;
  // Over the bins with at least one trusted point: the largest |bin mean| and bin std, and the spread of the bin
  // means (largest − smallest), mm.
  [[nodiscard]] double worst_bin_mean(ErrorSummary ApproachAngleBin::*method) const;
  [[nodiscard]] double worst_bin_std(ErrorSummary ApproachAngleBin::*method) const;
  [[nodiscard]] double bin_mean_spread(ErrorSummary ApproachAngleBin::*method) const;
};

[[nodiscard]] ApproachAngleStudyResult run_approach_angle_study(const ApproachAngleStudyOptions& options = {});

}  // namespace probecomp::studies
