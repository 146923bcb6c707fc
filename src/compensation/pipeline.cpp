#include "probecomp/compensation/pipeline.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>

#include "probecomp/nurbs/degree_elevation.hpp"
#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/offset_model.hpp"
#include "probecomp/compensation/contact.hpp"
#include "probecomp/compensation/conventional.hpp"
#include "probecomp/compensation/outliers.hpp"
#include "probecomp/nurbs/closest_point.hpp"

namespace probecomp::compensation {

namespace {

// The fit starts from the registered offset face. A degree-1 direction (a plane, a cylinder's rulings) could
// follow a deformation only by creases at the knots refinement inserts, so it is raised to degree 3 first
// (same shape and parameters, so the registration's (u, v) still hold).
nurbs::Surface fit_start(const nurbs::Surface& offset_face, const geometry::RigidTransform& T) {
  nurbs::Surface s = nurbs::transformed(offset_face, T);
  if (s.p() < 2) s = nurbs::elevate_degree_u(s, 3 - s.p());
  if (s.q() < 2) s = nurbs::elevate_degree_v(s, 3 - s.q());
  return s;
}

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Fits made at most per face while peeling outliers off (each refit follows a change in the points left out).
constexpr int kMaxOutlierFits = 4;
// Whether leaving points out of a fit (or taking them back in) is worth a refit: a point of residual e among n
// points on m control points moves its control points by about e·m/n, so points whose largest residual moves
// the fit by less than this fraction of the noise estimate change nothing measurable (a few 5σ points among a
// million on a few thousand control points move it by a hundredth of σ).
constexpr double kNegligibleShift = 0.1;

bool moves_fit(double largest_residual, std::size_t points, const fitting::AdaptiveFitResult& fit) {
  const double per_control_point = static_cast<double>(points) / std::max(fit.control_points, 1);
  return largest_residual / per_control_point > kNegligibleShift * fit.noise_sigma;
}

// A left-out point is refitted when the fit made without it misses it by at most this many outlier bounds.
constexpr double kSecondChance = 2.0;

std::string mm(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// Points spread over the input (every n/k-th) for cheap whole-set checks.
std::vector<Point3> spread_subset(std::span<const Point3> points, std::size_t k) {
  std::vector<Point3> out;
  const std::size_t step = std::max<std::size_t>(1, points.size() / k);
  for (std::size_t i = 0; i < points.size(); i += step) {
    if (points[i].allFinite()) out.push_back(points[i]);
  }
  return out;
}

// Stops the run when the points are nowhere near the model (wrong file, frame or unit): ICP would otherwise
// "align" them to whatever is nearest.
void check_points_near(const cad::ModelLocator& locator, std::span<const Point3> points,
                       const geometry::RigidTransform& initial, double fraction) {
  BoundingBox box;
  for (const cad::Face& f : locator.model().faces) {
    const BoundingBox b = nurbs::bounding_box(f.surface);
    box.extend(b.min);
    box.extend(b.max);
  }
  // 257 points give the median to within a few per cent of the distribution: plenty for a gross check.
  std::vector<Point3> subset = spread_subset(points, 257);
  if (subset.empty()) throw std::invalid_argument("no finite points to compensate");
  const geometry::RigidTransform to_cad = initial.inverse();
  for (Point3& p : subset) p = to_cad * p;
  const std::vector<cad::ModelPoint> feet = locator.closest_points(subset);
  std::vector<double> d;
  for (const cad::ModelPoint& m : feet) d.push_back(m.ok() ? std::abs(m.distance) : std::numeric_limits<double>::infinity());
  const auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), mid, d.end());
  const double limit = fraction * box.diagonal();
  if (!(*mid <= limit)) {
    throw std::invalid_argument("the points are nowhere near the model: their median distance from it is " + mm(*mid) +
                                " mm, more than " + mm(limit) + " mm (" + mm(100 * fraction) +
                                " % of its size); check the CAD file, the frame and the units");
  }
}

void check_registration(const registration::RegistrationResult& r) {
  if (r.status == registration::Status::TooFewPoints || r.status == registration::Status::NumericalError) {
    throw std::invalid_argument(std::string("registration failed (") + registration::to_string(r.status) + "): " +
                                r.stop_reason);
  }
}

// The distance of x from its foot point on `face`, + on the outward side.
double signed_distance(const cad::Face& face, const Point3& x, const nurbs::ClosestPointResult& foot) {
  const nurbs::UnitNormal n = nurbs::unit_normal(face.surface, foot.u, foot.v);
  const double side = (x - foot.point).dot(static_cast<double>(face.outward) * n.n);
  return side < 0.0 ? -foot.distance : foot.distance;
}

}  // namespace

