#pragma once
// The whole method (DESIGN.md §2) on a CAD model and a set of raw probe-centre points, as `probecomp compensate`
// runs it:
//   cad           material side → offset faces by r → register the raw centres to the offset model → fit each
//                 face's centre surface through its points (adaptive, outliers removed) → smooth (project on the
//                 fit) → offset by r along the fitted normal, into the material → deviation from the registered
//                 nominal;
//   conventional  c − r·(i,j,k), registered to the nominal; deviation from the registered nominal.
// Every input point comes back, in order, with a status saying whether it can be trusted.

#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/cad/material_side.hpp"
#include "probecomp/compensation/outliers.hpp"
#include "probecomp/fitting/adaptive.hpp"
#include "probecomp/fitting/offset.hpp"
#include "probecomp/registration/routes.hpp"

namespace probecomp::compensation {

enum class Method { Cad, Conventional };
[[nodiscard]] const char* to_string(Method m);

enum class PointStatus {
  Ok,
  Outlier,     // the fitted surface's residual is beyond the outlier bound: compensated, not trusted
  Edge,        // the tip touched a face's edge (foot point on a trim or domain edge): offset towards that edge
  FewPoints,   // its face had too few points for a fit: offset along the registered nominal normal
  NotOnModel,  // no closest point on the model (or not a finite point): nothing computed, fields empty
  Failed,      // the projection on the fitted surface failed: nothing computed, fields empty
};
[[nodiscard]] const char* to_string(PointStatus s);

struct CompensatedPoint {
  PointStatus status = PointStatus::NotOnModel;
  Point3 contact = Point3::Zero();   // compensated contact point, machine frame
  Vector3 normal = Vector3::Zero();  // outward unit normal used for the offset
  double deviation = 0.0;            // signed distance from the registered nominal, + outside the material, mm
  int face = -1;                     // index of the CAD face (cad::Face::index)
  [[nodiscard]] bool computed() const { return status != PointStatus::NotOnModel && status != PointStatus::Failed; }
};

struct FaceReport {
  int face = -1;          // cad::Face::index
  int points = 0;         // points assigned to the face by their correspondence
  bool fitted = false;    // else its points were offset along the nominal normal (too few for a fit)
  int outward = 1;        // of the fitted surface, as cad::Face::outward
  cad::MaterialSource material = cad::MaterialSource::NoPoints;
  fitting::AdaptiveFitResult::Status fit_status = fitting::AdaptiveFitResult::Status::NotDone;
  int control_points = 0;
  int rounds = 0;          // knot insertions
  double rms = 0.0;        // of the fit's residuals, mm
  double max_residual = 0.0;
  double noise_sigma = 0.0;
  int outliers = 0;
  std::optional<nurbs::Surface> centre_surface;  // the fitted probe-centre surface, machine frame (when fitted)
};

struct StageSeconds {
  double material_side = 0.0, offset = 0.0, registration = 0.0, fitting = 0.0, compensation = 0.0, deviation = 0.0;
};

struct CompensationResult {
  Method method = Method::Cad;
  registration::RegistrationResult registration;  // transform: CAD to machine
  std::vector<cad::MaterialSide> material;
  std::vector<CompensatedPoint> points;  // one per input point, in order
  std::vector<FaceReport> faces;         // faces that hold points, by index
  StageSeconds seconds;
  [[nodiscard]] int count(PointStatus s) const;
};

struct CompensateOptions {
  Method method = Method::Cad;
  double probe_radius = 0.0;  // mm, > 0
  registration::RegistrationOptions registration;
  fitting::OffsetOptions offset;
  // The face fit. Three departures from the fitter's defaults, measured on the cylinder studies (10 000 points,
  // a local sine of 1.5 mm peak, σ = 40 µm) and the free-form case:
  //  - smoothness 1e-3 (not 1e-6): refinement leaves thin spans at the data's edges holding few points, which
  //    a weak smoothness lets swing with the noise (largest error 0.49 mm at 1e-6, 0.043 mm at 1e-3);
  //  - one proximal step (not up to 200): with that smoothness the iteration creeps on for hundreds of steps
  //    through directions the data barely fix, and its end depends on the cap; one step is the Tikhonov fit
  //    towards the start, a quarter of the time and smoother (free-form case: std 1.25 µm, largest 6.4 µm,
  //    against 1.40 and 6.9 µm after 200 steps);
  //  - no parameter correction: projecting the points on the fit lets those at the data's corners slide out
  //    into the ill-determined spans (largest error 0.36 mm with two corrections at σ = 10 µm, 0.017 mm
  //    without), and the registration's (u, v) serve as well elsewhere at half the fitting time.
  fitting::AdaptiveFitOptions fit{.fit = {.smoothness = 1e-3, .max_iterations = 1}, .parameter_corrections = 0};
  // A face is fitted when it holds at least this many points per control point of its offset surface; fewer
  // cannot average the noise out (its points fall back to the nominal normal).
  double min_points_per_control_point = 2.0;
  // Gross outliers found before the fit, each against a quadratic through its neighbours (compensation/outliers.hpp).
  LocalOutlierOptions gross_outliers;
  // Residuals beyond this many noise sigmas (of the face's fit) mark outliers: left out of the refit. Five
  // sigmas: a Gaussian exceeds it once in 1.7 million points.
  double outlier_sigmas = 5.0;
  // ... and beyond this (mm): on noise-free data the fit's own model error (a few tenths of a micrometre where
  // refinement stopped) must not read as outliers. 2 µm is below any gross error and above that model error.
  double min_outlier_residual = 0.002;
  // Points whose first closest point on the model is farther than this fraction of the model's size are
  // "nowhere near the model" (wrong file, frame or unit): the run stops with an error.
  double max_initial_distance_fraction = 0.1;
  // Called at the start of each stage with the fraction of the run done (0–1); may be empty.
  std::function<void(const std::string& stage, double fraction)> progress;
};

// Throws std::invalid_argument with a one-line cause for input the method cannot use: a non-positive radius,
// no points, the conventional method without approach normals, points nowhere near the model, a failed
// registration.
[[nodiscard]] CompensationResult compensate(const cad::Model& model, std::span<const Point3> raw_centres,
                                            std::optional<std::span<const Vector3>> approach_normals,
                                            const CompensateOptions& options);

// The fitted part surfaces (contact surfaces, machine frame) of a CAD-method result: each fitted centre surface
// offset by the probe radius into the material. For `probecomp fit`.
[[nodiscard]] std::vector<nurbs::Surface> fitted_part_surfaces(const CompensationResult& result, double probe_radius,
                                                               const fitting::OffsetOptions& options = {});

}  // namespace probecomp::compensation
