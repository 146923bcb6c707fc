#include "probecomp/simulation/measure.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "probecomp/simulation/random.hpp"

namespace probecomp::simulation {

namespace {

// The approach point: the probe starts r + this beyond the programmed point along its normal (mm). A CMM part
// program comes to each touch from a prehit point a few mm out; 2 mm keeps the approach point inside bores and slots
// down to 2r + 2 mm across (a larger clearance would put it beyond their far wall), while a part placed nearer than
// planned moves the approach point out along the line (touch() below), not in.
constexpr double kApproachClearance = 2.0;
// How far past the nominal touch (travel r) the probe searches before it reports no touch (but see touch()), and
// how far the approach point may move out (mm): a CMM's search distance; several times the studies' misalignments
// and deformations (up to about 3 mm along a normal).
constexpr double kSearchDistance = 10.0;
// Moved along the line, the approach point leaves the tip this clear of the face it overlapped (mm), so that Newton
// lands clear on a curved face too; a margin and not the full clearance, which along a line that meets the face
// obliquely lies far out.
constexpr double kBackOffMargin = 0.01;
// A touch is accepted when the tip is within this of the part (mm), and a bracket on the travel this narrow has
// converged: far below any CMM's resolution.
constexpr double kTouchTolerance = 1e-9;
constexpr double kTravelTolerance = 1e-11;
// Below this remaining travel (gap / slope, mm) Newton's step on the nearest face is taken without asking whether
// another face lies within reach: no feature of a part is a micrometre across.
constexpr double kNearTravel = 1e-3;
// Newton along the line needs the distance to fall at least this fast (the cosine between the line and the
// direction from the foot point); at a lower slope the line runs along the face (or away from it).
constexpr double kGrazingCosine = 1e-3;
// Sphere-tracing steps, steps of the approach point and bracket refinements at most: the slowest march, towards a
// face met at a cosine of 0.1 with a second face within reach, takes about 100 steps.
constexpr int kMaxMarchSteps = 2000;
constexpr int kMaxBackOffSteps = 20;
constexpr int kMaxWalkInSteps = 1000;  // steps of at least kBackOffMargin over at most the clearance and 10 mm more
constexpr int kMaxBracketSteps = 200;
constexpr int kMaxPolishSteps = 4;
constexpr int kMaxNewtonSteps = 60;
// The search past the line's nearest meeting with the offset part goes this much farther (mm), so that a march
// reaching it from above is not stopped a rounding short of it.
constexpr double kSearchMargin = 1e-6;
// A second face within this of the tip (mm) is touched too: a thousand times the touch tolerance, far below any
// CMM's resolution, so that a line through the corner of two faces reports both whatever the rounding.
constexpr double kTwoFaceTolerance = 1e-6;
// Two contacts closer than this fraction of r are one (a shared edge, whose two faces' boundaries differ by the
// model's tolerance); a tip held in a corner of faces whose normals differ by ψ touches them 2r·sin(ψ/2) apart.
constexpr double kDistinctContacts = 1e-3;

// The probe centre at travel t along the programmed line, and its foot on the whole actual part.
struct LineSample {
  double t = 0.0;
  cad::ModelPoint foot;
  double gap = 0.0;    // distance to the part (see at()) − r: > 0 while the tip is clear of the part
  double slope = 0.0;  // d(gap)/dt: the cosine between the line and the direction from the foot point
};

class ProbeLine {
 public:
  ProbeLine(const cad::ModelLocator& actual, const ProgrammedPoint& programmed, double r)
      : actual_(actual), point_(programmed.point), n_(programmed.normal.normalized()), r_(r), face_(programmed.face) {}

  [[nodiscard]] Point3 centre(double t) const { return point_ + t * n_; }