const char* to_string(Method m) { return m == Method::Cad ? "cad" : "conventional"; }

const char* to_string(PointStatus s) {
  switch (s) {
    case PointStatus::Ok: return "ok";
    case PointStatus::Outlier: return "outlier";
    case PointStatus::Edge: return "edge";
    case PointStatus::FewPoints: return "few-points";
    case PointStatus::NotOnModel: return "not-on-model";
    case PointStatus::Failed: return "failed";
  }
  return "?";
}

int CompensationResult::count(PointStatus s) const {
  return static_cast<int>(std::count_if(points.begin(), points.end(), [s](const auto& p) { return p.status == s; }));
}

CompensationResult compensate(const cad::Model& model, std::span<const Point3> raw,
                              std::optional<std::span<const Vector3>> approach_normals,
                              const CompensateOptions& options) {
  const double r = options.probe_radius;
  if (!(r > 0.0) || !std::isfinite(r)) throw std::invalid_argument("the probe radius must be a positive number of mm");
  if (raw.empty()) throw std::invalid_argument("no points to compensate");
  if (model.faces.empty()) throw std::invalid_argument("the CAD model has no faces");
  if (approach_normals && approach_normals->size() != raw.size()) {
    throw std::invalid_argument("the approach normals do not match the points in number");
  }
  if (options.method == Method::Conventional && !approach_normals) {
    throw std::invalid_argument(
        "--method conventional needs the approach normals (columns i,j,k, or DMIS points with i,j,k); the input has "
        "none: use --method cad, which does not need them");
  }
  auto stage = [&](const std::string& name, double fraction) {
    if (options.progress) options.progress(name, fraction);
  };

  CompensationResult out;
  out.method = options.method;
  out.points.resize(raw.size());
  std::map<int, FaceReport> reports;  // by position in model.faces

  if (options.method == Method::Conventional) {
    stage("registration", 0.0);
    auto t0 = Clock::now();
    const std::vector<Point3> contacts = conventional_contact_points(raw, *approach_normals, r);
    const cad::ModelLocator locator(model);
    check_points_near(locator, contacts, options.registration.initial, options.max_initial_distance_fraction);
    out.registration = registration::register_points(locator, contacts, options.registration);
    check_registration(out.registration);
    out.seconds.registration = since(t0);
    for (std::size_t k = 0; k < raw.size(); ++k) {
      const registration::PointMatch& m = out.registration.matches[k];
      CompensatedPoint& c = out.points[k];
      if (!m.ok() || !contacts[k].allFinite()) continue;
      c.status = m.on_edge ? PointStatus::Edge : PointStatus::Ok;
      c.contact = contacts[k];
      c.normal = (*approach_normals)[k].normalized();
      c.deviation = m.distance;
      c.face = model.faces[static_cast<std::size_t>(m.face)].index;
      FaceReport& rep = reports[m.face];
      rep.face = c.face;
      rep.outward = model.faces[static_cast<std::size_t>(m.face)].outward;
      ++rep.points;
    }
    for (auto& [f, rep] : reports) out.faces.push_back(std::move(rep));
    return out;
  }

  // --- CAD-based method --- (on a copy: the material side is decided into its faces' `outward`)
  stage("material side", 0.0);
  auto t0 = Clock::now();
  cad::Model work = model;
  out.material = cad::decide_material_side(work, raw, approach_normals, options.registration.initial);
  out.seconds.material_side = since(t0);

  stage("offset model", 0.05);
  t0 = Clock::now();
  const cad::OffsetModel offset = cad::offset_model(work, r, options.offset);
  const cad::ModelLocator locator(offset.model);
  out.seconds.offset = since(t0);

  stage("registration", 0.15);
  t0 = Clock::now();
  check_points_near(locator, raw, options.registration.initial, options.max_initial_distance_fraction);
  out.registration = registration::register_to_offset_model(offset, locator, raw, options.registration);
  check_registration(out.registration);
  const geometry::RigidTransform T = out.registration.transform;
  out.seconds.registration = since(t0);

  // Points by face (their correspondences); edge points are compensated towards the edge, never fitted.
  std::map<int, std::vector<std::size_t>> by_face;
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const registration::PointMatch& m = out.registration.matches[k];
    if (!m.ok() || !raw[k].allFinite()) continue;
    FaceReport& rep = reports[m.face];
    ++rep.points;
    CompensatedPoint& c = out.points[k];
    c.face = work.faces[static_cast<std::size_t>(m.face)].index;
    if (m.on_edge) {
      const Point3 edge = T * nurbs::evaluate(work.faces[static_cast<std::size_t>(m.face)].surface, m.u, m.v);
      c.status = PointStatus::Edge;
      c.normal = (raw[k] - edge).normalized();
      c.contact = raw[k] - r * c.normal;
    } else {
      by_face[m.face].push_back(k);
    }
  }

  stage("fitting", 0.35);
  t0 = Clock::now();
  double compensation_seconds = 0.0;
  std::size_t done = 0;
  for (const auto& [f, members] : by_face) {
    const cad::Face& face = work.faces[static_cast<std::size_t>(f)];
    FaceReport& rep = reports[f];
    const nurbs::Surface start = fit_start(offset.model.faces[static_cast<std::size_t>(f)].surface, T);
    const double needed = options.min_points_per_control_point * start.num_u() * start.num_v();
    std::vector<Point3> pts;
    std::vector<fitting::SurfaceParameter> params;
    pts.reserve(members.size());
    params.reserve(members.size());
    for (std::size_t k : members) {
      pts.push_back(raw[k]);
      params.push_back({out.registration.matches[k].u, out.registration.matches[k].v});
    }
    std::optional<fitting::AdaptiveFitResult> fit;
    std::vector<double> weights(members.size(), 1.0);
    std::vector<char> gross(members.size(), 0);
    std::vector<std::uint32_t> neighbours;
    double bound = 0.0;
    if (static_cast<double>(members.size()) >= needed) {
      // Gross outliers first, from their neighbours, so that the fit's refinement never chases them.
      std::vector<double> residuals(members.size());
      std::vector<Vector3> normals(members.size());
      tbb::parallel_for(std::size_t{0}, members.size(), [&](std::size_t i) {
        residuals[i] = out.registration.matches[members[i]].distance;
        normals[i] = T.linear() * nurbs::unit_normal(face.surface, params[i].u, params[i].v).n;
      });
      LocalOutliers local = local_outliers(pts, residuals, normals, options.gross_outliers);
      gross = std::move(local.outlier);
      neighbours = std::move(local.nearest);
      for (std::size_t i = 0; i < members.size(); ++i) {
        if (gross[i]) weights[i] = 0.0;
      }
      // Outliers are found from the fit's own residuals (the deformation is data, not outliers, so the
      // registration's residuals cannot tell them), left out, and the face refitted, until no new point is
      // beyond the bound. A point once left out stays out: a fit bent by gross outliers can push good
      // neighbours beyond the bound too, and those are then reported as outliers (not trusted) rather than
      // left to oscillate in and out.
      for (int attempt = 0; attempt < kMaxOutlierFits; ++attempt) {
        // A refit starts from the last fit, whose knots already follow the shape: it seldom needs a round of
        // refinement, where starting over would repeat them all.
        fit = attempt == 0 ? fitting::fit_surface(start, pts, params, weights, options.fit, neighbours)
                           : fitting::fit_surface(fit->surface, pts, fit->params, weights, options.fit, neighbours);
        if (!fit->fitted()) break;
        bound = std::max(options.outlier_sigmas * fit->noise_sigma, options.min_outlier_residual);
        int flagged = 0;
        double largest = 0.0;
        for (std::size_t i = 0; i < members.size(); ++i) {
          if (weights[i] > 0.0 && std::abs(fit->residuals[i]) > bound) {
            weights[i] = 0.0;
            ++flagged;
            largest = std::max(largest, std::abs(fit->residuals[i]));
          }
        }
        if (flagged == 0 || !moves_fit(largest, members.size(), *fit)) break;
      }
      // A point left out (one its neighbours did not predict, as a narrow dent's bottom seen through a coarse
      // neighbourhood, or one an earlier, less refined fit missed) is given another chance when the last fit, made
      // without it, passes within twice the bound (left out, a point that alone carries a feature is missed by
      // more than it would be with it; gross errors are missed by far more). The face is refitted with those
      // points, and any that the new fit still misses by more than the bound is left out again.
      std::vector<std::size_t> second_chance;
      double largest = 0.0;
      for (std::size_t i = 0; fit->fitted() && i < members.size(); ++i) {
        if (weights[i] == 0.0 && std::abs(fit->residuals[i]) <= kSecondChance * bound) {
          weights[i] = 1.0;
          second_chance.push_back(i);
          largest = std::max(largest, std::abs(fit->residuals[i]));
        }
      }
      // Without a refit (the points could not move the fit measurably) their residuals stand as they are.
      if (!second_chance.empty() && moves_fit(largest, members.size(), *fit)) {
        fit = fitting::fit_surface(fit->surface, pts, fit->params, weights, options.fit, neighbours);
      }
      if (fit->fitted()) {
        for (std::size_t i : second_chance) {
          if (std::abs(fit->residuals[i]) > bound) weights[i] = 0.0;
        }
      }
    }
    rep.fitted = fit && fit->fitted();
    const auto tc = Clock::now();
    if (rep.fitted) {
      rep.fit_status = fit->status;
      rep.control_points = fit->control_points;
      rep.rounds = fit->rounds;
      rep.rms = fit->rms;
      rep.max_residual = fit->max_residual;
      rep.noise_sigma = fit->noise_sigma;
      rep.centre_surface = fit->surface;
      const std::vector<ContactPoint> contacts = contact_points(fit->surface, face.outward, r, pts, fit->params);
      for (std::size_t i = 0; i < members.size(); ++i) {
        CompensatedPoint& c = out.points[members[i]];
        if (!contacts[i].ok()) {
          c.status = PointStatus::Failed;
          continue;
        }
        const bool trusted = weights[i] > 0.0;
        c.status = trusted ? PointStatus::Ok : PointStatus::Outlier;
        rep.outliers += trusted ? 0 : 1;
        c.contact = contacts[i].contact;
        c.normal = contacts[i].normal;
      }
    } else {
      // Too few points (or a fit that could not be made): the registered nominal normal.
      const Eigen::Matrix3d R = T.linear();
      for (std::size_t i = 0; i < members.size(); ++i) {
        CompensatedPoint& c = out.points[members[i]];
        const nurbs::UnitNormal n = nurbs::unit_normal(face.surface, params[i].u, params[i].v);
        c.status = PointStatus::FewPoints;
        c.normal = R * (static_cast<double>(face.outward) * n.n);
        c.contact = raw[members[i]] - r * c.normal;
      }
    }
    compensation_seconds += since(tc);
    done += members.size();
    stage("fitting", 0.35 + 0.5 * static_cast<double>(done) / static_cast<double>(raw.size()));
  }
  out.seconds.fitting = since(t0) - compensation_seconds;
  out.seconds.compensation = compensation_seconds;

  stage("deviation", 0.9);
  t0 = Clock::now();
  // Newton from the correspondence's (u, v) (nominal and offset faces share their parametrisation), with the
  // face's global search where Newton fails.
  const geometry::RigidTransform to_cad = T.inverse();
  std::vector<char> retry(raw.size(), 0);
  tbb::parallel_for(std::size_t{0}, raw.size(), [&](std::size_t k) {
    CompensatedPoint& c = out.points[k];
    if (!c.computed()) return;
    const registration::PointMatch& m = out.registration.matches[k];
    const cad::Face& face = work.faces[static_cast<std::size_t>(m.face)];
    const Point3 x = to_cad * c.contact;
    const nurbs::ClosestPointResult foot = nurbs::refine_closest_point(face.surface, x, m.u, m.v);
    if (foot.ok()) {
      c.deviation = signed_distance(face, x, foot);
    } else {
      retry[k] = 1;
    }
  });
  std::map<int, nurbs::ClosestPointSolver> solvers;  // built for the faces that need one
  for (std::size_t k = 0; k < raw.size(); ++k) {
    if (!retry[k]) continue;
    const registration::PointMatch& m = out.registration.matches[k];
    const cad::Face& face = work.faces[static_cast<std::size_t>(m.face)];
    const nurbs::ClosestPointSolver& solver = solvers.try_emplace(m.face, face.surface).first->second;
    const Point3 x = to_cad * out.points[k].contact;
    const nurbs::ClosestPointResult foot = solver.closest_point(x);
    if (foot.ok()) {
      out.points[k].deviation = signed_distance(face, x, foot);
    } else {
      out.points[k].status = PointStatus::Failed;
    }
  }
  out.seconds.deviation = since(t0);
  for (auto& [f, rep] : reports) {
    rep.face = work.faces[static_cast<std::size_t>(f)].index;
    rep.outward = work.faces[static_cast<std::size_t>(f)].outward;
    if (!out.material.empty()) rep.material = out.material[static_cast<std::size_t>(f)].source;
    out.faces.push_back(std::move(rep));
  }
  stage("done", 1.0);
  return out;
}

std::vector<nurbs::Surface> fitted_part_surfaces(const CompensationResult& result, double probe_radius,
                                                 const fitting::OffsetOptions& options) {
  std::vector<nurbs::Surface> out;
  for (const FaceReport& f : result.faces) {
    if (!f.fitted) continue;
    // The contact surface is the centre surface moved by r into the material, against the outward normal.
    const fitting::OffsetResult o = fitting::offset_surface(*f.centre_surface, -probe_radius * f.outward, options);
    if (o.status == fitting::OffsetResult::Status::Degenerate) {
      throw std::runtime_error("face " + std::to_string(f.face) + ": the fitted surface has no normal somewhere");
    }
    out.push_back(o.surface);
  }
  return out;
}

}  // namespace probecomp::compensation
