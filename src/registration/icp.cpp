#include "probecomp/registration/icp.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <array>

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "probecomp/geometry/point_tree.hpp"
#include "probecomp/nurbs/osculating_patch.hpp"
#include "icp_state.hpp"

namespace probecomp::registration {

using nurbs::OsculatingPatch;

const char* to_string(Metric metric) {
  return metric == Metric::PointToPlane ? "point-to-plane" : "point-to-point";
}

const char* to_string(Status status) {
  switch (status) {
    case Status::Converged: return "converged";
    case Status::MaxIterations: return "max-iterations";
    case Status::TooFewPoints: return "too-few-points";
    case Status::NumericalError: return "numerical-error";
  }
  return "?";
}

namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;

struct Step {
  geometry::RigidTransform motion = geometry::RigidTransform::Identity();  // in the CAD frame, applied to the points
  Constraints constraints;
  bool finite = true;
};

// Extrapolate an update (see Convergence) only when it and the one before point the same way to within about 8°
// and it is clearly smaller: a steady linear convergence, not an oscillation or a first large move.
constexpr double kAitkenCosine = 0.99;
constexpr double kAitkenMaxRatio = 0.7;
// Points slide on their feet's osculating paraboloids until they have moved this many robust scales since the last
// search. A paraboloid's distance is out by about |∇κ| D³/6 after a slide of D: at D = 2σ̂ = 0.1 mm on a face curved
// to a radius of 10 mm that changes over 10 mm, 2e-6 mm. A tangent plane's would be κD²/2 = 5e-4 mm.
constexpr double kSlideReach = 2.0;
// The coarse stage (register_points) is a start for the whole set, which moves it by about the subset's own
// uncertainty σ̂/√m anyway (the two sets' minima differ by that): it stops when an update moves the points by less
// than this many times the whole set's relative tolerance (a tenth of σ̂/√m by default: σ̂/√m), and its slides go
// this many times farther between searches (their model error grows as the cube of the distance: 10^(1/3) for a ten
// times coarser precision). 10 000 points on the demo's panel, 4 other cases: the subset's searches 3–5 → 2, the
// errors against the truth unchanged to 0.1 nm.
constexpr double kCoarseToleranceFactor = 10.0;
constexpr double kCoarseReachFactor = 2.154434690031884;  // 10^(1/3)

// The step of one iteration from the points x (CAD frame), their feet and weights w (0: unused), as a motion
// about the data's centroid c (carried along with the data) with rotations scaled by their RMS radius L. With
// `patches` (one per point), each point's distance and its gradient come from its foot's osculating paraboloid
// (where the patch is valid), else from the foot's tangent plane.
Step estimate(Metric metric, std::span<const Point3> x, std::span<const cad::ModelPoint> feet, std::span<const double> w,
              std::span<const OsculatingPatch> patches, const Point3& c, double L) {
  Step step;
  // Partial sums over a fixed number of consecutive chunks, in parallel, then added in chunk order: the result
  // does not depend on the thread count.
  constexpr std::size_t kChunks = 64;
  // Each chunk's lower triangle of H = Σ w J Jᵀ (21 entries, row by row) and g = Σ w r J, written out: Eigen's
  // rank update of a fixed 6 × 6 goes through its general triangular product, several times slower per point
  // (1 M points: 18 ms a step, against a pass over the arrays of a few).
  std::array<std::array<double, 21>, kChunks> Hc;
  std::array<std::array<double, 6>, kChunks> gc;
  tbb::parallel_for(std::size_t{0}, kChunks, [&](std::size_t chunk) {
    std::array<double, 21> Hp{};
    std::array<double, 6> gp{};
    const std::size_t first = x.size() * chunk / kChunks, last = x.size() * (chunk + 1) / kChunks;
    for (std::size_t i = first; i < last; ++i) {
      if (w[i] == 0.0) continue;
      Vector3 n = feet[i].normal;
      double r = n.dot(x[i] - feet[i].point);
      if (!patches.empty() && patches[i].valid()) {
        const OsculatingPatch::Prediction p = patches[i].predict(feet[i].point, n, x[i]);
        r = p.distance;
        n = p.gradient;
      }
      const Vector3 a = (x[i] - c).cross(n) / L;
      const double J[6] = {a.x(), a.y(), a.z(), n.x(), n.y(), n.z()};
      const double wr = w[i] * r;
      int e = 0;
      for (int row = 0; row < 6; ++row) {
        const double wJ = w[i] * J[row];
        for (int col = 0; col <= row; ++col) Hp[e++] += wJ * J[col];
        gp[row] += wr * J[row];
      }
    }
    Hc[chunk] = Hp;
    gc[chunk] = gp;
  });
  Matrix6 H = Matrix6::Zero();
  geometry::Twist g = geometry::Twist::Zero();
  for (std::size_t chunk = 0; chunk < kChunks; ++chunk) {
    int e = 0;
    for (int row = 0; row < 6; ++row) {
      for (int col = 0; col <= row; ++col) H(row, col) += Hc[chunk][e++];
      g(row) += gc[chunk][row];
    }
  }
  H = H.selfadjointView<Eigen::Lower>();
  const Eigen::SelfAdjointEigenSolver<Matrix6> eig(H);
  step.constraints = analyse_constraints(eig, c, L);
  const int free = 6 - step.constraints.fixed;

  geometry::Twist delta = geometry::Twist::Zero();
  if (metric == Metric::PointToPlane) {
    // Gauss–Newton on the fixed motions only: δ = −Σ_k (e_k·g / λ_k) e_k over the constrained eigenvectors.
    for (int k = free; k < 6; ++k) {
      const geometry::Twist e = eig.eigenvectors().col(k);
      delta -= (e.dot(g) / eig.eigenvalues()(k)) * e;
    }
  } else {
    // Closed-form weighted least squares x → q (Arun, Huang and Blostein 1987; reflection excluded).
    double W = 0.0;
    Point3 cx = Point3::Zero(), cq = Point3::Zero();
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (w[i] == 0.0) continue;
      W += w[i];
      cx += w[i] * x[i];
      cq += w[i] * feet[i].point;
    }
    cx /= W;
    cq /= W;
    Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (w[i] != 0.0) C += w[i] * (x[i] - cx) * (feet[i].point - cq).transpose();
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(C, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
    geometry::RigidTransform M = geometry::RigidTransform::Identity();
    M.linear() = svd.matrixV() * D * svd.matrixU().transpose();
    M.translation() = cq - M.linear() * cx;
    delta = scaled_twist_of(M, c, L);
  }
  if (free > 0) {
    // The data say nothing about the free motions, so the step takes none of them, in a sense that does not
    // depend on the twist's centre: the data centroid does not move along a free translation, and the data do
    // not turn about a free rotation's axis. δ is corrected within the free subspace N (where the objective
    // is flat) until C·δ = 0, C holding those conditions as rows.
    const auto& N = step.constraints.free_basis;
    Eigen::MatrixXd Cm(free, 6);
    for (int k = 0; k < free; ++k) {
      const FreeMotion& f = step.constraints.free[static_cast<std::size_t>(k)];
      Cm.row(k).setZero();
      if (f.kind == FreeMotion::Kind::Translation) {
        Cm.row(k).tail<3>() = f.direction.transpose();
      } else {
        Cm.row(k).head<3>() = f.direction.transpose();
      }
    }
    const Eigen::MatrixXd CN = Cm * N;
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(CN);
    if (lu.isInvertible()) {
      delta -= N * lu.solve(Cm * delta);
    } else {
      delta -= N * (N.transpose() * delta);
    }
  }
  step.finite = delta.allFinite();
  step.motion = motion_about(delta, c, L);
  return step;
}

std::string describe(double mm_value) {
  std::ostringstream s;
  s.precision(2);
  s << std::scientific << mm_value << " mm";
  return s.str();
}

// Robust weights make ICP an iteratively reweighted least squares, which converges linearly: successive
// updates point the same way and shrink by a steady ratio ρ (about 0.2 with Cauchy weights on Gaussian
// noise, against quadratic convergence without weights). When two updates agree so, the remaining ones sum
// to ρ/(1 − ρ) of the last, and taking them at once (Aitken's extrapolation along the same screw) saves the
// iterations; the next step corrects what the extrapolation misses.
class Convergence {
 public:
  explicit Convergence(const Criteria& criteria) : criteria_(criteria) {}