  [[nodiscard]] LineSample at(double t, const cad::ModelPoint* hint) const {
    LineSample s;
    s.t = t;
    const Point3 c = centre(t);
    s.foot = hint != nullptr && hint->ok() ? actual_.closest_point(c, *hint) : actual_.closest_point(c);
    if (!s.foot.ok()) return s;
    // A loose face of a model with no solid may face either way (its file's orientation is no more than a guess),
    // so its distance counts unsigned: the tip is as clear of its back as of its front. So does a foot on a face's
    // edge farther than r: there the sign is the side of the face's plane, and far beyond a convex edge the centre
    // lies behind the plane yet outside the part (within r, the tip's side of the edge is what the march needs).
    const bool far_beyond_edge = s.foot.on_edge() && std::abs(s.foot.distance) > r_;
    const double d = sided(s.foot.face) && !far_beyond_edge ? s.foot.distance : std::abs(s.foot.distance);
    s.gap = d - r_;
    // The gradient of that distance: the unit vector from the foot point, or the face normal when the centre is on
    // the part.
    const Vector3 g = std::abs(d) > 1e-12 ? Vector3((c - s.foot.point) / d) : s.foot.normal;
    s.slope = g.dot(n_);
    return s;
  }

  // How far (mm) the probe may travel from `s` towards the part with no face other than the nearest one within
  // reach of the tip: the distance to the others is 1-Lipschitz. Infinite when none is within `wanted` of a touch.
  [[nodiscard]] double reach_of_other_faces(const LineSample& s, double wanted) const {
    const cad::ModelPoint other = actual_.closest_point_on_other_faces(centre(s.t), s.foot.face, r_ + wanted);
    return other.face < 0 ? std::numeric_limits<double>::infinity() : std::abs(other.distance) - r_;
  }

  // Whether the face's signed distance is trusted: which side of it is material is known for a solid's faces
  // and, from the plan, for the programmed face.
  [[nodiscard]] bool sided(int face) const {
    return face == face_ || actual_.model().faces.at(static_cast<std::size_t>(face)).material_known;
  }

  // Whether the tip, overlapping the part at `s`, moves out along the line to start clear: when the face it
  // overlaps most is the programmed one, or any face when the plan does not say which it is on.
  [[nodiscard]] bool may_back_off(const LineSample& s) const { return face_ < 0 || s.foot.face == face_; }

  [[nodiscard]] cad::ModelPoint other_face_touched(const LineSample& s) const {
    cad::ModelPoint other = actual_.closest_point_on_other_faces(centre(s.t), s.foot.face, r_ + kTwoFaceTolerance);
    const bool touched = other.face >= 0 && std::abs(std::abs(other.distance) - r_) <= kTwoFaceTolerance &&
                         (other.point - s.foot.point).norm() > kDistinctContacts * r_;
    if (!touched) other.face = -1;
    return other;
  }

