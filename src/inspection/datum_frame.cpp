#include "probecomp/inspection/datum_frame.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>

#include <Eigen/Eigenvalues>

#include "probecomp/cad/analytic.hpp"
#include "probecomp/cad/locator.hpp"
#include "probecomp/registration/constraints.hpp"
#include "restricted_fit.hpp"

namespace probecomp::inspection {

namespace {

// Gauss–Newton stops when an update moves no point by more than this (mm), far below what a CMM resolves; the
// points start within micrometres of their faces (the registration put them there), so a few steps suffice.
constexpr double kMotionTolerance = 1e-10;
constexpr int kMaxIterations = 50;
constexpr int kMaxHalvings = 30;

// The rows of H's eigen-decomposition the points fix: eigenvalues above registration::kUnconstrainedRatio of the
// largest, as the registration judges the whole part's motions.
void split_directions(const Eigen::MatrixXd& A, RestrictedFit& fit) {
  const Eigen::Index k = A.cols();
  fit.fixed.resize(k, 0);
  fit.free.resize(k, 0);
  fit.lambda.resize(0);
  if (k == 0) return;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A.transpose() * A);
  const double largest = eig.eigenvalues().maxCoeff();
  std::vector<Eigen::Index> fixed, free;
  for (Eigen::Index i = 0; i < k; ++i) {
    (largest > 0.0 && eig.eigenvalues()(i) > registration::kUnconstrainedRatio * largest ? fixed : free).push_back(i);
  }
  fit.fixed.resize(k, static_cast<Eigen::Index>(fixed.size()));
  fit.lambda.resize(static_cast<Eigen::Index>(fixed.size()));
  for (std::size_t j = 0; j < fixed.size(); ++j) {
    fit.fixed.col(static_cast<Eigen::Index>(j)) = eig.eigenvectors().col(fixed[j]);
    fit.lambda(static_cast<Eigen::Index>(j)) = eig.eigenvalues()(fixed[j]);
  }
  fit.free.resize(k, static_cast<Eigen::Index>(free.size()));
  for (std::size_t j = 0; j < free.size(); ++j) fit.free.col(static_cast<Eigen::Index>(j)) = eig.eigenvectors().col(free[j]);
}

// Where the datum's faces are all cylinders or all spheres (features of size), the radius of its fit is free. Returns
// the faces' kind then.
std::optional<cad::ElementaryKind> size_kind(const cad::Model& model, const std::vector<int>& faces) {
  std::optional<cad::ElementaryKind> kind;
  for (int f : faces) {
    const cad::Face& face = model.faces[static_cast<std::size_t>(f)];
    if (!face.analytic) return std::nullopt;
    const cad::ElementaryKind k = face.analytic->surface().kind;
    if (k != cad::ElementaryKind::Cylinder && k != cad::ElementaryKind::Sphere) return std::nullopt;
    if (kind && *kind != k) return std::nullopt;
    kind = k;
  }
  return kind;
}

// The direction the datum's faces share (DatumResult::axis), if they are planes, cylinders or cones that share one.
// Within 1e-9: the same direction as written in the file, to its 10–15 digits.
std::optional<Vector3> shared_axis(const cad::Model& model, const std::vector<int>& faces) {
  std::optional<Vector3> axis;
  std::optional<cad::ElementaryKind> kind;
  for (int f : faces) {
    const cad::Face& face = model.faces[static_cast<std::size_t>(f)];
    if (!face.analytic) return std::nullopt;
    const cad::ElementarySurface& s = face.analytic->surface();
    if (s.kind != cad::ElementaryKind::Plane && s.kind != cad::ElementaryKind::Cylinder && s.kind != cad::ElementaryKind::Cone) {
      return std::nullopt;
    }
    Vector3 a = s.z.normalized();
    if (s.kind == cad::ElementaryKind::Plane) {
      // Outward: the face's `outward` is of its NURBS's S_u × S_v (whose parameters may run against the plane's).
      const nurbs::Domain dom = face.surface.domain();
      const nurbs::SurfaceD1 d = nurbs::derivatives_d1(face.surface, 0.5 * (dom.u0 + dom.u1), 0.5 * (dom.v0 + dom.v1));
      a = d.Su.cross(d.Sv).normalized() * static_cast<double>(face.outward);
      if (!a.allFinite()) return std::nullopt;
    }
    if (kind && *kind != s.kind) return std::nullopt;
    kind = s.kind;
    if (!axis) {
      axis = a;
    } else if (s.kind == cad::ElementaryKind::Plane ? (a - *axis).norm() > 1e-9 : a.cross(*axis).norm() > 1e-9) {
      return std::nullopt;
    }
  }
  return axis;
}

// +1 where the outward normal points away from the cylinder's axis (a pin) or the sphere's centre (a ball), −1 for a
// hole or a socket: the sign that turns the mean outward distance into a change of radius.
double radius_sign(const cad::ElementarySurface& s, const cad::ModelPoint& foot) {
  Vector3 radial = foot.point - s.origin;
  if (s.kind == cad::ElementaryKind::Cylinder) radial -= radial.dot(s.z) * s.z;
  return radial.dot(foot.normal) >= 0.0 ? 1.0 : -1.0;
}

}  // namespace