  // The update to take for an estimated step: the step itself, or its extrapolation. `length` is the data's radius.
  geometry::RigidTransform accelerate(const geometry::RigidTransform& step, double length) {
    geometry::RigidTransform motion = step;
    const geometry::Twist xi = geometry::to_twist(step);
    geometry::Twist scaled = xi;
    scaled.head<3>() *= length;  // rotation as the motion it gives at the data's radius, comparable with mm
    if (previous_step_.norm() > 0.0 && scaled.norm() > 0.0) {
      const double ratio = scaled.norm() / previous_step_.norm();
      const double cosine = scaled.dot(previous_step_) / (scaled.norm() * previous_step_.norm());
      if (cosine > kAitkenCosine && ratio < kAitkenMaxRatio) motion = geometry::from_twist(xi / (1.0 - ratio));
    }
    previous_step_ = scaled;
    return motion;
  }

  // How far an update may move the points and still count as converged, mm, for `used` points of robust scale `scale`.
  [[nodiscard]] double tolerance(double scale, std::size_t used) const {
    return std::max(criteria_.motion_tolerance,
                    criteria_.relative_motion_tolerance * scale / std::sqrt(static_cast<double>(used)));
  }

 private:
  const Criteria& criteria_;
  geometry::Twist previous_step_ = geometry::Twist::Zero();
};

// The ICP loop on all `machine_points`. `hints` (empty, or one per point) start the first pass's Newton.
RegistrationResult iterate(const cad::ModelLocator& model, std::span<const Point3> machine_points,
                           const RegistrationOptions& options, std::vector<cad::ModelPoint> hints,
                           std::span<const double> offsets, double slide_reach = kSlideReach) {
  using Search = detail::IcpState::Search;
  RegistrationResult result;
  result.located_by.assign(options.located_by.begin(), options.located_by.end());
  const std::size_t n = machine_points.size();
  const std::size_t needed = options.metric == Metric::PointToPlane ? 6 : 3;
  const bool hinted_start = !hints.empty();
  detail::IcpState state(model, machine_points, options, std::move(hints), offsets);
  detail::DataFrame frame;  // set on the first step
  Convergence convergence(options.criteria);
  geometry::RigidTransform to_cad = options.initial.inverse();

  result.status = Status::MaxIterations;
  bool exact = true;         // the correspondences of this step are exact closest points
  bool search_next = true;   // the next step searches its correspondences (else it slides on the last ones' planes)
  Search next = Search::Local;
  geometry::RigidTransform last_motion = geometry::RigidTransform::Identity();
  double drift = 0.0;  // largest motion of a point since its correspondence was found, mm
  double reach = 0.0;  // how far points may slide on their osculating paraboloids before a new search, mm
  for (int it = 1; it <= options.criteria.max_iterations; ++it) {
    const bool fresh = search_next;  // correspondences found at the current transform
    std::size_t used = 0;
    if (fresh) {
      exact = (it == 1 && !hinted_start) || next == Search::Exact;
      used = state.correspondences(to_cad, next);
      ++result.searches;
      drift = 0.0;
      reach = slide_reach * state.scale();
    } else {
      used = state.slide(last_motion);
    }
    result.iterations = it;
    if (used < needed) {
      result.status = Status::TooFewPoints;
      const std::size_t locating = options.located_by.empty() ? n : result.locating_points();
      result.stop_reason = "only " + std::to_string(used) + " of " + std::to_string(locating) +
                           (options.located_by.empty() ? " points" : " points that locate the part") +
                           " have a usable correspondence (not on a face edge, found, finite)";
      break;
    }
    if (it == 1) frame = detail::DataFrame::of(state.points());

    const Step step = estimate(options.metric, state.points(), state.targets(), state.weights(),
                               fresh ? std::span<const OsculatingPatch>() : state.patches(), frame.centroid,
                               frame.length);
    result.constraints = step.constraints;
    if (!step.finite) {
      result.status = Status::NumericalError;
      result.stop_reason = "the estimate is not finite (degenerate correspondences)";
      break;
    }

    const geometry::RigidTransform motion = convergence.accelerate(step.motion, frame.length);
    to_cad = motion * to_cad;
    last_motion = motion;
    const double moved = frame.move(motion);
    drift += moved;

    if (moved <= convergence.tolerance(state.scale(), used)) {
      if (fresh && exact) {
        result.status = Status::Converged;
        result.stop_reason = "converged: the last update moved no point more than " + describe(moved);
        break;
      }
      // Settled on these correspondences: search again where the points now are, exactly, to confirm (the slides
      // were on second-order models, so the search is expected to move the points no further than the tolerance).
      next = Search::Exact;
      search_next = true;
    } else {
      next = Search::Local;
      search_next = options.metric != Metric::PointToPlane || drift > reach;
    }
    if (it == options.criteria.max_iterations) {
      result.stop_reason = "iteration limit " + std::to_string(it) + " reached; the last update moved points up to " +
                           describe(moved);
    }
  }

  // The correspondences reported are the last pass's: at the final transform to within the motion tolerance
  // when converged; otherwise an exact pass at the final transform.
  if (n > 0 && result.status != Status::NumericalError && result.status != Status::Converged) {
    state.correspondences(to_cad, Search::Exact);
  }
  result.transform = to_cad.inverse();
  state.finish(result);
  return result;
}
}  // namespace