 private:
  const cad::ModelLocator& actual_;
  Point3 point_;
  Vector3 n_;
  double r_;
  int face_;  // the programmed face, −1 when not known
};

Touch touched_at(const ProbeLine& line, const LineSample& s) {
  Touch out;
  if (!s.foot.ok() || std::abs(s.gap) > kTouchTolerance) return out;
  const cad::ModelPoint& foot = s.foot;
  const Point3 centre = line.centre(s.t);
  const bool edge = foot.on_edge();
  // Against the back of a loose face (one whose material side is not known: distances to it count unsigned), the
  // tip came from inside the part as the file orients it: the plan's normal or the model is wrong there, and no
  // probe touches so. At a face's edge the sign is only the side of the face's plane: behind it, the centre may be
  // outside beyond a convex edge or inside at a concave one, which the faces alone do not tell; such a touch is not
  // reported (the compensation, on the same signed distance, could not place it either).
  if (foot.distance < 0.0 && (edge ? line.sided(foot.face) : !line.sided(foot.face))) return out;
  const cad::ModelPoint other = line.other_face_touched(s);
  out.status = other.face >= 0 ? Touch::Status::TwoFaces : edge ? Touch::Status::Edge : Touch::Status::OK;
  out.centre = centre;
  out.measured = centre;
  out.contact = foot.point;
  out.normal = edge ? Vector3((centre - foot.point).normalized()) : foot.normal;
  out.face = foot.face;
  out.u = foot.u;
  out.v = foot.v;
  out.travel = s.t;
  if (other.face >= 0) {
    out.other_face = other.face;
    out.other_contact = other.point;
  }
  return out;
}

// A contact within the tolerance made exact: Newton on the touched face while its steps, each below the tolerance
// over the slope, still shrink the gap (nothing can come between the tip and the part in a nanometre).
LineSample polished(const ProbeLine& line, LineSample s) {
  for (int step = 0; step < kMaxPolishSteps && s.slope > kGrazingCosine; ++step) {
    const double dt = s.gap / s.slope;
    if (std::abs(dt) < kTravelTolerance) break;
    const LineSample next = line.at(s.t - dt, &s.foot);
    if (!next.foot.ok() || !(std::abs(next.gap) < std::abs(s.gap))) break;
    s = next;
  }
  return s;
}

// The first contact inside a bracket: the tip clear at `hi`, overlapping the part at `lo`, the two a step of the
// march apart, too short for the contact to be anything but one crossing. Regula falsi with the Illinois halving
// (the distance to a corner of two faces has a kink, where Newton would stall).
Touch refine(const ProbeLine& line, LineSample hi, LineSample lo) {
  double g_hi = hi.gap, g_lo = lo.gap;
  int kept = 0;  // > 0: hi kept twice running, < 0: lo
  for (int step = 0; step < kMaxBracketSteps && hi.t - lo.t > kTravelTolerance; ++step) {
    double t = hi.t - g_hi * (hi.t - lo.t) / (g_hi - g_lo);
    if (!(t > lo.t && t < hi.t)) t = 0.5 * (lo.t + hi.t);
    const LineSample m = line.at(t, &hi.foot);
    if (!m.foot.ok()) return {};
    if (std::abs(m.gap) <= kTouchTolerance) return touched_at(line, polished(line, m));
    if (m.gap > 0.0) {
      hi = m;
      g_hi = m.gap;
      kept = kept < 0 ? kept - 1 : -1;
      if (kept <= -2) g_lo *= 0.5;
    } else {
      lo = m;
      g_lo = m.gap;
      kept = kept > 0 ? kept + 1 : 1;
      if (kept >= 2) g_hi *= 0.5;
    }
  }
  return touched_at(line, hi.t - lo.t <= kTravelTolerance ? hi : LineSample{});
}

// Where the line meets the part's offset by r nearest the nominal touch: Newton on dist(centre, part) = r from the
// nominal touch (travel r), the paper's simulated touch; NaN where Newton fails (a grazing line, or none near).
double nearest_meeting(const cad::ModelLocator& actual, const ProgrammedPoint& programmed, double r) {
  const Vector3 n = programmed.normal.normalized();
  double t = r;
  cad::ModelPoint foot;
  for (int step = 0; step < kMaxNewtonSteps; ++step) {
    const Point3 c = programmed.point + t * n;
    foot = step == 0 ? actual.closest_point(c) : actual.closest_point(c, foot);
    if (!foot.ok()) break;
    const Vector3 g = std::abs(foot.distance) > 1e-12 ? Vector3((c - foot.point) / foot.distance) : foot.normal;
    const double slope = g.dot(n);
    if (slope < kGrazingCosine) break;
    const double dt = -(foot.distance - r) / slope;
    t += dt;
    if (std::abs(dt) < kTravelTolerance) return t;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// The probe's first contact with the whole part along the programmed line (DESIGN.md §8). March from the approach
// point towards the part: each step is the tip's clearance (the distance to the part is 1-Lipschitz, so such a step
// cannot pass through any face: sphere tracing), or Newton's step on the nearest face when the other faces are
// out of its reach; a step that ends inside the part brackets the first contact. What this cannot see: a single
// face that comes within r of the line and recedes again inside one Newton step (a face folded back on itself
// within the step; a convex face's tangent stays below its distance, so Newton never steps past it).
Touch touch(const cad::ModelLocator& actual, const ProgrammedPoint& programmed, double r) {
  const ProbeLine line(actual, programmed, r);
  const double planned_start = r + kApproachClearance;
  double end = r - kSearchDistance;
  bool extended = false;
  LineSample s = line.at(planned_start, nullptr);
  if (!s.foot.ok()) return {};
  // Where the tip overlaps the part at the approach point, the approach point moves along the line to the nearest
  // clear place. Out, when what it overlaps is the programmed face: the part is nearer than planned (Newton on the
  // overlap, landing kBackOffMargin clear). In, when it is another face: the space in front of the programmed face
  // is narrower than the clearance (a blade's neighbour, a wall beside a floor), and a programmer would come in
  // closer; but no nearer than the nominal touch, and not into the programmed face. Where neither frees the tip, the
  // line is blocked, as a real probe's would be.
  for (int step = 0; s.gap < -kTouchTolerance && line.may_back_off(s); ++step) {
    if (step == kMaxBackOffSteps || s.slope < kGrazingCosine) return {};
    const double t = s.t + (kBackOffMargin - s.gap) / s.slope;
    if (t > planned_start + kSearchDistance) return {};
    s = line.at(t, &s.foot);
    if (!s.foot.ok()) return {};
  }
  for (int step = 0; s.gap < -kTouchTolerance; ++step) {
    // Not through the material: a centre inside another face (signed distance < 0) is inside the part.
    if (step == kMaxWalkInSteps || line.may_back_off(s) || s.t <= r || s.gap < -r) return {};
    // The overlap lasts at least its depth along the line (1-Lipschitz), so a step of the depth passes no clear
    // place; kBackOffMargin at least, so that an overlap that ends obliquely is left in few steps.
    s = line.at(std::max(s.t - std::max(-s.gap, kBackOffMargin), r), &s.foot);
    if (!s.foot.ok()) return {};
  }
  for (int step = 0; step < kMaxMarchSteps; ++step) {
    if (s.gap <= kTouchTolerance) return touched_at(line, polished(line, s));
    if (s.t - end <= 0.0) {
      // The search reaches kSearchDistance past the nominal touch, or as far as the line's nearest meeting with the
      // offset part when that lies farther: a part misplaced by tens of mm (the registration tests' 10° and 35°)
      // is still measured where the paper's simulation measures it, if the line is clear down to there.
      const double meeting = extended ? std::numeric_limits<double>::quiet_NaN() : nearest_meeting(actual, programmed, r);
      extended = true;
      if (!(meeting - kSearchMargin < end)) return {};
      end = meeting - kSearchMargin;
    }
    double h = s.gap;  // always safe
    const double newton = s.slope > kGrazingCosine ? s.gap / s.slope : std::numeric_limits<double>::infinity();
    if (newton > h) {
      if (newton <= kNearTravel) {
        h = newton;
      } else {
        h = std::max(h, std::min(newton, line.reach_of_other_faces(s, std::min(newton, s.t - end))));
      }
    }
    h = std::min(h, s.t - end);
    const LineSample next = line.at(s.t - h, &s.foot);
    if (!next.foot.ok()) return {};
    if (next.gap < -kTouchTolerance) return refine(line, s, next);
    s = next;
  }
  return {};
}

// Programmed points at fractions (a, b) of the face's (u, v) domain.
std::vector<ProgrammedPoint> plan_at(const cad::Face& face, const std::vector<std::pair<double, double>>& ab) {
  const nurbs::Domain d = face.surface.domain();
  std::vector<ProgrammedPoint> out;
  out.reserve(ab.size());
  for (const auto& [a, b] : ab) {
    const double u = d.u0 + a * (d.u1 - d.u0), v = d.v0 + b * (d.v1 - d.v0);
    const nurbs::UnitNormal n = nurbs::unit_normal(face.surface, u, v);
    out.push_back({nurbs::evaluate(face.surface, u, v), static_cast<double>(face.outward) * n.n, face.index});
  }
  return out;
}

}  // namespace

std::vector<ProgrammedPoint> grid_plan(const cad::Face& face, int nu, int nv, PlanMargin margin) {
  std::vector<std::pair<double, double>> ab;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      ab.emplace_back(margin.u + (1.0 - 2.0 * margin.u) * (nu > 1 ? static_cast<double>(i) / (nu - 1) : 0.5),
                      margin.v + (1.0 - 2.0 * margin.v) * (nv > 1 ? static_cast<double>(j) / (nv - 1) : 0.5));
    }
  }
  return plan_at(face, ab);
}

std::vector<ProgrammedPoint> random_plan(const cad::Face& face, int n, std::uint64_t seed, PlanMargin margin) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> a(margin.u, 1.0 - margin.u), b(margin.v, 1.0 - margin.v);
  std::vector<std::pair<double, double>> ab;
  for (int k = 0; k < n; ++k) {
    const double x = a(rng), y = b(rng);  // in this order: the same draws as before margins per direction
    ab.emplace_back(x, y);
  }
  return plan_at(face, ab);
}

