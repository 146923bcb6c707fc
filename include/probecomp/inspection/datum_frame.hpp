#pragma once
// Datum reference frames (ISO 5459, ASME Y14.5; DESIGN.md §7) set up on the compensated contact points. A datum is
// the nominal shape of its faces fitted to the trusted points on them, a cylinder's or sphere's size free (a hole's
// datum is its axis, whatever its measured radius): least squares, or tangent (every point on the material side,
// the deepest as shallow as can be: a plane resting on the high points, a hole's largest inscribed cylinder, a
// pin's smallest circumscribed one). Datums are taken in order, each moving the part
// only in the motions the ones before it left free: the primary fixes what its feature can (a plane: one
// translation and two rotations; a cylinder: two translations and two rotations), the secondary then the tertiary
// fix what remains. Which motions a feature fixes is read from its points, as registration/constraints.hpp does for
// the whole part, so the paper's 3-2-1 (three points on a plane, two on a second, one on a third) is a frame too.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "probecomp/cad/model.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/geometry/rigid.hpp"

namespace probecomp::inspection {

enum class DatumFit { LeastSquares, Tangent };
[[nodiscard]] const char* to_string(DatumFit f);  // "least-squares", "tangent"

// A point or line datum target (A1): the datum simulator touches the part there. A line is the segment of its
// length either side of `point` along `direction` (cad::DatumTarget: the file's place may be its start or middle).
struct Target {
  std::string label;                    // "A1"
  Point3 point = Point3::Zero();        // on the nominal, mm
  Vector3 direction = Vector3::Zero();  // a line's (unit); zero for a point
  double length = 0.0;                  // a line's, mm
  [[nodiscard]] bool line() const { return direction != Vector3::Zero(); }
  // How far `x` (CAD frame) is from it, mm.
  [[nodiscard]] double distance(const Point3& x) const;
};

// A trusted point within this distance of a target (in the CAD frame, the part placed by the registration) is a
// touch of it: a touch programmed at the target lands within the registration's misfit of it (micrometres), and a
// face's other points, 10–40 of them, lie millimetres apart.
inline constexpr double kTargetReach = 1.0;

struct DatumSpec {
  std::string name;
  std::vector<int> faces;  // model face indices, as `probecomp info` lists them
  DatumFit fit = DatumFit::LeastSquares;
  // Datum targets: the datum is fitted to the trusted points on `faces` within kTargetReach of one of them, and is
  // not set up while a target has none.
  std::vector<Target> targets{};
};

struct DatumResult {
  std::string name;
  std::vector<int> faces;
  DatumFit fit = DatumFit::LeastSquares;
  int points = 0;    // trusted points fitted
  int fixes = 0;     // motions it fixed, of those the datums before it left free
  double rms = 0.0;  // of its points' distances from the fitted datum, mm
  std::optional<double> size_change;  // cylinder or sphere: fitted radius minus nominal, mm
  // Its direction on the nominal (CAD frame, unit): a plane's outward normal, a cylinder's or cone's axis (as the
  // file orients it), when all its faces share it; none for a sphere, a free-form face or faces that differ. QIF's
  // DatumPrecedence alignment gives it.
  std::optional<Vector3> axis;
};

// Motions are scaled twists δ = (L·ω, v) about `centre` (registration::motion_about), L = `length`.
struct DatumFrame {
  enum class Status { OK, NotDone };
  Status status = Status::NotDone;
  std::string reason;  // NotDone: why, one line naming the datum
  // CAD to machine, as the registration's transform, with the part located by its datums; motions no datum fixes
  // are those of the registration.
  geometry::RigidTransform transform = geometry::RigidTransform::Identity();
  std::vector<DatumResult> datums;  // in the frame's order
  Point3 centre = Point3::Zero();
  double length = 1.0;
  Eigen::Matrix<double, 6, Eigen::Dynamic> free_basis;  // orthonormal columns: the motions no datum fixes
  // Of the located part's motion, from the datum points' standard uncertainties (first order): its share of a
  // deviation's variance at x with normal n is J·covariance·Jᵀ, J = ((x − c) × n / L, n) (registration::normal_variance).
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();

  [[nodiscard]] bool ok() const { return status == Status::OK; }
  [[nodiscard]] int fixed() const { return ok() ? 6 - static_cast<int>(free_basis.cols()) : 0; }  // motions fixed
};

// The frame of `datums` (primary first) on `result`'s ok points. NotDone, with the reason, when a datum has no
// trusted point, fixes no motion the ones before it left, or its fit does not converge.
[[nodiscard]] DatumFrame establish_frame(const std::vector<DatumSpec>& datums, const cad::Model& nominal,
                                         const compensation::CompensationResult& result);

// `result` put in `frame`: its transform the frame's, and each computed point's deviation its signed distance (+ outside
// the material) from its own face of the nominal model so placed (the face it was compensated on), its u with the frame's own
// share added (DatumFrame::covariance), and the statistics of them.
// The output's `alignment`.
[[nodiscard]] compensation::CompensationResult aligned(const compensation::CompensationResult& result,
                                                       const DatumFrame& frame, const cad::Model& nominal);

}  // namespace probecomp::inspection