RegistrationResult register_points(const cad::ModelLocator& model, std::span<const Point3> machine_points,
                                   const RegistrationOptions& options, std::span<const double> offsets) {
  const std::size_t n = machine_points.size();
  if (!offsets.empty() && offsets.size() != n) {
    throw std::invalid_argument("register_points: one offset per point expected");
  }
  if (!options.located_by.empty() && options.located_by.size() != n) {
    throw std::invalid_argument("register_points: one located_by flag per point expected");
  }
  const std::size_t subset_size = std::min(kCoarseStagePoints, n / 4);
  if (subset_size < kMinCoarseStagePoints) return iterate(model, machine_points, options, {}, offsets);
  // Coarse stage: a spread subset (every k-th point) brings the model close, where closest points are cheap.
  // Then each point's Newton starts from the foot of its nearest subset point, and the full set iterates on;
  // an exact pass still confirms every correspondence before convergence is accepted.
  const std::size_t stride = n / subset_size;
  std::vector<Point3> subset;
  std::vector<double> subset_offsets;
  std::vector<std::uint8_t> subset_located_by;
  for (std::size_t i = 0; i < n; i += stride) {
    if (!machine_points[i].allFinite()) continue;
    subset.push_back(machine_points[i]);
    if (!offsets.empty()) subset_offsets.push_back(offsets[i]);
    if (!options.located_by.empty()) subset_located_by.push_back(options.located_by[i]);
  }
  RegistrationOptions coarse_options = options;
  coarse_options.located_by = subset_located_by;
  coarse_options.criteria.relative_motion_tolerance *= kCoarseToleranceFactor;
  // The subset's k-d tree (for the hints below) is built while the coarse stage runs: it needs only the points.
  RegistrationResult coarse;
  std::unique_ptr<geometry::OwnedPointTree> near_tree;
  tbb::parallel_invoke(
      [&] { coarse = iterate(model, subset, coarse_options, {}, subset_offsets, kCoarseReachFactor * kSlideReach); },
      [&] { near_tree = std::make_unique<geometry::OwnedPointTree>(std::vector<Point3>(subset)); });
  if (coarse.status == Status::TooFewPoints || coarse.status == Status::NumericalError) {
    return iterate(model, machine_points, options, {}, offsets);
  }
  // A point's hint is its nearest subset point's foot moved to first order by the offset between the two:
  // (u, v) + J⁺ Δ with J = [S_u S_v] there (machine frame: J⁺ turned by the transform), rather than that foot
  // itself: the subset points are a stride apart, and Newton from their feet took 3 evaluations a point (a
  // million points on the demo's panel), from the moved ones about 2.
  const Eigen::Matrix3d to_cad_rotation = coarse.transform.linear().transpose();
  std::vector<Eigen::Matrix<double, 2, 3>> to_parameters(subset.size(), Eigen::Matrix<double, 2, 3>::Zero());
  const cad::Model& cad_model = model.model();
  tbb::parallel_for(std::size_t{0}, subset.size(), [&](std::size_t k) {
    const PointMatch& m = coarse.matches[k];
    if (!m.ok() || m.face < 0) return;
    const cad::Face& face = cad_model.faces[static_cast<std::size_t>(m.face)];
    if (face.analytic) return;  // a closed form needs no start
    const nurbs::SurfaceD1 d = nurbs::derivatives_d1(face.surface, m.u, m.v);
    Eigen::Matrix<double, 3, 2> J;
    J << d.Su, d.Sv;
    const Eigen::Matrix2d JtJ = J.transpose() * J;
    const double det = JtJ.determinant();
    if (!(det > 1e-12 * JtJ(0, 0) * JtJ(1, 1))) return;  // tangents (nearly) parallel: no first-order move
    to_parameters[k] = JtJ.inverse() * J.transpose() * to_cad_rotation;
  });
  const geometry::OwnedPointTree& near = *near_tree;
  std::vector<cad::ModelPoint> hints(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      if (!machine_points[i].allFinite()) continue;
      const double q[3] = {machine_points[i].x(), machine_points[i].y(), machine_points[i].z()};
      std::uint32_t k = 0;
      double dist_sq = 0.0;  // squared (nanoflann)
      nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(1);
      knn.init(&k, &dist_sq);
      near.tree.findNeighbors(knn, q, nanoflann::SearchParams());
      const PointMatch& m = coarse.matches[k];
      hints[i].status = m.status;
      hints[i].face = m.face;
      hints[i].u = m.u;
      hints[i].v = m.v;
      if (m.ok() && m.face >= 0) {
        const Eigen::Vector2d step = to_parameters[k] * (machine_points[i] - near.cloud.points[k]);
        const nurbs::Domain dom = cad_model.faces[static_cast<std::size_t>(m.face)].surface.domain();
        hints[i].u = std::clamp(m.u + step.x(), dom.u0, dom.u1);
        hints[i].v = std::clamp(m.v + step.y(), dom.v0, dom.v1);
      }
    }
  });
  RegistrationOptions full = options;
  full.initial = coarse.transform;
  RegistrationResult result = iterate(model, machine_points, full, std::move(hints), offsets);
  result.coarse_iterations = coarse.iterations;
  return result;
}

std::vector<PointMatch> matches_at(const cad::ModelLocator& model, std::span<const Point3> machine_points,
                                   const geometry::RigidTransform& transform, std::span<const double> offsets) {
  if (!offsets.empty() && offsets.size() != machine_points.size()) {
    throw std::invalid_argument("matches_at: one offset per point expected");
  }
  RegistrationOptions still;
  still.initial = transform;
  still.criteria.max_iterations = 0;  // no step: the exact pass at the start is the answer
  return iterate(model, machine_points, still, {}, offsets).matches;
}

}  // namespace probecomp::registration