std::vector<ProgrammedPoint> scan_line_plan(const cad::Face& face, int lines, int per_line, bool along_u,
                                            PlanMargin margin) {
  const double ma = along_u ? margin.u : margin.v, mb = along_u ? margin.v : margin.u;
  std::vector<std::pair<double, double>> ab;
  ab.reserve(static_cast<std::size_t>(std::max(lines, 0)) * static_cast<std::size_t>(std::max(per_line, 0)));
  for (int l = 0; l < lines; ++l) {
    const double b = mb + (1.0 - 2.0 * mb) * (lines > 1 ? static_cast<double>(l) / (lines - 1) : 0.5);
    for (int k = 0; k < per_line; ++k) {
      const int along = l % 2 == 0 ? k : per_line - 1 - k;
      const double a = ma + (1.0 - 2.0 * ma) * (per_line > 1 ? static_cast<double>(along) / (per_line - 1) : 0.5);
      if (along_u) {
        ab.emplace_back(a, b);
      } else {
        ab.emplace_back(b, a);
      }
    }
  }
  return plan_at(face, ab);
}

const char* to_string(Touch::Status s) {
  switch (s) {
    case Touch::Status::OK: return "ok";
    case Touch::Status::Edge: return "edge";
    case Touch::Status::Missed: return "missed";
    case Touch::Status::TwoFaces: return "two-faces";
  }
  return "?";
}

