#pragma once
// The whole method (DESIGN.md §2) on a CAD model and raw probe-centre points, as named steps:
//   load        cad::Model::load (STEP/IGES) and io::read_points (CSV, DMIS, QIF): not here, files are cad/'s and io/'s
//   prepare     each face's material side, every face offset by r towards the probe, the offset model indexed
//   register    the raw centres registered to the offset model (robust ICP)
//   fit         points assigned to faces by their correspondences; each face's centre surface fitted through its
//               points (adaptive, outliers flagged and left out)
//   compensate  each point smoothed onto its fit and moved by r along the fitted normal into the material; its
//               deviation from the registered nominal
//   write       results/files.hpp (CSV, DMIS, QIF), results/statistics.hpp (JSON statistics)
// compensate() composes them; the conventional method (c − r·(i,j,k), registered to the nominal) has one step.
// Every input point comes back, in order, with a status saying whether it can be trusted.

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "probecomp/cad/analytic.hpp"
#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/material_side.hpp"
#include "probecomp/cad/model.hpp"
#include "probecomp/cad/offset_model.hpp"
#include "probecomp/compensation/outliers.hpp"
#include "probecomp/compensation/qualified_radii.hpp"
#include "probecomp/fitting/adaptive.hpp"
#include "probecomp/fitting/offset.hpp"
#include "probecomp/geometry/tip_radii.hpp"
#include "probecomp/probe/qualification.hpp"
#include "probecomp/registration/icp.hpp"

