#pragma once
// Rigid registration of measured points to a CAD model by ICP (DESIGN.md §2 step 3; Besl and McKay 1992 for
// point-to-point, Chen and Medioni 1992 for point-to-plane). Each iteration: the exact closest point on the
// model for every point (all faces, inside their trims; parallel, deterministic), robust weights from the
// residuals' own scale, then one estimation step:
//   PointToPoint  the closed-form weighted least-squares rotation and translation (SVD; the paper's method);
//   PointToPlane  one Gauss–Newton step on Σ w (n·(x − q))², the default: it converges in a few iterations
//                 where point-to-point slides slowly along flat or gently curved surfaces.
// Motions the data cannot fix (see constraints.hpp) are held at the starting transform.

#include <algorithm>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "probecomp/cad/locator.hpp"
#include "probecomp/registration/constraints.hpp"
#include "probecomp/geometry/rigid.hpp"
#include "probecomp/registration/robust.hpp"

namespace probecomp::registration {

enum class Metric { PointToPlane, PointToPoint };
[[nodiscard]] const char* to_string(Metric metric);

struct Criteria {
  int max_iterations = 100;
  // Converged when an iteration's update moves no measured point by more than this (mm). At 1e-9 mm the
  // remaining error of a Gauss–Newton step is far below anything a CMM resolves.
  double motion_tolerance = 1e-9;
  // Or when it moves them by less than this fraction of the estimate's own uncertainty, σ̂/√(points used):
  // iterating further changes nothing the data can tell apart (with σ̂ = 5 µm and 10 000 points: 5e-11 mm).
  double relative_motion_tolerance = 0.1;
};

struct RegistrationOptions {
  Metric metric = Metric::PointToPlane;
  RobustKernel robust;
  Criteria criteria;
  geometry::RigidTransform initial = geometry::RigidTransform::Identity();  // CAD to machine: where the part is thought to be
  // Correspondences farther than this (mm) are not used; the default uses all (the robust weights cope).
  double max_distance = std::numeric_limits<double>::infinity();
  // When given (one per point): only the points marked nonzero enter the estimate, the part located by them alone
  // (its datum features' points: registration/routes.hpp). The others get their correspondences at the final
  // transform and no weight. Must outlive the call.
  std::span<const std::uint8_t> located_by{};
};

enum class Status {
  Converged,      // the last update moved no point more than the motion tolerance
  MaxIterations,  // stopped at the iteration limit; the transform is the last estimate
  TooFewPoints,   // fewer usable correspondences than the metric needs (3 for point-to-point, 6 for plane)
  NumericalError, // a non-finite value in the estimate
};
[[nodiscard]] const char* to_string(Status status);

// One measured point's correspondence on the model at the final transform.
// Its members ordered so that the small ones share a word: 40 bytes (a million points: 40 MB).
struct PointMatch {
  double u = 0.0, v = 0.0;
  double distance = 0.0;      // signed, + on the model's outward side, mm (in CAD frame = machine frame)
  double weight = 0.0;        // robust weight in the last step; 0 when not used
  int face = -1;
  nurbs::ClosestPointStatus status = nurbs::ClosestPointStatus::NotConverged;
  bool on_edge = false;       // the foot point is on a face's trim or domain edge: the point lies beyond it
  bool inlier = false;        // used, and |distance| ≤ kOutlierSigmas · scale

  [[nodiscard]] bool ok() const {
    return status == nurbs::ClosestPointStatus::Converged || status == nurbs::ClosestPointStatus::OnBoundary;
  }
};
static_assert(sizeof(PointMatch) == 40);

struct RegistrationResult {
  Status status = Status::TooFewPoints;
  std::string stop_reason;                              // one line, for people
  geometry::RigidTransform transform = geometry::RigidTransform::Identity(); // CAD to machine
  double rms = 0.0;            // RMS distance of the inliers, mm
  double scale = 0.0;          // robust scale σ̂ of the residuals at the end, mm
  int iterations = 0;           // on all points
  int searches = 0;             // closest-point searches of all points; the other iterations slide (see icp_state.hpp)
  int coarse_iterations = 0;    // on the subset first (large point sets; see kCoarseStagePoints)
  int starts = 1;               // starting transforms tried (more than one: a coarse alignment, credibility.hpp)
  int left_out = 0;             // points the fits flagged that a second registration left out (0: registered once)
  int used = 0;                // correspondences used in the last step (not on an edge, within max_distance)
  int inliers = 0;
  Constraints constraints;     // the motions the data fix; the free ones were held at the start
  std::vector<PointMatch> matches;  // one per input point, in input order
  std::vector<std::string> notes;   // what a caller should pass on to the user (e.g. how a coarse alignment went)
  // Empty: every usable point located the part. Else one per point, nonzero for those that did (its datum features'
  // points; RegistrationOptions::located_by): the credibility checks and a second registration keep to them.
  std::vector<std::uint8_t> located_by;

  // How many points located the part: those marked in located_by, or all of them.
  [[nodiscard]] std::size_t locating_points() const {
    if (located_by.empty()) return matches.size();
    return static_cast<std::size_t>(std::count_if(located_by.begin(), located_by.end(), [](std::uint8_t f) { return f != 0; }));
  }

  [[nodiscard]] bool converged() const { return status == Status::Converged; }
};

// A spread subset of a quarter of the points, at most this many, is registered first: closest points far from the
// model are the costly ones, and the subset takes the whole set close for a fraction of the cost...
inline constexpr std::size_t kCoarseStagePoints = 4096;
// ... when it holds at least this many (4 096 points and more; 10 000 points: 3 searches of all of them instead of 6).
inline constexpr std::size_t kMinCoarseStagePoints = 1024;

// Registers `machine_points` (machine frame) to the model behind `model` (CAD frame). The result's transform
// maps CAD to machine. Points on an edge, not found, or not finite are reported, never used. `offsets`, when given
// (one per point, mm), move each point's target that far out along the model's outward normal: a probe centre of a
// tip larger than the one the model is offset for (geometry/tip_radii.hpp). Its match's distance is then from that
// target.
[[nodiscard]] RegistrationResult register_points(const cad::ModelLocator& model, std::span<const Point3> machine_points,
                                                 const RegistrationOptions& options = {},
                                                 std::span<const double> offsets = {});

// Each point's correspondence on the model at `transform` (CAD to machine), as register_points reports them, the
// model not moved. `offsets` as for register_points.
[[nodiscard]] std::vector<PointMatch> matches_at(const cad::ModelLocator& model, std::span<const Point3> machine_points,
                                                 const geometry::RigidTransform& transform,
                                                 std::span<const double> offsets = {});

}  // namespace probecomp::registration