double Target::distance(const Point3& x) const {
  if (!line()) return (x - point).norm();
  const double along = std::clamp(direction.dot(x - point), -length, length);
  return (x - (point + along * direction)).norm();
}

cad::Model faces_of(const cad::Model& nominal, const std::vector<int>& faces) {
  cad::Model own;
  own.file_units = nominal.file_units;
  for (int f : faces) own.faces.push_back(nominal.faces[static_cast<std::size_t>(f)]);
  return own;
}

RestrictedFit fit_in_motions(const cad::ModelLocator& faces, std::span<const Point3> points, const MotionBasis& basis,
                             const Point3& centre, double length, bool size_free) {
  RestrictedFit fit;
  std::vector<Point3> moved(points.begin(), points.end());
  for (int iteration = 0;; ++iteration) {
    fit.feet = faces.closest_points(moved);
    fit.used.clear();
    for (std::size_t i = 0; i < moved.size(); ++i) {
      if (fit.feet[i].ok() && !fit.feet[i].on_trim_edge) fit.used.push_back(static_cast<int>(i));
    }
    const Eigen::Index n = static_cast<Eigen::Index>(fit.used.size());
    fit.J.resize(n, 6);
    fit.d.resize(n);
    for (Eigen::Index r = 0; r < n; ++r) {
      const cad::ModelPoint& foot = fit.feet[static_cast<std::size_t>(fit.used[static_cast<std::size_t>(r)])];
      const Point3& x = moved[static_cast<std::size_t>(fit.used[static_cast<std::size_t>(r)])];
      fit.J.block<1, 3>(r, 0) = ((x - centre).cross(foot.normal) / length).transpose();
      fit.J.block<1, 3>(r, 3) = foot.normal.transpose();
      fit.d(r) = foot.distance;
    }
    fit.A = fit.J * basis;
    Eigen::VectorXd d = fit.d;
    fit.size = 0.0;
    if (size_free && n > 0) {
      // The size's least-squares value is the mean distance: taking means out of d and A solves for it.
      fit.size = d.mean();
      d.array() -= fit.size;
      fit.A.rowwise() -= fit.A.colwise().mean();
    }
    split_directions(fit.A, fit);
    fit.iterations = iteration;
    if (n == 0 || iteration == kMaxIterations) return fit;
    const Eigen::VectorXd g = fit.fixed.transpose() * (fit.A.transpose() * d);
    geometry::Twist delta = -basis * (fit.fixed * (g.array() / fit.lambda.array()).matrix());
    // Damped: a step that does not lower the points' mean squared distance (sizes taken out) is halved, as far as
    // it takes. A direction the points fix only weakly, with the start far off (a face moved by a millimetre), can
    // otherwise throw them off their faces and the iteration with them.
    const auto mean_square = [&](const std::vector<cad::ModelPoint>& feet) {
      double sum = 0.0, mean = 0.0;
      int count = 0;
      for (const cad::ModelPoint& f : feet) {
        if (!f.ok() || f.on_trim_edge) continue;
        sum += f.distance * f.distance;
        mean += f.distance;
        ++count;
      }
      if (count == 0) return std::numeric_limits<double>::infinity();
      mean /= count;
      return sum / count - (size_free ? mean * mean : 0.0);
    };
    const double before = mean_square(fit.feet);
    std::vector<Point3> trial(moved.size());
    geometry::RigidTransform step;
    for (int halving = 0;; ++halving) {
      step = registration::motion_about(delta, centre, length);
      for (std::size_t i = 0; i < moved.size(); ++i) trial[i] = step * moved[i];
      if (mean_square(faces.closest_points(trial)) < before) break;
      if (halving == kMaxHalvings) {
        // No step along the Gauss–Newton direction lowers the mean square: the points are at its minimum as far as
        // they can tell (the direction comes from a nearly unfixed motion), and stay where they are.
        fit.converged = true;
        return fit;
      }
      delta *= 0.5;
    }
    fit.motion = step * fit.motion;
    double largest = 0.0;
    for (std::size_t i = 0; i < moved.size(); ++i) {
      largest = std::max(largest, (trial[i] - moved[i]).norm());
      moved[i] = trial[i];
    }
    if (largest <= kMotionTolerance) {
      // The last step moved the points by less than the tolerance: the feet, J and d above stand for the end.
      fit.converged = true;
      return fit;
    }
  }
}