std::vector<Touch> simulate_touches(const cad::ModelLocator& actual, std::span<const ProgrammedPoint> plan,
                                    const MeasurementOptions& options) {
  std::vector<Touch> out(plan.size());
  tbb::parallel_for(std::size_t{0}, plan.size(),
                    [&](std::size_t k) {
                      out[k] = touch(actual, plan[k], options.probe_radii.empty() ? options.probe_radius : options.probe_radii.at(k));
                    });
  if (!options.pretravel.none()) {
    for (std::size_t k = 0; k < out.size(); ++k) {
      if (out[k].status == Touch::Status::Missed) continue;
      const Vector3 d = -plan[k].normal.normalized();
      out[k].measured = out[k].centre + options.pretravel(d) * d;
    }
  }
  if (options.noise_sigma > 0.0) {
    std::mt19937_64 rng(options.seed);
    std::normal_distribution<double> noise(0.0, options.noise_sigma);
    for (Touch& t : out) {
      // Drawn for every point, touched or not, so that one point's noise does not depend on another's touch.
      const Vector3 e = draw_vector(noise, rng);
      if (t.status != Touch::Status::Missed) t.measured += e;
    }
  }
  return out;
}

cad::Model actual_model(const cad::Model& nominal, const Deformation& deformation,
                        const geometry::RigidTransform& placement) {
  cad::Model out = nominal;
  for (cad::Face& face : out.faces) {
    face.surface = nurbs::transformed(deformed_surface(face.surface, face.outward, deformation), placement);
    face.analytic = nullptr;  // deformed, the face is no longer the file's plane or cylinder
  }
  return out;
}

}  // namespace probecomp::simulation