namespace probecomp::compensation {

enum class Method { Cad, Conventional };
[[nodiscard]] const char* to_string(Method m);

enum class PointStatus {
  Ok,
  Outlier,     // the fitted surface's residual is beyond the outlier bound: compensated, not trusted
  Edge,        // the tip touched a face's edge (foot point on a trim or domain edge): offset towards that edge
  DoubleContact,  // the tip sat against two faces at once (a concave corner, a fillet tighter than r): which one
                  // stopped it is unknown; not fitted, offset towards the nominal part's point nearest to it
  FewPoints,   // its face had too few points for a fit: offset along the registered nominal normal
  NotOnModel,  // no closest point on the model (or not a finite point): nothing computed, fields empty
  Failed,      // the projection on the fitted surface failed: nothing computed, fields empty
};
[[nodiscard]] const char* to_string(PointStatus s);
// Every status, in the order above (for counts and reports).
inline constexpr PointStatus kPointStatuses[] = {
    PointStatus::Ok,        PointStatus::Outlier,    PointStatus::Edge,  PointStatus::DoubleContact,
    PointStatus::FewPoints, PointStatus::NotOnModel, PointStatus::Failed};

struct CompensatedPoint {
  PointStatus status = PointStatus::NotOnModel;
  Point3 contact = Point3::Zero();   // compensated contact point, machine frame
  Vector3 normal = Vector3::Zero();  // outward unit normal used for the offset
  double deviation = 0.0;            // signed distance from the registered nominal, + outside the material, mm
  // Standard uncertainty (k = 1, mm) of the contact point along its normal: the fit's share σ̂·√(variance factor)
  // (its hat-matrix diagonal and noise estimate), its estimated bias (AdaptiveFitResult::misfit) and the
  // registration's share (registration::normal_variance times its residual variance) in quadrature; for an Outlier
  // or a point the last fit did not use, its residual from the fit too (the reading and the fit disagree by that
  // much, and which is right is not known); next to points left out, r(1 − cos θ) for the fit's normal's
  // disagreement θ with the centres around it (normal_support.hpp). Where no fit stands behind the point (few
  // points, an edge) the fit's share is the registration's residual scale: the raw centre's whole scatter about the
  // model; past a fitted face's edge also how far that face's fit puts the part from the nominal at the rim (the
  // contact is on the nominal rim). NaN where nothing was computed.
  double uncertainty = std::numeric_limits<double>::quiet_NaN();
  int face = -1;                     // index of the CAD face (cad::Face::index)
  double radius = 0.0;               // the tip radius the point was taken (and compensated) with, mm
  [[nodiscard]] bool computed() const { return status != PointStatus::NotOnModel && status != PointStatus::Failed; }
};

struct FaceReport {
  int face = -1;          // cad::Face::index
  int points = 0;         // points assigned to the face by their correspondence
  bool fitted = false;    // else its points were offset along the nominal normal (too few for a fit)
  // Too few points for its NURBS fit, but fitted as the plane, cylinder, sphere, cone or torus it is: its points are
  // offset along that element's normal (status ok).
  std::optional<cad::ElementaryKind> fitted_as;
  int outward = 1;        // of the fitted surface, as cad::Face::outward
  cad::MaterialSource material = cad::MaterialSource::File;
  fitting::AdaptiveFitResult::Status fit_status = fitting::AdaptiveFitResult::Status::NotDone;
  std::string stop_reason;  // one line: why the face's fit stopped where it did, or why it was not fitted
  int fits = 0;             // fits made (the first, and refits after outliers were left out or taken back)
  int control_points = 0;
  int rounds = 0;           // knot insertion rounds over all of the face's fits
  double rms = 0.0;         // of the last fit's residuals, mm
  double max_residual = 0.0;
  double noise_sigma = 0.0;
  double effective_dof = 0.0;     // tr H of the fit: its effective number of parameters (per coordinate)
  double log10_smoothing = 0.0;   // the fit's smoothing λ, log10, relative to the data's weight (penalized.hpp)
  double mean_uncertainty = 0.0;  // mean u over the face's computed points, mm
  int counts[std::size(kPointStatuses)] = {};  // the face's points by status, in the order of kPointStatuses
  // Points at the position of an earlier point of the face (within 1e-9 mm: a reading recorded twice): fitted once
  // as one observation, each still compensated and reported.
  int repeated = 0;
  std::optional<nurbs::Surface> centre_surface;  // the fitted probe-centre surface, machine frame (when fitted)
  [[nodiscard]] int count(PointStatus s) const { return counts[static_cast<int>(s)]; }
};

// --- prepare ---

struct PrepareOptions {
  fitting::OffsetOptions offset;
  // The first guess of the transform CAD → machine, for the material side's votes (usually the identity).
  geometry::RigidTransform initial = geometry::RigidTransform::Identity();
  // Every face whose side the raw centres decided (MaterialSource::Data) turned to the other side: the second
  // hypothesis register_material_sides weighs (issue 49).
  bool flip_data_sides = false;
  // And these faces (positions) turned, when the raw centres decided them: after registration their centres lay
  // inside the material (prepare_and_register).
  std::vector<int> flip_faces{};
};

// The model the points are registered to. Movable, not copyable: the locator refers to the offset model, and
// both live on the heap so that a move keeps that reference valid.
struct PreparedModel {
  // The tip radius of each raw centre. The model is offset by the smallest (probe_radius): larger tips' centres
  // are registered that much farther out, and moved in by the difference before a face is fitted, so that each
  // face's fit is of the smallest tip's centre surface whatever mix of tips measured it.
  geometry::TipRadii radii;
  double probe_radius = 0.0;  // radii.smallest(): the offset model's and the fitted centre surfaces' radius
  // The input model, each face's `outward` its decided material side (held by pointer, as the offset model is,
  // so that the locators over them stay valid when the prepared model moves).
  std::unique_ptr<const cad::Model> nominal;
  std::vector<cad::MaterialSide> material;   // per face of `nominal`: what decided it
  std::unique_ptr<const cad::OffsetModel> offset;    // every face of `nominal` offset by +r
  std::unique_ptr<const cad::ModelLocator> locator;  // closest points on offset->model
  // Closest points on the nominal model: where a tip of radius r whose centre is known touches the part.
  std::unique_ptr<const cad::ModelLocator> nominal_locator;
  double seconds = 0.0;
};

// Throws InputError for a radius that is not positive, per-point radii that do not match the points in number, or a
// model without faces.
[[nodiscard]] PreparedModel prepare_model(const cad::Model& model, const geometry::TipRadii& radii,
                                          std::span<const Point3> raw_centres,
                                          std::optional<std::span<const Vector3>> approach_normals,
                                          const PrepareOptions& options = {});

// --- register ---

struct RegisterOptions {
  registration::RegistrationOptions icp;
  // Points whose first closest point on the model is farther than this fraction of the model's size are
  // "nowhere near the model" (wrong file, frame or unit): the run stops with an InputError.
  double max_initial_distance_fraction = 0.1;
  // A registration that stays doubtful after the coarse alignment (registration/credibility.hpp) is refused with a
  // RegistrationError unless this is set: the checks cannot tell a wrong pose from a part that deviates from its
  // model by about r, and only the user knows which it is. Accepted, it comes back with a warning in its notes.
  bool accept_doubtful = false;
  // The faces of the specification's datum features (as `probecomp info` lists them). A registration that stays
  // doubtful on all the points is tried on theirs alone (registration::register_by_faces), as a drawing locates its
  // part: the other faces may then be as far off as the part deviates. Kept when credible on those points and they
  // fix all six motions; the result's notes say so. Empty: no such fallback.
  std::vector<int> datum_faces{};
};

// The raw centres registered to the prepared offset model. Throws InputError when the points are nowhere near
// the model and RegistrationError when ICP could not run (too few points, numerical failure); a registration
// that ran but did not converge comes back with its status and stop reason.
[[nodiscard]] registration::RegistrationResult register_centres(const PreparedModel& prepared,
                                                                std::span<const Point3> raw_centres,
                                                                const RegisterOptions& options = {});

// Prepared and registered. Where the raw centres alone decided a face's material side (no approach normals, no
// closed solid: MaterialSource::Data), that vote is only as good as the part's first pose: a panel 1–2° off its CAD
// frame leaves its centres on both sides of the nominal. So the registration is made to both sides and the one
// whose residuals' robust scale is clearly the smaller is kept (its registration's notes say so); when neither is,
// a RegistrationError says that the side cannot be told from these data. Else prepare_model, then register_centres.
struct PreparedRegistration {
  PreparedModel prepared;
  registration::RegistrationResult registration;
};
[[nodiscard]] PreparedRegistration prepare_and_register(const cad::Model& model, const geometry::TipRadii& radii,
                                                        std::span<const Point3> raw_centres,
                                                        std::optional<std::span<const Vector3>> approach_normals,
                                                        const PrepareOptions& prepare, const RegisterOptions& options);

// --- fit ---

struct FitOptions {
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
  // (Where the points lie along lines, fit_faces chooses the smoothing by leaving out a knot span's points at once:
  // fitting::CrossValidation::LeaveSpanOut.)
  //  - the penalty's weight over the face from the local balance of data and penalty (fitting::AdaptiveFitOptions::
  //    SpatialPenalty::Balance; fit_faces keeps it away from gross errors): over the shape suite's 94 faces, std
  //    median 1.192 -> 1.054 µm, faces with a region whose ±2u coverage is under 88 % 27 -> 23 (docs/accuracy.md).
  fitting::AdaptiveFitOptions surface{
      .fit = {}, .parameter_corrections = 0, .spatial_penalty = fitting::AdaptiveFitOptions::SpatialPenalty::Balance};
  // A face is fitted when it holds at least this many points per control point of its offset surface; fewer
  // cannot average the noise out (its points fall back to the nominal normal).
  double min_points_per_control_point = 2.0;
  // Outliers, decided against the face's fit (compensation/outliers.hpp): flagged, left out of the refit, still
  // compensated on the fit.
  OutlierTest outliers;
  // On noisy scan lines, also fit with the energy's anisotropy chosen (fitting::PenalizedFitOptions::anisotropic)
  // and keep that fit unless it predicts whole lines left out worse than the isotropic one by more than two standard
  // errors (fit_faces). Off: the isotropic energy there, as on exact data.
  bool anisotropy_on_scan_lines = true;
};

// One face's points and its fit.
// A face with too few points for its NURBS net, fitted as the elementary surface it is (its centres' own
// least-squares element, fitting/elements.hpp; the tip's centres lie on an element of the same kind and axis), in
// the machine frame.
struct ElementFaceFit {
  cad::ElementaryKind kind = cad::ElementaryKind::Plane;
  Point3 point = Point3::Zero();    // plane: the centroid; cylinder, cone: an axis point; sphere, torus: the centre
  Vector3 axis = Vector3::Zero();   // plane: its normal; cylinder, cone, torus: the axis (unit)
  double radius = 0.0;              // the centres' cylinder's or sphere's, the cone's at `point`, the torus's major
  double half_angle = 0.0;          // cone: radians, its radius growing along `axis` (fitting::ConeFit)
  double minor_radius = 0.0;        // torus: the tube's, mm
  double rms = 0.0;                 // of the points used, orthogonal to the element, mm
  int used = 0;                     // points used (the rest left out as outliers)
  int parameters = 0;               // fitted: 3 plane, 4 sphere, 5 cylinder, 6 cone, 7 torus, less `held`
  int held = 0;                     // cone, torus: combinations of its parameters held at the nominal's, which the
                                    // points fix too poorly (fitting::HoldPoorlyFixed)
  // The noise along the normal its rows take as u, mm: pooled over the part's element faces (the NURBS-fitted faces'
  // median where that pool has under 50 degrees of freedom) unless its own residuals show more
  // (compensation/element_faces.hpp); infinity where nothing tells it.
  double noise = std::numeric_limits<double>::infinity();
};

struct FaceFit {
  int face = -1;                                   // position in the prepared model's faces
  std::vector<std::uint32_t> members;              // input indices of the points fitted on it, ascending (4 B each)
  std::vector<fitting::SurfaceParameter> params;   // theirs: on the fit when fitted, else the registration's
  std::vector<char> trusted;                       // per member: 0 where left out as an outlier
  std::vector<char> in_last_fit;                   // per member: 1 where the last fit used it
  // Per member, when points were left out of the fit or lie along lines: the angle (radians) between the fit's
  // normal and what the centres around it show (compensation/normal_support.hpp); NaN where it could not be told.
  // Else empty.
  std::vector<double> normal_angle;
  // The points lie along lines (a scanning probe's), and each on a line was checked so (normal_support.hpp).
  bool normal_checked_along_lines = false;
  // Then, per member (else empty; compensation/scan_lines.hpp): the fit's bias along its line, from the residuals
  // around it, mm; and the angle its normal may be off across the lines, where no data show it, radians.
  std::vector<double> line_bias, normal_unseen_angle;
  double line_spacing = 0.0;  // then, the lines' spacing, mm
  std::optional<fitting::AdaptiveFitResult> fit;   // when the face was fitted
  std::optional<ElementFaceFit> element;           // when it was too sparse for that, but fitted as its element
  FaceReport report;
};

struct FitResult {
  // Every face that holds points, by position. Points whose correspondence is on a face's edge, or whose tip
  // touched a second face, count in its report but are never fitted.
  std::vector<FaceFit> faces;
  // Per input point: the second face (position) its tip touched within the contact tolerance, or −1.
  std::vector<int> second_contact;
  // The centres' noise along the normal over the part, mm: the faces fitted as their elements pooled, else (too few
  // degrees of freedom there) the NURBS-fitted faces' median estimate (compensation/element_faces.hpp); infinity
  // when no face was fitted.
  double noise_sigma = std::numeric_limits<double>::infinity();
  double seconds = 0.0;
};

// Called with the fraction of the step done (0–1); may be empty.
using StepProgress = std::function<void(double fraction)>;

// Per raw centre: the second face (position) the tip also touched, or −1. A second face counts when the registered
// centre is as near it as to its own face (r plus the deviation there) within the contact tolerance (4 σ of the
// registration's residuals, 1 µm to 2 % of r), and the directions from the two feet to the centre are over 15°
// apart: a concave corner, not a smooth continuation. Edge points
// (whose foot is already past their face) and points without a correspondence have none.
[[nodiscard]] std::vector<int> second_contacts(const PreparedModel& prepared, std::span<const Point3> raw_centres,
                                               const registration::RegistrationResult& registration);

[[nodiscard]] FitResult fit_faces(const PreparedModel& prepared, std::span<const Point3> raw_centres,
                                  const registration::RegistrationResult& registration, const FitOptions& options = {},
                                  const StepProgress& progress = {});

// --- compensate ---

// Each point smoothed onto its face's fit and moved by r along the fitted normal into the material (or along the
// registered nominal normal where the face was not fitted, or towards the edge for edge points), and its signed
// deviation from the registered nominal. One result per input point, in order. `warnings`, when given, receives
// what the rows' statuses and u alone do not say (fitted normals turned far from the nominal part's).
[[nodiscard]] std::vector<CompensatedPoint> compensate_points(const PreparedModel& prepared,
                                                              std::span<const Point3> raw_centres,
                                                              const registration::RegistrationResult& registration,
                                                              const FitResult& fits,
                                                              std::vector<std::string>* warnings = nullptr);

// --- the whole method ---

// Seconds per step of compensate(); the command line adds reading and writing.
struct Timings {
  double prepare = 0.0, registration = 0.0, fitting = 0.0, compensation = 0.0;
  [[nodiscard]] double total() const { return prepare + registration + fitting + compensation; }
};

// Counts by status, and the deviations of the trusted (ok) points.
struct Statistics {
  int total = 0;
  int counts[std::size(kPointStatuses)] = {};  // by PointStatus, in the order of kPointStatuses
  double deviation_mean = 0.0, deviation_std = 0.0, deviation_min = 0.0, deviation_max = 0.0;  // mm, ok points
  [[nodiscard]] int count(PointStatus s) const { return counts[static_cast<int>(s)]; }
};
[[nodiscard]] Statistics statistics(std::span<const CompensatedPoint> points);

struct CompensationResult {
  Method method = Method::Cad;
  registration::RegistrationResult registration;  // transform: CAD to machine
  std::vector<cad::MaterialSide> material;        // per face of the model (CAD method)
  std::vector<CompensatedPoint> points;           // one per input point, in order
  std::vector<FaceReport> faces;                  // faces that hold points, by index
  // The radius the faces' centre surfaces are for: the smallest tip's (PreparedModel::probe_radius), mm.
  // With CompensateOptions::qualification: how each stylus's points took their radii (empty otherwise).
  std::vector<StylusRadii> styli{};
  // Each point's radius came from its stylus's qualification, by direction: CompensatedPoint::radius is that
  // effective radius.
  [[nodiscard]] bool qualified_radii() const { return !styli.empty(); }
  double centre_radius = 0.0;
  Statistics statistics;
  Timings seconds;
  // What the user should know to read the result right, one line each (the command line prints them on standard
  // error and in --json): never a silent change to what was asked.
  std::vector<std::string> warnings;
  [[nodiscard]] int count(PointStatus s) const { return statistics.count(s); }
};

struct CompensateOptions {
  Method method = Method::Cad;
  double probe_radius = 0.0;  // mm, > 0
  // Per point (mm, > 0), when the points were taken with tips of several radii; empty: probe_radius for every point.
  std::vector<double> probe_radii{};
  // Styli qualified on a reference sphere (probe/qualification.hpp): each point's radius is its stylus's effective
  // radius in the direction it was touched from (−(i,j,k); without approach normals, against the normal a first run
  // fits there), and that radius's uncertainty joins its u. Styli it does not hold take probe_radii (NaN: none) or
  // probe_radius (0: none), as compensation/qualified_radii.hpp says. Null: probe_radius / probe_radii as they are.
  const probe::Qualification* qualification = nullptr;
  std::vector<std::string> styli{};  // each point's stylus, for the qualification; empty: the one it holds
  registration::RegistrationOptions registration;
  double max_initial_distance_fraction = 0.1;  // as RegisterOptions
  bool accept_doubtful_registration = false;   // as RegisterOptions::accept_doubtful
  std::vector<int> datum_faces{};              // as RegisterOptions::datum_faces
  fitting::OffsetOptions offset;
  FitOptions fit;
  // Called at the start of each step with the fraction of the run done (0–1); may be empty.
  std::function<void(const std::string& step, double fraction)> progress;
};

// Throws InputError for input the method cannot use (a non-positive radius, no points, the conventional method
// without approach normals, points nowhere near the model) and RegistrationError for a registration that could
// not run.
[[nodiscard]] CompensationResult compensate(const cad::Model& model, std::span<const Point3> raw_centres,
                                            std::optional<std::span<const Vector3>> approach_normals,
                                            const CompensateOptions& options);

// The fitted part surfaces (contact surfaces, machine frame) of a CAD-method result: each fitted centre surface
// offset by its radius (result.centre_radius) into the material. Throws FitError where a fitted surface has no
// normal.
[[nodiscard]] std::vector<nurbs::Surface> fitted_part_surfaces(const CompensationResult& result,
                                                               const fitting::OffsetOptions& options = {});

}  // namespace probecomp::compensation