const char* to_string(DatumFit f) { return f == DatumFit::Tangent ? "tangent" : "least-squares"; }

DatumFrame establish_frame(const std::vector<DatumSpec>& datums, const cad::Model& nominal,
                           const compensation::CompensationResult& result) {
  DatumFrame frame;
  const geometry::RigidTransform to_cad = result.registration.transform.inverse();
  // Each datum's trusted points in the CAD frame, with the standard uncertainties their fit's errors are taken with.
  // A fitted face's contacts are smoothed: each one's u is small, but their errors are one common error of the fit
  // (an element face's contacts lie on one fitted plane), not independent. A datum fitted to them as if they were
  // independent would be √n times too sure of itself (NIST CTC-04: a frame turned 5 times its stated uncertainty).
  // Taking each with the face's noise instead, as independent, is the datum fitted to the raw centres: about right,
  // and never too sure.
  std::map<int, double> face_noise;
  for (const compensation::FaceReport& f : result.faces) face_noise[f.face] = f.noise_sigma;
  std::vector<std::vector<Point3>> points(datums.size());
  std::vector<std::vector<double>> u(datums.size());
  Point3 centre = Point3::Zero();
  std::size_t total = 0;
  std::string untouched;  // the first target no trusted point touches
  for (std::size_t s = 0; s < datums.size(); ++s) {
    const std::set<int> faces(datums[s].faces.begin(), datums[s].faces.end());
    const std::vector<Target>& targets = datums[s].targets;
    std::vector<int> touches(targets.size(), 0);
    for (const compensation::CompensatedPoint& p : result.points) {
      if (p.status != compensation::PointStatus::Ok || !faces.contains(p.face)) continue;
      const Point3 x = to_cad * p.contact;
      bool at_target = targets.empty();
      for (std::size_t t = 0; t < targets.size(); ++t) {
        if (targets[t].distance(x) <= kTargetReach) {
          ++touches[t];
          at_target = true;
        }
      }
      if (!at_target) continue;
      points[s].push_back(x);
      const auto noise = face_noise.find(p.face);
      u[s].push_back(std::max(std::isfinite(p.uncertainty) ? p.uncertainty : 0.0,
                              noise != face_noise.end() && std::isfinite(noise->second) ? noise->second : 0.0));
      centre += points[s].back();
      ++total;
    }
    for (std::size_t t = 0; t < targets.size() && untouched.empty(); ++t) {
      if (touches[t] > 0) continue;
      const Target& target = targets[t];
      char where[192];
      if (!target.line()) {
        std::snprintf(where, sizeof where, " mm of its target %s (%.3f, %.3f, %.3f)", target.label.c_str(),
                      target.point.x(), target.point.y(), target.point.z());
      } else {
        std::snprintf(where, sizeof where, " mm of its line target %s (%.3f mm either side of (%.3f, %.3f, %.3f) along (%.4f, %.4f, %.4f))",
                      target.label.c_str(), target.length, target.point.x(), target.point.y(), target.point.z(),
                      target.direction.x(), target.direction.y(), target.direction.z());
      }
      char reach[32];
      std::snprintf(reach, sizeof reach, "%g", kTargetReach);
      untouched = "datum " + datums[s].name + ": no trusted point within " + reach + where;
    }
  }
  double spread = 0.0;
  if (total > 0) {
    centre /= static_cast<double>(total);
    for (const auto& set : points) {
      for (const Point3& x : set) spread += (x - centre).squaredNorm();
    }
    spread = std::sqrt(spread / static_cast<double>(total));
  }
  frame.centre = centre;
  frame.length = spread > 0.0 ? spread : 1.0;
  frame.transform = result.registration.transform;
  MotionBasis basis = MotionBasis::Identity(6, 6);
  geometry::RigidTransform correction = geometry::RigidTransform::Identity();  // applied to CAD-frame points
  // ∂(correction's scaled twist)/∂(each datum point's error along its normal), to first order: 6 × all points.
  Eigen::MatrixXd sensitivity = Eigen::MatrixXd::Zero(6, static_cast<Eigen::Index>(total));
  Eigen::VectorXd variance(static_cast<Eigen::Index>(total));
  Eigen::Index first_column = 0;
  auto refuse = [&](const std::string& why) {
    frame.status = DatumFrame::Status::NotDone;
    frame.reason = why;
    return frame;
  };
  if (!untouched.empty()) return refuse(untouched);
  for (std::size_t s = 0; s < datums.size(); ++s) {
    const DatumSpec& spec = datums[s];
    const std::string datum = "datum " + spec.name;
    if (points[s].empty()) return refuse(datum + ": no trusted point on its faces");
    if (basis.cols() == 0) return refuse(datum + ": the datums before it already fix every motion");
    const cad::Model own = faces_of(nominal, spec.faces);
    const cad::ModelLocator locator(own);
    std::vector<Point3> moved;
    moved.reserve(points[s].size());
    for (const Point3& x : points[s]) moved.push_back(correction * x);
    const std::optional<cad::ElementaryKind> kind = size_kind(nominal, spec.faces);
    // The least-squares fit, which also tells the motions this datum fixes; a tangent fit starts from it.
    const RestrictedFit fit = fit_in_motions(locator, moved, basis, centre, frame.length, kind.has_value());
    if (!fit.converged) return refuse(datum + ": its fit did not converge");
    if (fit.fixed.cols() == 0) {
      return refuse(datum + ": its " + std::to_string(fit.used.size()) + " points fix no motion the datums before it left free");
    }
    // What the update of this datum's fit depends on, to first order: it is −G (e + J δ_before), e its points'
    // distances, δ_before the motion the datums before it made.
    Eigen::MatrixXd G, J;
    std::vector<int> used;
    Eigen::VectorXd residuals;
    double size = 0.0;
    if (spec.fit == DatumFit::LeastSquares) {
      correction = fit.motion * correction;
      // G = basis · fixed · Λ⁻¹ · fixedᵀ · Aᵀ (the Gauss–Newton solution).
      G = basis * (fit.fixed * fit.lambda.cwiseInverse().asDiagonal() * fit.fixed.transpose() * fit.A.transpose());
      J = fit.J;
      used = fit.used;
      residuals = fit.d.array() - fit.size;
      size = fit.size;
    } else {
      for (Point3& x : moved) x = fit.motion * x;
      const TangentFit tangent = fit_tangent(locator, moved, basis * fit.fixed, centre, frame.length, kind.has_value());
      if (!tangent.converged) return refuse(datum + ": its tangent fit did not converge");
      correction = tangent.motion * fit.motion * correction;
      G = -tangent.sensitivity;
      J = tangent.J;
      used = tangent.used;
      residuals = tangent.d;
      size = tangent.size;
    }
    sensitivity = (Eigen::MatrixXd::Identity(6, 6) - G * J) * sensitivity;
    for (std::size_t r = 0; r < used.size(); ++r) {
      sensitivity.col(first_column + used[r]) -= G.col(static_cast<Eigen::Index>(r));
    }
    for (std::size_t i = 0; i < points[s].size(); ++i) variance(first_column + static_cast<Eigen::Index>(i)) = u[s][i] * u[s][i];
    first_column += static_cast<Eigen::Index>(points[s].size());

    DatumResult d;
    d.name = spec.name;
    d.faces = spec.faces;
    d.fit = spec.fit;
    d.points = static_cast<int>(used.size());
    d.fixes = static_cast<int>(fit.fixed.cols());
    d.rms = residuals.size() > 0 ? std::sqrt(residuals.array().square().mean()) : 0.0;
    if (kind && !fit.used.empty()) {
      const cad::ModelPoint& foot = fit.feet[static_cast<std::size_t>(fit.used.front())];
      d.size_change = size * radius_sign(own.faces[static_cast<std::size_t>(foot.face)].analytic->surface(), foot);
    }
    d.axis = shared_axis(nominal, spec.faces);
    frame.datums.push_back(std::move(d));
    basis = basis * fit.free;
  }
  // Unused columns (points past an edge) have zero sensitivity; their variance does not matter.
  for (Eigen::Index i = first_column; i < variance.size(); ++i) variance(i) = 0.0;
  frame.covariance = sensitivity * variance.asDiagonal() * sensitivity.transpose();
  frame.free_basis = basis;
  frame.transform = result.registration.transform * correction.inverse();
  frame.status = DatumFrame::Status::OK;
  return frame;
}

compensation::CompensationResult aligned(const compensation::CompensationResult& result, const DatumFrame& frame,
                                         const cad::Model& nominal) {
  compensation::CompensationResult out = result;
  out.registration.transform = frame.transform;
  const geometry::RigidTransform to_cad = frame.transform.inverse();
  // Each row's deviation from its own face, as the compensation took it: a face that deviates by about its distance
  // from another (STC-08's moved 1.14 mm) has its contacts as near to that one, and the nearest face would read it.
  std::map<int, std::size_t> position;  // face index -> position in nominal.faces
  for (std::size_t f = 0; f < nominal.faces.size(); ++f) position.emplace(nominal.faces[f].index, f);
  std::map<int, std::vector<std::size_t>> rows_of;  // by position in nominal.faces
  for (std::size_t k = 0; k < result.points.size(); ++k) {
    if (!result.points[k].computed()) continue;
    const auto at = position.find(result.points[k].face);
    if (at != position.end()) {
      rows_of[static_cast<int>(at->second)].push_back(k);
    } else {
      out.points[k].deviation = std::numeric_limits<double>::quiet_NaN();  // no face of this model: nothing to say
    }
  }
  std::vector<Point3> points;
  std::vector<std::size_t> rows;
  std::vector<cad::ModelPoint> feet;
  for (const auto& [f, face_rows] : rows_of) {
    const std::size_t first = points.size();
    for (const std::size_t k : face_rows) {
      points.push_back(to_cad * result.points[k].contact);
      rows.push_back(k);
    }
    const cad::Model own = faces_of(nominal, {f});
    const std::vector<cad::ModelPoint> on_face =
        cad::ModelLocator(own).closest_points(std::span<const Point3>(points).subspan(first));
    feet.insert(feet.end(), on_face.begin(), on_face.end());
  }
  for (std::size_t i = 0; i < rows.size(); ++i) {
    compensation::CompensatedPoint& p = out.points[rows[i]];
    p.deviation = feet[i].ok() ? feet[i].distance : std::numeric_limits<double>::quiet_NaN();
    // The frame's own uncertainty moves the nominal under the point: its share at the point, along the normal.
    if (feet[i].ok() && std::isfinite(p.uncertainty)) {
      Eigen::Matrix<double, 6, 1> J;
      J.head<3>() = (points[i] - frame.centre).cross(feet[i].normal) / frame.length;
      J.tail<3>() = feet[i].normal;
      p.uncertainty = std::sqrt(p.uncertainty * p.uncertainty + J.dot(frame.covariance * J));
    }
  }
  out.statistics = compensation::statistics(out.points);
  return out;
}

}  // namespace probecomp::inspection
