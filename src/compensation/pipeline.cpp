#include "probecomp/compensation/pipeline.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <string_view>

#include "probecomp/compensation/contact.hpp"
#include "probecomp/compensation/conventional.hpp"
#include "probecomp/compensation/normal_support.hpp"
#include "probecomp/compensation/outliers.hpp"
#include "probecomp/error.hpp"
#include "probecomp/geometry/neighbours.hpp"
#include "probecomp/geometry/parallel.hpp"
#include "probecomp/geometry/point_set.hpp"
#include "probecomp/geometry/statistics.hpp"
#include "probecomp/geometry/stopwatch.hpp"
#include "probecomp/nurbs/closest_point.hpp"
#include "probecomp/nurbs/degree_elevation.hpp"
#include "probecomp/registration/credibility.hpp"
#include "probecomp/registration/routes.hpp"

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

// Raw centre k as the smallest tip's centre would be: a larger tip's moved in by the difference of their radii
// along the outward normal (machine frame) of `fit` at `at` (the face's fitted centre surface, whose outward side
// is `outward`), or where there is no fit or it has no normal there, of the registered nominal face at the
// point's correspondence. Exact when the normal is the actual surface's.
Point3 as_smallest_tip(const PreparedModel& prepared, const registration::RegistrationResult& registration,
                       std::span<const Point3> raw, std::size_t k, const nurbs::Surface* fit = nullptr,
                       int outward = 1, fitting::SurfaceParameter at = {}) {
  const geometry::TipRadii& radii = prepared.radii;
  if (radii.uniform() || radii[k] == radii.smallest()) return raw[k];
  Vector3 normal = Vector3::Zero();
  if (fit != nullptr) {
    const nurbs::UnitNormal n = nurbs::unit_normal(*fit, at.u, at.v);
    if (n.status != nurbs::UnitNormal::Status::Degenerate) normal = static_cast<double>(outward) * n.n;
  }
  if (normal == Vector3::Zero()) {
    const registration::PointMatch& m = registration.matches[k];
    normal = registration.transform.linear() * prepared.nominal_locator->outward_normal(m.face, m.u, m.v);
  }
  return raw[k] - (radii[k] - radii.smallest()) * normal;
}

// How far off along the normal a contact point offset by r can be when the fit's normal is θ from the actual one.
double normal_doubt(double r, double theta) { return std::isnan(theta) ? r : r * (1.0 - std::cos(theta)); }
// That doubt is worth a warning from a micrometre (mm): what the users' tolerances are stated to.
constexpr double kNormalDoubtReported = 1e-3;

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

std::string mm(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

std::string um(double v_mm) { return mm(1e3 * v_mm) + " um"; }

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
  std::vector<Point3> subset = geometry::spread_subset(points, 257);
  if (subset.empty()) throw InputError("no finite points to compensate");
  const geometry::RigidTransform to_cad = initial.inverse();
  for (Point3& p : subset) p = to_cad * p;
  const std::vector<cad::ModelPoint> feet = locator.closest_points(subset);
  std::vector<double> d;
  for (const cad::ModelPoint& m : feet) d.push_back(m.ok() ? std::abs(m.distance) : std::numeric_limits<double>::infinity());
  const double median = geometry::upper_median_in_place(d);
  const double limit = fraction * box.diagonal();
  if (!(median <= limit)) {
    throw InputError("the points are nowhere near the model: their median distance from it is " + mm(median) +
                                " mm, more than " + mm(limit) + " mm (" + mm(100 * fraction) +
                                " % of its size); check the CAD file, the frame and the units");
  }
}

// Points identical to within this (mm) are one position: far below any CMM's resolution, far above rounding.
constexpr double kSamePosition = 1e-9;
// Points whose spread across their main direction is below this fraction of the spread along it lie on a line.
// A scan line across a curved face bends by far more (the free-form panel's shallowest line: 1e-3 of its length).
constexpr double kLineRatio = 1e-6;

// Refuses a point set that cannot fix the part (issue 20): every point at one position (a probe that did not
// move, a file of repeated rows), or all on one line (about which nothing fixes the part's rotation, and across
// which no surface is measured). Principal spreads from the points' covariance.
void check_point_spread(std::span<const Point3> raw) {
  const geometry::PrincipalAxes axes = geometry::principal_axes(raw);
  const std::size_t n = axes.count;
  if (n == 0) throw InputError("no finite points to compensate");
  const Point3& centre = axes.centroid;
  const Eigen::Vector3d& spread = axes.spread;  // ascending
  if (spread[2] <= kSamePosition) {
    throw InputError("all " + std::to_string(n) + " points are at one position (" + mm(centre.x()) + ", " +
                     mm(centre.y()) + ", " + mm(centre.z()) +
                     "): they fix neither the part's position nor any surface");
  }
  if (spread[1] <= std::max(kLineRatio * spread[2], kSamePosition)) {
    throw InputError("the " + std::to_string(n) + " points lie on one line (spread " + mm(spread[1]) +
                     " mm across it, " + mm(spread[2]) +
                     " mm along it): they cannot fix the part's rotation about that line nor measure a surface");
  }
}

// The fit's per-point results for every member of a face, from those of the member's position among the points
// fitted (`position`: member → fitted point).
void per_member(fitting::AdaptiveFitResult& fit, std::span<const std::uint32_t> position) {
  auto expand = [&](auto& values) {
    std::remove_reference_t<decltype(values)> out(position.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, position.size(), 1 << 14), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) out[i] = values[position[i]];
    });
    values = std::move(out);
  };
  expand(fit.params);
  expand(fit.residuals);
  expand(fit.variance_factor);
  expand(fit.misfit);
}

// What the user must know about a registration: its notes, an iteration limit reached, and the motions the data
// do not fix (held at the start: the deviations are blind to them).
void registration_warnings(const registration::RegistrationResult& r, std::vector<std::string>& warnings) {
  warnings.insert(warnings.end(), r.notes.begin(), r.notes.end());
  if (r.status == registration::Status::MaxIterations) {
    warnings.push_back("the registration did not converge: " + r.stop_reason);
  }
  for (const registration::FreeMotion& f : r.constraints.free) {
    const Vector3 d = r.transform.linear() * f.direction;  // machine frame
    std::string what = f.kind == registration::FreeMotion::Kind::Translation ? "translation along (" : "rotation about (";
    what += mm(d.x()) + ", " + mm(d.y()) + ", " + mm(d.z()) + ")";
    if (f.kind == registration::FreeMotion::Kind::Rotation) {
      const Point3 c = r.transform * f.through;
      what += " through (" + mm(c.x()) + ", " + mm(c.y()) + ", " + mm(c.z()) + ")";
    }
    warnings.push_back("the points do not fix the part's " + what +
                       ": it was held at the starting alignment, and the deviations cannot show it");
  }
}

// Rounds of the coarse alignment at most (each 13 starts on a 512-point subset).
constexpr int kCoarseRounds = 3;
// A start must lower the registration score by this fraction to be taken over the one before.
constexpr double kBetterScore = 0.05;
// A registration nothing fits better is still refused when more than this share of the points sit over r/2 inside
// the material. Measured: the cylinder study's 1.5 mm sine (r = 1 mm), a right registration, has 21 %; the
// die-cast sample 10° off, registered on the wrong side of its walls, 29–45 %.
constexpr double kMaxInsideShareKept = 0.25;

constexpr const char* kNotFitted = "not fitted: ";
constexpr const char* kOffsetAlongNominal = "; its points are offset along the nominal normal";

// Faces that hold points but were not fitted, and why (the user can measure more there): one warning, the faces
// with the most points first, at most kListedFaces of them by name.
void unfitted_face_warnings(const std::vector<FaceReport>& faces, std::vector<std::string>& warnings) {
  constexpr std::size_t kListedFaces = 5;
  std::vector<const FaceReport*> unfitted;
  int points = 0;
  for (const FaceReport& f : faces) {
    if (f.fitted || f.points == 0) continue;
    unfitted.push_back(&f);
    points += f.points;
  }
  if (unfitted.empty()) return;
  std::stable_sort(unfitted.begin(), unfitted.end(), [](const FaceReport* a, const FaceReport* b) { return a->points > b->points; });
  std::string w = std::to_string(unfitted.size()) + " face" + (unfitted.size() == 1 ? "" : "s") + " with points " +
                  (unfitted.size() == 1 ? "was" : "were") + " not fitted; their " + std::to_string(points) +
                  " points are offset along the nominal normal (status few-points or edge)";
  for (std::size_t k = 0; k < std::min(unfitted.size(), kListedFaces); ++k) {
    // The face's reason without what the whole warning already says.
    std::string why = unfitted[k]->stop_reason;
    if (why.starts_with(kNotFitted)) why.erase(0, std::string_view(kNotFitted).size());
    if (const auto tail = why.find(kOffsetAlongNominal); tail != std::string::npos) why.erase(tail);
    w += (k == 0 ? ": " : "; ") + std::string("face ") + std::to_string(unfitted[k]->face) + ", " + why;
  }
  if (unfitted.size() > kListedFaces) w += "; ... (every face in --json)";
  warnings.push_back(w);
}

void check_registration(const registration::RegistrationResult& r) {
  if (r.status == registration::Status::TooFewPoints || r.status == registration::Status::NumericalError) {
    throw RegistrationError(std::string("registration failed (") + registration::to_string(r.status) + "): " +
                                r.stop_reason);
  }
}

// The distance of x from its foot point on `face`, + on the outward side. Only the side is taken from the normal,
// so Newton's own tangents serve where it gives them and they are not (nearly) parallel: one evaluation fewer a
// point (a million deviations: 2 evaluations each instead of 3).
double signed_distance(const cad::Face& face, const Point3& x, const nurbs::ClosestPointResult& foot) {
  Vector3 n = foot.Su.cross(foot.Sv);
  if (!(n.norm() > 1e-8 * foot.Su.norm() * foot.Sv.norm())) n = nurbs::unit_normal(face.surface, foot.u, foot.v).n;
  const double side = (x - foot.point).dot(static_cast<double>(face.outward) * n);
  return side < 0.0 ? -foot.distance : foot.distance;
}

// What both methods and prepare_model need before anything else.
void check_model_and_radii(const cad::Model& model, const geometry::TipRadii& radii, std::size_t points) {
  if (!(radii.smallest() > 0.0) || !std::isfinite(radii.largest())) {
    throw InputError("the probe radius must be a positive number of mm");
  }
  if (!radii.uniform() && radii.count() != points) {
    throw InputError("the points have " + std::to_string(radii.count()) + " tip radii for " + std::to_string(points) +
                     " points");
  }
  if (model.faces.empty()) throw InputError("the CAD model has no faces");
}

// The tip radius of every point: probe_radii where given (each checked, naming the point), else probe_radius.
geometry::TipRadii tip_radii(const CompensateOptions& options, std::size_t points) {
  if (options.probe_radii.empty()) return geometry::TipRadii(options.probe_radius);
  if (options.probe_radii.size() != points) {
    throw InputError("the points have " + std::to_string(options.probe_radii.size()) + " tip radii for " +
                     std::to_string(points) + " points");
  }
  for (std::size_t k = 0; k < points; ++k) {
    const double r = options.probe_radii[k];
    if (!(r > 0.0) || !std::isfinite(r)) {
      throw InputError("point " + std::to_string(k + 1) + ": the tip radius must be a positive number of mm, not " +
                       mm(r));
    }
  }
  return geometry::TipRadii(options.probe_radii);
}


// Why a face's fit stopped, in one line.
std::string fit_stop_reason(const fitting::AdaptiveFitResult& fit, const fitting::AdaptiveFitOptions& options) {
  using S = fitting::AdaptiveFitResult::Status;
  switch (fit.status) {
    case S::OK: return "every span's residuals are consistent with the noise estimate";
    case S::NoiseNotReached:
      return std::to_string(fit.spans_above_noise) + " span(s) still above the noise: " +
             (fit.rounds >= options.max_rounds ? "the refinement rounds ran out"
                                               : "the points support no more control points");
    case S::NotDone: return "the fit could not be set up (too few usable points for its control points)";
    case S::NumericalError: return "the fit's normal equations could not be solved";
  }
  return "?";
}

}  // namespace

const char* to_string(Method m) { return m == Method::Cad ? "cad" : "conventional"; }

const char* to_string(PointStatus s) {
  switch (s) {
    case PointStatus::Ok: return "ok";
    case PointStatus::Outlier: return "outlier";
    case PointStatus::Edge: return "edge";
    case PointStatus::DoubleContact: return "double-contact";
    case PointStatus::FewPoints: return "few-points";
    case PointStatus::NotOnModel: return "not-on-model";
    case PointStatus::Failed: return "failed";
  }
  return "?";
}

Statistics statistics(std::span<const CompensatedPoint> points) {
  Statistics st;
  st.total = static_cast<int>(points.size());
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  st.deviation_min = std::numeric_limits<double>::infinity();
  st.deviation_max = -std::numeric_limits<double>::infinity();
  for (const CompensatedPoint& p : points) {
    ++st.counts[static_cast<int>(p.status)];
    if (p.status != PointStatus::Ok) continue;
    ++n;
    sum += p.deviation;
    st.deviation_min = std::min(st.deviation_min, p.deviation);
    st.deviation_max = std::max(st.deviation_max, p.deviation);
  }
  if (n == 0) {
    st.deviation_min = st.deviation_max = 0.0;
    return st;
  }
  st.deviation_mean = sum / n;
  // Two passes: the spread of micrometre deviations about a mean that may be millimetres is kept exactly.
  for (const CompensatedPoint& p : points) {
    if (p.status == PointStatus::Ok) sum2 += (p.deviation - st.deviation_mean) * (p.deviation - st.deviation_mean);
  }
  st.deviation_std = std::sqrt(sum2 / n);
  return st;
}

PreparedModel prepare_model(const cad::Model& model, const geometry::TipRadii& radii, std::span<const Point3> raw,
                            std::optional<std::span<const Vector3>> approach_normals, const PrepareOptions& options) {
  check_model_and_radii(model, radii, raw.size());
  const geometry::Stopwatch clock;
  const double probe_radius = radii.smallest();
  PreparedModel p;
  p.radii = radii;
  p.probe_radius = probe_radius;
  auto nominal = std::make_unique<cad::Model>(model);  // a copy: the material side is decided into its faces' `outward`
  // One locator of the nominal model serves the material side's votes and everything after (it reads each face's
  // `outward` as it answers, so the decision does not stale it).
  p.nominal_locator = std::make_unique<cad::ModelLocator>(*nominal);
  p.material = cad::decide_material_side(*nominal, *p.nominal_locator, raw, approach_normals, options.initial);
  if (options.flip_data_sides || !options.flip_faces.empty()) {
    for (std::size_t f = 0; f < p.material.size(); ++f) {
      if (p.material[f].source != cad::MaterialSource::Data) continue;
      const bool listed = std::find(options.flip_faces.begin(), options.flip_faces.end(), static_cast<int>(f)) !=
                          options.flip_faces.end();
      if (options.flip_data_sides == listed) continue;
      nominal->faces[f].outward *= -1;
      p.material[f].outward = nominal->faces[f].outward;
      p.material[f].agreeing = p.material[f].points - p.material[f].agreeing;
      p.material[f].median_distance = -p.material[f].median_distance;
    }
  }
  auto offset = std::make_unique<cad::OffsetModel>(cad::offset_model(*nominal, probe_radius, options.offset));
  p.locator = std::make_unique<cad::ModelLocator>(offset->model);
  p.offset = std::move(offset);
  p.nominal = std::move(nominal);
  p.seconds = clock.seconds();
  return p;
}

registration::RegistrationResult register_centres(const PreparedModel& prepared, std::span<const Point3> raw,
                                                  const RegisterOptions& options) {
  check_points_near(*prepared.locator, raw, options.icp.initial, options.max_initial_distance_fraction);
  const std::vector<double> beyond = prepared.radii.beyond_smallest();
  registration::RegistrationResult r =
      registration::register_to_offset_model(*prepared.offset, *prepared.locator, raw, options.icp, beyond);
  check_registration(r);
  const geometry::TipRadii& radius = prepared.radii;
  const registration::Credibility first = registration::assess_registration(r, radius);
  if (first.ok()) return r;
  // Doubtful from the given start: ICP may have found a local minimum. Multi-start ICP from turned starts looks
  // for a better basin; each round starts from the best so far (a start that brought the model closer lets the
  // next turns reach what the first could not), until the registration is credible or no start fits better.
  registration::RegistrationResult best = std::move(r);
  double best_score = registration::registration_score(best, radius);
  registration::Credibility verdict = first;
  int starts = 1;
  bool moved = false;
  for (int round = 0; round < kCoarseRounds && !verdict.ok(); ++round) {
    // Turns of the best registration so far, and in the first round of the given start too: the local minimum ICP
    // fell into may be farther from the right one than the start was, or nearer.
    registration::RegistrationOptions again = options.icp;
    again.initial = best.transform;
    registration::CoarseAlignment coarse = registration::coarse_align(*prepared.locator, raw, radius, again);
    starts += coarse.starts;
    if (round == 0) {
      again.initial = options.icp.initial;
      const registration::CoarseAlignment from_start =
          registration::coarse_align(*prepared.locator, raw, radius, again);
      starts += from_start.starts;
      if (from_start.score < coarse.score) coarse = from_start;
    }
    again.initial = coarse.transform;
    registration::RegistrationResult candidate =
        registration::register_to_offset_model(*prepared.offset, *prepared.locator, raw, again, beyond);
    check_registration(candidate);
    const double score = registration::registration_score(candidate, radius);
    if (!(score < (1.0 - kBetterScore) * best_score)) break;
    best = std::move(candidate);
    best_score = score;
    verdict = registration::assess_registration(best, radius);
    moved = true;
  }
  best.starts = starts;
  const std::string tried = std::to_string(starts - 1) + " starts of a coarse alignment (ICP from the model turned " +
                            "about the points' principal axes)";
  if (verdict.ok()) {
    best.notes.push_back("the registration from the given start was not credible (" + first.reason + "); " + tried +
                         " found a credible one");
    return best;
  }
  // Nothing fits better: the figures may be the part's own form error, unless the data hardly touch the model or
  // most of them sit on its wrong side, where no deviation can be trusted.
  if (verdict.status == registration::Credibility::Status::LittleOverlap || verdict.inside_share > kMaxInsideShareKept) {
    throw RegistrationError("the registration is not credible: " + verdict.reason + "; " + tried +
                            " found none better. Give a rough alignment with --initial-transform T.txt (4 x 4, CAD -> "
                            "machine), or check the CAD file, the frame and the probe radius");
  }
  const std::string doubtful = "the registration is doubtful: " + verdict.reason + "; " + tried +
                               (moved ? " improved it but found no credible one" : " found none better");
  if (!options.accept_doubtful) {
    throw RegistrationError(doubtful + ". Give a rough alignment with --initial-transform T.txt (4 x 4, CAD -> machine); "
                            "if the part really deviates from its model by about the probe radius, "
                            "--accept-doubtful-registration runs on with a warning");
  }
  best.notes.push_back(doubtful + ", and was accepted as asked: these may be the part's own deviations, or a wrong pose");
  return best;
}

namespace {
// The two sides' robust scales must differ by this factor for the smaller to be believed. Registered to its wrong
// side, a curved face's centres miss the offset surface by what no rigid motion takes up (the offset's curvature
// differs by 2r: the free-form panel of issue 49, 40 µm against 3 µm); a flat face's, or one too gently curved for
// the noise and the part's own deformation to let it show, fit the two sides alike. The part's deformation is in
// both sides' residuals and can even favour the wrong side: measured on the shape suite, the right side's scale
// over the wrong one's 0.53–0.57 (the panel with a 0.15 mm bulge), 0.78 and 0.69 (creased and waved faces), but
// 1.10 (S10, a twisted and dented hood) and 1.44 (D228, a panel with a 0.23 mm crease). Hence 1.6, above the worst
// seen; below kClearSideContrast the choice is stated as weak in the warning, and a sound vote of where the
// centres lie (kSoundVote) decides instead.
constexpr double kSideContrast = 1.6;
constexpr double kClearSideContrast = 2.0;
// The share of a face's raw centres on one side of the nominal that makes that side's vote sound by itself.
constexpr double kSoundVote = 0.9;
}  // namespace

namespace {

// Each face whose side the raw centres decided, once more after registration: the sides were decided or turned
// together, but on a part of several open faces the pose is the large face's, and a small face's centres (touches
// near its edge with the large one) voted before registration as the misalignment put them. Registered, a face on
// its wrong side has its centres a probe diameter inside the material (median signed distance from the nominal
// below −r/2, where r from its probe side): turned, and registered again from the pose found. (A surface of IGES
// example surf128, 1.2° off, no i,j,k: two of its four faces on the wrong side, 298 rows `ok` and 2 mm off.) A lone
// face decides its own pose, so this says nothing of it: the two sides' registrations do.
PreparedRegistration settle_each_face(const cad::Model& model, const geometry::TipRadii& radii, std::span<const Point3> raw,
                                      std::optional<std::span<const Vector3>> approach_normals,
                                      const PrepareOptions& used, const RegisterOptions& options,
                                      PreparedRegistration chosen) {
  const std::vector<cad::MaterialSide>& sides = chosen.prepared.material;
  const auto data_faces = std::count_if(sides.begin(), sides.end(),
                                        [](const cad::MaterialSide& m) { return m.source == cad::MaterialSource::Data; });
  const auto with_points = std::count_if(sides.begin(), sides.end(), [](const cad::MaterialSide& m) { return m.points > 0; });
  if (data_faces == 0 || with_points < 2) return chosen;
  // The offset model's distances plus its radius: each centre's distance from the nominal face, about its tip's
  // radius on the probe side.
  std::vector<std::vector<double>> distance(sides.size());
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const registration::PointMatch& m = chosen.registration.matches[k];
    if (!m.ok() || m.on_edge || !raw[k].allFinite()) continue;
    if (sides[static_cast<std::size_t>(m.face)].source != cad::MaterialSource::Data) continue;
    distance[static_cast<std::size_t>(m.face)].push_back(m.distance + radii.smallest());
  }
  PrepareOptions again = used;
  std::string turned;
  for (std::size_t f = 0; f < sides.size(); ++f) {
    if (distance[f].empty()) continue;
    const double median = geometry::median_in_place(distance[f]);
    if (!(median < -0.5 * radii.smallest())) continue;
    again.flip_faces.push_back(static_cast<int>(f));
    turned += (turned.empty() ? "" : ", ") + std::to_string(model.faces[f].index) + " (median " + mm(median) + " mm)";
  }
  if (turned.empty()) return chosen;
  RegisterOptions from_here = options;
  from_here.icp.initial = chosen.registration.transform;
  PreparedModel p = prepare_model(model, radii, raw, approach_normals, again);
  registration::RegistrationResult r = register_centres(p, raw, from_here);
  r.notes = std::move(chosen.registration.notes);
  r.notes.push_back("face(s) " + turned + " turned to the other side after registration: their centres lay inside the "
                    "material, at that median distance from the nominal");
  return {std::move(p), std::move(r)};
}

}  // namespace

PreparedRegistration prepare_and_register(const cad::Model& model, const geometry::TipRadii& radii,
                                          std::span<const Point3> raw, std::optional<std::span<const Vector3>> approach_normals,
                                          const PrepareOptions& prepare, const RegisterOptions& options) {
  PreparedModel first = prepare_model(model, radii, raw, approach_normals, prepare);
  std::string faces;
  for (std::size_t f = 0; f < first.material.size(); ++f) {
    if (first.material[f].source != cad::MaterialSource::Data) continue;
    faces += (faces.empty() ? "" : ", ") + std::to_string(first.nominal->faces[f].index);
  }
  if (faces.empty()) {
    registration::RegistrationResult r = register_centres(first, raw, options);
    return {std::move(first), std::move(r)};
  }
  // The other hypothesis turns every such face at once: a part's open faces are measured in one pose, so the
  // centres' side of each is wrong or right together, not face by face.
  PrepareOptions other_options = prepare;
  other_options.flip_data_sides = !prepare.flip_data_sides;
  PreparedModel other = prepare_model(model, radii, raw, approach_normals, other_options);
  // Each side's registration, or why it could not be made credible.
  struct Attempt {
    std::optional<registration::RegistrationResult> r;
    std::string error;
  };
  auto attempt = [&](const PreparedModel& p) {
    Attempt a;
    try {
      a.r = register_centres(p, raw, options);
    } catch (const RegistrationError& e) {
      a.error = e.what();
    }
    return a;
  };
  Attempt a = attempt(first), b = attempt(other);
  const std::string which = "the material side of face" + std::string(faces.find(',') != std::string::npos ? "s " : " ") +
                            faces + " (no approach normals, no closed solid)";
  if (!a.r && !b.r) throw RegistrationError(a.error);
  auto keep = [&](PreparedModel& p, registration::RegistrationResult& r, const std::string& why) {
    r.notes.push_back(which + " " + why);
    const PrepareOptions& used = &p == &first ? prepare : other_options;
    return settle_each_face(model, radii, raw, approach_normals, used, options,
                            PreparedRegistration{std::move(p), std::move(r)});
  };
  if (!b.r) return keep(first, *a.r, "was decided from the data: registered to the other side, " + b.error);
  if (!a.r) return keep(other, *b.r, "was decided by registering to both sides: the side the centres first lay on " +
                                         std::string("gave none credible (") + a.error + ")");
  const double sa = a.r->scale, sb = b.r->scale;
  auto figures = [](double keep_scale, double other_scale) {
    return "robust scale of the residuals " + um(keep_scale) + " against " + um(other_scale) + " on the other side" +
           (other_scale < kClearSideContrast * keep_scale
                ? std::string(" (a weak contrast: give each point's approach normal (i,j,k) to be sure)")
                : std::string());
  };
  // Where the centres lie before registration is a test of its own, sound when nearly all of them lie on one side:
  // the pose is then off by less than r where it matters (every centre on the wrong side needs the part moved more
  // than r along the face's normal). It failed on the panel of issue 49, 1–2° off, its centres on both sides. The
  // fit overrules a sound vote only when its contrast is clear (kClearSideContrast).
  double least_share = 1.0;
  for (const cad::MaterialSide& m : first.material) {
    if (m.source == cad::MaterialSource::Data && m.points > 0) {
      least_share = std::min(least_share, static_cast<double>(m.agreeing) / m.points);
    }
  }
  const bool sound_vote = least_share >= kSoundVote;
  const std::string vote = "where the centres lie before registration (" + mm(100.0 * least_share) + " % on one side)";
  if (sb * kClearSideContrast <= sa) {
    return keep(other, *b.r, "was decided by registering to both sides, against the side the centres first lay on: " + figures(sb, sa));
  }
  if (sa * kClearSideContrast <= sb) return keep(first, *a.r, "was decided by registering to both sides: " + figures(sa, sb));
  if (sound_vote) {
    return keep(first, *a.r, "was decided by " + vote + ", the two sides fitting too alike to tell: " + figures(sa, sb));
  }
  if (sb * kSideContrast <= sa) {
    return keep(other, *b.r, "was decided by registering to both sides, against the side the centres first lay on: " + figures(sb, sa));
  }
  if (sa * kSideContrast <= sb) return keep(first, *a.r, "was decided by registering to both sides: " + figures(sa, sb));
  throw RegistrationError("cannot tell " + which + ": registered to either side, the centres fit about as well (robust "
                          "scale of the residuals " + um(sa) + " and " + um(sb) + "), and before registration only " +
                          mm(100.0 * least_share) + " % of them lie on one side. Give each point's approach normal "
                          "(i,j,k) or a CAD model whose faces bound a solid");
}

namespace {

// A tip against a second face: its centre within this much (mm) as near that face's offset as its own, at most ...
double contact_tolerance(double noise, double probe_radius) {
  // Four noise σ: a tip on one face alone is rarely that close to a second by chance. At most 2 % of r: past
  // that, the second face's foot near a smooth continuation of the first (a tangent fillet) would be within
  // reach too, at an angle between their normals of up to √(2·tol/r) = 11°, under kMinContactAngle.
  constexpr double kNoiseSigmas = 4.0;
  constexpr double kMaxFractionOfRadius = 0.02;
  constexpr double kFloor = 1e-3;
  return std::min(std::max(kNoiseSigmas * noise, kFloor), kMaxFractionOfRadius * probe_radius);
}
// ... and with normals this far apart (degrees): two faces meeting at a concave edge, not one continuing smoothly.
constexpr double kMinContactAngle = 15.0;

}  // namespace

std::vector<int> second_contacts(const PreparedModel& prepared, std::span<const Point3> raw,
                                 const registration::RegistrationResult& registration) {
  const double min_cos = std::cos(kMinContactAngle * std::numbers::pi / 180.0);
  const geometry::RigidTransform to_cad = registration.transform.inverse();
  return geometry::parallel_map<int>(raw.size(), 64, [&](std::size_t k) {
    const registration::PointMatch& m = registration.matches[k];
    if (!m.ok() || m.on_edge || !raw[k].allFinite()) return -1;
    // On the nominal model: the tip's centre is r + its deviation from the face it touches. The other face's
    // contact direction is from its foot to the centre (its normal inside the face; across a convex edge shared
    // with the first face, nearly the first face's normal, which is one contact, not two).
    const Point3 c = to_cad * raw[k];
    const double r = prepared.radii[k];
    const double tol = contact_tolerance(registration.scale, r);
    const cad::ModelPoint other = prepared.nominal_locator->closest_point_on_other_faces(c, m.face, std::abs(r + m.distance) + tol);
    if (other.face < 0 || !other.ok()) return -1;
    const Vector3 n = prepared.nominal_locator->outward_normal(m.face, m.u, m.v);
    return n.dot((c - other.point).normalized()) < min_cos ? other.face : -1;
  });
}

FitResult fit_faces(const PreparedModel& prepared, std::span<const Point3> raw,
                    const registration::RegistrationResult& registration, const FitOptions& options,
                    const StepProgress& progress) {
  const geometry::Stopwatch clock;
  const cad::Model& work = *prepared.nominal;
  const geometry::RigidTransform& T = registration.transform;
  FitResult out;
  out.second_contact = second_contacts(prepared, raw, registration);
  // Points by face (their correspondences); edge and double-contact points count in their face's report but are
  // never fitted.
  std::map<int, FaceFit> by_face;
  auto member = [&](std::size_t k) {
    const registration::PointMatch& m = registration.matches[k];
    return m.ok() && raw[k].allFinite() && !m.on_edge && out.second_contact[k] < 0;
  };
  // Counted first, so that each face's member list is allocated once, at its size; by face position in arrays
  // (a map's lookup for each of a million points took 30 ms).
  const std::size_t n_faces = work.faces.size();
  std::vector<std::size_t> member_count(n_faces, 0), point_count(n_faces, 0);
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const registration::PointMatch& m = registration.matches[k];
    if (!m.ok() || !raw[k].allFinite()) continue;
    const std::size_t f = static_cast<std::size_t>(m.face);
    ++point_count[f];
    if (member(k)) ++member_count[f];
  }
  std::vector<std::vector<std::uint32_t>*> members_of(n_faces, nullptr);
  for (std::size_t f = 0; f < n_faces; ++f) {
    if (point_count[f] == 0) continue;
    FaceFit& ff = by_face[static_cast<int>(f)];
    ff.report.points = static_cast<int>(point_count[f]);
    ff.members.reserve(member_count[f]);
    members_of[f] = &ff.members;
  }
  for (std::size_t k = 0; k < raw.size(); ++k) {
    if (member(k)) members_of[static_cast<std::size_t>(registration.matches[k].face)]->push_back(static_cast<std::uint32_t>(k));
  }

  std::size_t done = 0;
  for (auto& [f, ff] : by_face) {
    ff.face = f;
    const cad::Face& face = work.faces[static_cast<std::size_t>(f)];
    FaceReport& rep = ff.report;
    rep.face = face.index;
    rep.outward = face.outward;
    rep.material = prepared.material[static_cast<std::size_t>(f)].source;
    // A face that had no points nearest to it before registration kept the file's orientation.
    if (rep.material == cad::MaterialSource::NoPoints) rep.material = cad::MaterialSource::File;
    const std::vector<std::uint32_t>& members = ff.members;
    const nurbs::Surface start = fit_start(prepared.offset->model.faces[static_cast<std::size_t>(f)].surface, T);
    // The members' centres as the smallest tip's would be: a larger tip's moved in by the difference along the
    // registered nominal normal, and once there is a fit, along the fit's own (see the refits below).
    bool mixed = false;
    for (std::size_t k : members) mixed = mixed || prepared.radii[k] != prepared.radii.smallest();
    std::vector<Point3> member_points(members.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, members.size(), 1 << 14), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) member_points[i] = as_smallest_tip(prepared, registration, raw, members[i]);
    });
    // A point at an earlier point's position (a reading recorded twice: a scanner's repeated sample, a row copied)
    // is one observation: fitted once. Counted twice it would be its own nearest neighbour, so the noise estimate
    // (differences of neighbouring residuals) would read low, the cross-validation would take the copies as
    // confirming each other, and the fit would chase the noise (10 % repeated on the free-form case: 1 927
    // control points instead of 783).
    // With each point's nearest other (the fit's noise estimate takes differences of neighbouring residuals), from
    // the same k-d tree.
    geometry::NearestAndFirst around = geometry::nearest_other_and_first(member_points, kSamePosition);
    const std::vector<std::uint32_t>& first = around.first;
    std::vector<std::uint32_t> position(members.size());  // member → its position among the fitted points
    std::vector<Point3> pts;
    std::vector<std::uint32_t> fitted_point;  // fitted point → its input index
    std::vector<fitting::SurfaceParameter> params;
    // Each member's position among the fitted points (a repeat takes its first's). The members' centres are
    // compacted in place into the fitted points (a position is never past its member: forward, nothing is
    // overwritten before it is read), not copied: a second array of them would be the fit's peak (a million points:
    // 24 MB, 24 bytes a point). The other arrays are filled at those positions in parallel.
    std::size_t kept = 0;
    pts = std::move(member_points);
    for (std::size_t i = 0; i < members.size(); ++i) {
      if (first[i] != i) {
        position[i] = position[first[i]];
        ++rep.repeated;
      } else {
        position[i] = static_cast<std::uint32_t>(kept);
        pts[kept++] = pts[i];
      }
    }
    pts.resize(kept);
    fitted_point.resize(kept);
    params.resize(kept);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, members.size(), 1 << 14), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        if (first[i] != i) continue;
        fitted_point[position[i]] = members[i];
        params[position[i]] = {registration.matches[members[i]].u, registration.matches[members[i]].v};
      }
    });
    const double needed = options.min_points_per_control_point * start.num_u() * start.num_v();
    std::optional<fitting::AdaptiveFitResult>& fit = ff.fit;
    std::vector<double> weights(pts.size(), 1.0);
    // Each point's nearest other point, once per face for all its refits. Without repeats the fitted points are the
    // members in order, whose nearest are at hand; with them, found again among the points kept.
    const std::vector<std::uint32_t> nearest = rep.repeated == 0 ? std::move(around.nearest) : fitting::nearest_neighbours(pts);
    around = {};
    std::vector<char> in_fit;  // per fitted point: 1 where the last fit used it
    // Points along a scanning probe's lines are predicted from their own line's neighbours whatever the fit does
    // between the lines: their smoothing is chosen by leaving a knot span's points out at once (penalized.hpp).
    // Elsewhere a point alone: a narrow, steep feature on a grid wants the fit that leave-one-out chooses (a dent of
    // 19° flanks without noise: largest error 0.5 µm, against 4.5 µm left out by spans).
    fitting::AdaptiveFitOptions surface = options.surface;
    NormalCheck normal_check;
    normal_check.along_lines = sampled_along_lines(pts);
    // Nor is the energy made anisotropic there: a penalty that lets the fit bend freely across the lines lets it
    // ring between them (shape suite, S13 without noise: std 4.6 -> 31 um with it).
    if (*normal_check.along_lines) {
      surface.fit.cross_validation = fitting::CrossValidation::LeaveSpanOut;
      surface.fit.anisotropic = false;
    }
    auto refit = [&](const nurbs::Surface& from, std::span<const fitting::SurfaceParameter> at) {
      in_fit.resize(pts.size());
      for (std::size_t j = 0; j < pts.size(); ++j) in_fit[j] = weights[j] > 0.0;
      fit = fitting::fit_surface(from, pts, at, weights, surface, nearest);
      ++rep.fits;
      rep.rounds += fit->rounds;
    };
    std::vector<char> outlier(pts.size(), 0);
    if (static_cast<double>(pts.size()) >= needed) {
      // Outliers are decided against the fit itself (compensation/outliers.hpp), left out, and the face refitted,
      // until the set left out no longer changes: a point left out is taken back when the fit made without it
      // predicts it within its bound (a point a fit bent by a gross error had pushed out), so that the set left
      // out is the one the final fit agrees with.
      bool moved_along_fit = false;
      for (int attempt = 0; attempt < kMaxOutlierFits; ++attempt) {
        // A refit starts over from the registered offset face: the first fit's refinement and adaptive penalty
        // may have followed the gross errors it then found, and would keep their marks.
        refit(start, params);
        if (!fit->fitted()) break;
        // The first fit, gross errors and all, against the face's noise; the refits without them against the
        // spread around each point (compensation/outliers.hpp).
        outlier = outliers_against_fit(*fit, weights, options.outliers, attempt == 0 ? Spread::Face : Spread::Local);
        int changed = 0;
        double largest = 0.0;
        for (std::size_t i = 0; i < pts.size(); ++i) {
          if ((weights[i] > 0.0) == !outlier[i]) continue;
          weights[i] = outlier[i] ? 0.0 : 1.0;
          ++changed;
          largest = std::max(largest, std::abs(fit->residuals[i]));
        }
        // Larger tips' centres were moved in along the nominal normal, which is off the actual one by the part's
        // tilt θ there: an error of Δr·(1 − cos θ) (0.4 µm for Δr = 0.5 mm at 2°). Moved again along the fit's
        // normal, once, and refitted.
        const bool move_again = mixed && !moved_along_fit;
        if (move_again) {
          for (std::size_t j = 0; j < pts.size(); ++j) {
            pts[j] = as_smallest_tip(prepared, registration, raw, fitted_point[j], &fit->surface, face.outward, fit->params[j]);
          }
          moved_along_fit = true;
        }
        if (!move_again && (changed == 0 || !moves_fit(largest, pts.size(), *fit))) break;
      }
    }
    rep.fitted = fit && fit->fitted();
    ff.trusted.resize(members.size());
    // Trusted: what the last fit says (a point taken back or left out after it keeps the last fit's verdict).
    ff.in_last_fit.resize(members.size());
    for (std::size_t i = 0; i < members.size(); ++i) {
      ff.trusted[i] = !outlier[position[i]];
      ff.in_last_fit[i] = in_fit.empty() || in_fit[position[i]];
    }
    if (rep.fitted) {
      std::vector<double> last_weights(in_fit.begin(), in_fit.end());
      const NormalDisagreement check = normal_disagreement(fit->surface, pts, fit->params, last_weights, normal_check);
      ff.normal_checked_along_lines = check.along_lines;
      if (!check.angle.empty()) {
        ff.normal_angle.resize(members.size());
        for (std::size_t i = 0; i < members.size(); ++i) ff.normal_angle[i] = check.angle[position[i]];
      }
      per_member(*fit, position);
      rep.fit_status = fit->status;
      rep.stop_reason = fit_stop_reason(*fit, options.surface);
      rep.control_points = fit->control_points;
      rep.rms = fit->rms;
      rep.max_residual = fit->max_residual;
      rep.noise_sigma = fit->noise_sigma;
      rep.effective_dof = fit->effective_dof;
      rep.log10_smoothing = fit->log10_smoothing;
      rep.centre_surface = fit->surface;
      ff.params = fit->params;
    } else {
      ff.params.resize(members.size());
      for (std::size_t i = 0; i < members.size(); ++i) ff.params[i] = params[position[i]];
      if (fit) {
        rep.fit_status = fit->status;
        rep.stop_reason = fit_stop_reason(*fit, options.surface) + kOffsetAlongNominal;
        fit.reset();
      } else {
        rep.stop_reason = kNotFitted + std::to_string(pts.size()) + " points off the edges for " +
                          std::to_string(start.num_u() * start.num_v()) + " control points (" + mm(needed) +
                          " needed)" + kOffsetAlongNominal;
      }
    }
    done += members.size();
    if (progress) progress(static_cast<double>(done) / static_cast<double>(std::max<std::size_t>(raw.size(), 1)));
  }
  out.faces.reserve(by_face.size());
  for (auto& [f, ff] : by_face) out.faces.push_back(std::move(ff));
  out.seconds = clock.seconds();
  return out;
}

std::vector<CompensatedPoint> compensate_points(const PreparedModel& prepared, std::span<const Point3> raw,
                                                const registration::RegistrationResult& registration,
                                                const FitResult& fits) {
  const cad::Model& work = *prepared.nominal;
  const geometry::TipRadii& radii = prepared.radii;
  const geometry::RigidTransform& T = registration.transform;
  std::vector<CompensatedPoint> out(raw.size());
  for (std::size_t k = 0; k < raw.size(); ++k) out[k].radius = radii[k];
  // Points no fit stands behind (past an edge, against two faces, on a face with too few points): the tip touched
  // the nominal part where it is nearest to the registered centre, on whichever face that is. Offset towards that
  // point (along its face's normal inside a face, towards the edge past one); the deviation is the centre's
  // distance from it less r.
  const geometry::RigidTransform to_cad = T.inverse();
  auto double_contact = [&](std::size_t k) { return !fits.second_contact.empty() && fits.second_contact[k] >= 0; };
  // Every point with a correspondence but not in a fitted face's fit (edge and double-contact points never are).
  std::vector<char> unfitted(raw.size(), 0);
  for (std::size_t k = 0; k < raw.size(); ++k) unfitted[k] = registration.matches[k].ok();
  for (const FaceFit& ff : fits.faces) {
    if (ff.report.fitted) {
      for (std::size_t k : ff.members) unfitted[k] = 0;
    }
  }
  // Each fitted face by position, for the rows past its edges.
  std::vector<const FaceFit*> fitted_face(work.faces.size(), nullptr);
  for (const FaceFit& ff : fits.faces) {
    if (ff.report.fitted && ff.fit) fitted_face[static_cast<std::size_t>(ff.face)] = &ff;
  }
  tbb::parallel_for(std::size_t{0}, raw.size(), [&](std::size_t k) {
    if (!unfitted[k] || !raw[k].allFinite()) return;
    const registration::PointMatch& m = registration.matches[k];
    cad::ModelPoint hint;
    hint.status = m.status;
    hint.face = m.face;
    hint.u = m.u;
    hint.v = m.v;
    const Point3 x = to_cad * raw[k];
    const cad::ModelPoint foot = prepared.nominal_locator->closest_point(x, hint);
    CompensatedPoint& c = out[k];
    if (!foot.ok() || !((x - foot.point).norm() > 0.0)) {
      c.status = PointStatus::Failed;
      return;
    }
    const Vector3 towards = (foot.distance < 0.0 ? -1.0 : 1.0) * (x - foot.point).normalized();
    c.status = m.on_edge ? PointStatus::Edge : double_contact(k) ? PointStatus::DoubleContact : PointStatus::FewPoints;
    c.face = work.faces[static_cast<std::size_t>(foot.face)].index;
    c.normal = T.linear() * towards;
    const double r = radii[k];
    c.contact = raw[k] - r * c.normal;
    c.deviation = foot.distance - (foot.distance < 0.0 ? -r : r);
    c.uncertainty = registration.scale;
    // A tip past a fitted face's edge touched the part's rim, which the part's deformation moved with the face: its
    // contact is taken on the nominal rim, and u says how far the face's fit puts the part from the nominal there.
    // (The fitted centre surface's displacement from the registered offset, less r times the turn of its normal:
    // a slope of 1° near the rim alone moves the centre surface 17 µm sideways at r = 1 mm.) Measured on the panel
    // with a 0.1 mm bump reaching its edge, 1.1° off: edge rows within 2u of the part 59 % -> 93 %.
    const FaceFit* ff = m.on_edge ? fitted_face[static_cast<std::size_t>(foot.face)] : nullptr;
    if (ff != nullptr) {
      const nurbs::Surface& offset = prepared.offset->model.faces[static_cast<std::size_t>(foot.face)].surface;
      const nurbs::UnitNormal n_fit = nurbs::unit_normal(ff->fit->surface, foot.u, foot.v);
      const nurbs::UnitNormal n_off = nurbs::unit_normal(offset, foot.u, foot.v);
      const double side = work.faces[static_cast<std::size_t>(foot.face)].outward;
      Vector3 moved = nurbs::evaluate(ff->fit->surface, foot.u, foot.v) - T * nurbs::evaluate(offset, foot.u, foot.v);
      if (n_fit.status != nurbs::UnitNormal::Status::Degenerate && n_off.status != nurbs::UnitNormal::Status::Degenerate) {
        moved -= prepared.probe_radius * side * (n_fit.n - T.linear() * n_off.n);
      }
      c.uncertainty = std::hypot(c.uncertainty, moved.norm());
    }
  });
  for (const FaceFit& ff : fits.faces) {
    if (!ff.report.fitted) continue;
    const cad::Face& face = work.faces[static_cast<std::size_t>(ff.face)];
    const std::vector<std::uint32_t>& members = ff.members;
    // The fit is of the smallest tip's centre surface: each member's centre moved onto it along the fit's normal.
    // In blocks, so that a face of a million points holds the contacts of a block at a time (96 bytes a point).
    constexpr std::size_t kBlock = 1 << 16;
    std::vector<Point3> pts;
    for (std::size_t first = 0; first < members.size(); first += kBlock) {
      const std::size_t count = std::min(kBlock, members.size() - first);
      pts.resize(count);
      for (std::size_t i = 0; i < count; ++i) {
        pts[i] = as_smallest_tip(prepared, registration, raw, members[first + i], &ff.fit->surface, face.outward,
                                 ff.params[first + i]);
      }
      const std::vector<ContactPoint> contacts = contact_points(
          ff.fit->surface, face.outward, radii.smallest(), pts, std::span(ff.params).subspan(first, count));
      for (std::size_t b = 0; b < count; ++b) {
        const std::size_t i = first + b;
        CompensatedPoint& c = out[members[i]];
        c.face = face.index;
        if (!contacts[b].ok()) {
          c.status = PointStatus::Failed;
          continue;
        }
        c.status = ff.trusted[i] ? PointStatus::Ok : PointStatus::Outlier;
        c.contact = contacts[b].contact;
        c.normal = contacts[b].normal;
        c.uncertainty = std::hypot(ff.fit->noise_sigma * std::sqrt(ff.fit->variance_factor[i]), ff.fit->misfit[i]);
        // An outlier's reading and the fit disagree by its residual, and which of them is right is not known (a
        // gross error, or shape the fit cannot follow): its u covers both. So does that of a point the last fit
        // left out but found within its bound (the refits ran out before taking it back): the fit there is a
        // prediction made without it (measured: a noise-free point 1.3 µm from such a prediction, u 0.18 µm).
        if (!ff.trusted[i] || !ff.in_last_fit[i]) c.uncertainty = std::hypot(c.uncertainty, ff.fit->residuals[i]);
        // Next to points left out, the fit's normal may not be what the data show: the contact point is then
        // r(1 − cos θ) off along it (normal_support.hpp). Where θ could not be told, the worst case: r.
        if (!ff.normal_angle.empty()) c.uncertainty = std::hypot(c.uncertainty, normal_doubt(radii[members[i]], ff.normal_angle[i]));
      }
    }
  }

  // Deviations of the fitted points: Newton from the correspondence's (u, v) (nominal and offset faces share their
  // parametrisation), with the face's global search where Newton fails.
  std::vector<char> retry(raw.size(), 0);
  tbb::parallel_for(std::size_t{0}, raw.size(), [&](std::size_t k) {
    CompensatedPoint& c = out[k];
    if (!c.computed() || unfitted[k]) return;
    const registration::PointMatch& m = registration.matches[k];
    const cad::Face& face = work.faces[static_cast<std::size_t>(m.face)];
    const Point3 x = to_cad * c.contact;
    const nurbs::ClosestPointResult foot = nurbs::refine_closest_point(face.surface, x, m.u, m.v);
    if (foot.ok()) {
      c.deviation = signed_distance(face, x, foot);
    } else {
      retry[k] = 1;
    }
  });
  // The registration's share of u, in quadrature with the fit's: the registered model's position along the
  // normal varies with the measurement noise as normal_variance says (most along weakly fixed motions). The noise
  // is the fits' estimate (their median over the fitted faces), not the registration's residual scale, which
  // holds the part's deformation too: that is what the deviations measure, not an uncertainty of where the
  // model sits.
  double noise = registration.scale;
  {
    std::vector<double> fitted_noise;
    for (const FaceFit& ff : fits.faces) {
      if (ff.report.fitted) fitted_noise.push_back(ff.fit->noise_sigma);
    }
    if (!fitted_noise.empty()) noise = geometry::median_in_place(fitted_noise);
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, raw.size(), 4096), [&](const auto& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      CompensatedPoint& c = out[k];
      if (!c.computed()) continue;
      const double reg = noise * noise * registration::normal_variance(registration.constraints, to_cad * c.contact,
                                                                      to_cad.linear() * c.normal);
      c.uncertainty = std::sqrt(c.uncertainty * c.uncertainty + std::max(reg, 0.0));
    }
  });
  std::map<int, nurbs::ClosestPointSolver> solvers;  // built for the faces that need one
  for (std::size_t k = 0; k < raw.size(); ++k) {
    if (!retry[k]) continue;
    const registration::PointMatch& m = registration.matches[k];
    const cad::Face& face = work.faces[static_cast<std::size_t>(m.face)];
    const nurbs::ClosestPointSolver& solver = solvers.try_emplace(m.face, face.surface).first->second;
    const Point3 x = to_cad * out[k].contact;
    const nurbs::ClosestPointResult foot = solver.closest_point(x);
    if (foot.ok()) {
      out[k].deviation = signed_distance(face, x, foot);
    } else {
      out[k].status = PointStatus::Failed;
      out[k].uncertainty = std::numeric_limits<double>::quiet_NaN();
    }
  }
  return out;
}

namespace {

CompensationResult compensate_conventional(const cad::Model& model, std::span<const Point3> raw,
                                           std::span<const Vector3> approach_normals, const geometry::TipRadii& radii,
                                           const CompensateOptions& options) {
  CompensationResult out;
  out.method = Method::Conventional;
  out.points.resize(raw.size());
  if (options.progress) options.progress("registration", 0.0);
  const geometry::Stopwatch clock;
  const std::vector<Point3> contacts = conventional_contact_points(raw, approach_normals, radii);
  const cad::ModelLocator locator(model);
  check_points_near(locator, contacts, options.registration.initial, options.max_initial_distance_fraction);
  out.registration = registration::register_points(locator, contacts, options.registration);
  check_registration(out.registration);
  out.seconds.registration = clock.seconds();
  std::map<int, FaceReport> reports;  // by position in model.faces
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const registration::PointMatch& m = out.registration.matches[k];
    CompensatedPoint& c = out.points[k];
    c.radius = radii[k];
    if (!m.ok() || !contacts[k].allFinite()) continue;
    const cad::Face& face = model.faces[static_cast<std::size_t>(m.face)];
    c.status = m.on_edge ? PointStatus::Edge : PointStatus::Ok;
    c.contact = contacts[k];
    c.normal = approach_normals[k].normalized();
    c.deviation = m.distance;
    c.face = face.index;
    FaceReport& rep = reports[m.face];
    rep.face = c.face;
    rep.outward = face.outward;
    rep.material = face.material_known ? cad::MaterialSource::Solid : cad::MaterialSource::File;
    rep.stop_reason = "not fitted: the conventional method offsets along the approach normals";
    ++rep.points;
  }
  for (auto& [f, rep] : reports) out.faces.push_back(std::move(rep));
  return out;
}

}  // namespace

namespace {

// Gross outliers the fits flagged still pulled on the registration through their robust weights (a point 0.1 mm out
// keeps a Cauchy weight near 0.4 at the usual scale). Registered again without them, from where the registration
// ended, the deviations (distances from the registered model) no longer depend on them: 1 % of the points 0.1–5 mm
// out moved the others' deviations by up to 0.52 µm before (Pipeline.GrossOutliersMoveNoOtherPoint). The flagged
// points keep their first correspondences (hints for their deviations). Kept as it was if ICP does not converge.
//
// Unless their pull is below ICP's own convergence tolerance: to first order, leaving points out moves the
// registration by the Gauss–Newton step of their weighted residuals, δ = H⁺ Σ w r J (H⁺ the registration's
// covariance per unit variance), and the data by at most |ω| R + |t| (R: the farthest point from H's centre). When
// that is within the tolerance ICP stops at, registering again could not be told from the registration there is
// (10 M points on the demo's panel: 7 flagged, a second registration of 26 s that moved nothing). Only for a few
// points (kMaxSkippedShare of those used): more, and the robust scale, and so every weight, moves with them too.
constexpr double kMaxSkippedShare = 1e-3;

bool outliers_move_registration(const PreparedModel& prepared, std::span<const Point3> raw,
                                const std::vector<std::size_t>& flagged, const registration::RegistrationOptions& icp,
                                const registration::RegistrationResult& r) {
  if (static_cast<double>(flagged.size()) > kMaxSkippedShare * static_cast<double>(r.used)) return true;
  const registration::Constraints& c = r.constraints;
  const geometry::RigidTransform to_cad = r.transform.inverse();
  geometry::Twist g = geometry::Twist::Zero();
  for (const std::size_t k : flagged) {
    const registration::PointMatch& m = r.matches[k];
    if (!(m.weight > 0.0)) continue;
    const Vector3 n = prepared.locator->outward_normal(m.face, m.u, m.v);
    geometry::Twist J;
    J.head<3>() = (to_cad * raw[k] - c.centre).cross(n) / c.length;
    J.tail<3>() = n;
    g += m.weight * m.distance * J;
  }
  const geometry::Twist delta = c.covariance * g;
  double reach = 0.0;  // the farthest point from H's centre, mm
  for (const Point3& x : raw) {
    if (x.allFinite()) reach = std::max(reach, (to_cad * x - c.centre).norm());
  }
  const double moved = delta.head<3>().norm() / c.length * reach + delta.tail<3>().norm();
  const double tolerance = std::max(icp.criteria.motion_tolerance, icp.criteria.relative_motion_tolerance * r.scale /
                                                                        std::sqrt(static_cast<double>(std::max<std::size_t>(r.used, 1))));
  return !(moved <= tolerance);
}

void register_without_outliers(const PreparedModel& prepared, std::span<const Point3> raw, const FitResult& fits,
                               const registration::RegistrationOptions& icp, registration::RegistrationResult& r) {
  std::vector<std::size_t> flagged;
  for (const FaceFit& ff : fits.faces) {
    for (std::size_t i = 0; i < ff.trusted.size(); ++i) {
      if (!ff.trusted[i]) flagged.push_back(ff.members[i]);
    }
  }
  if (flagged.empty() || !outliers_move_registration(prepared, raw, flagged, icp, r)) return;
  std::vector<Point3> kept(raw.begin(), raw.end());
  // Not finite: reported by ICP, never used.
  for (const std::size_t k : flagged) kept[k] = Point3::Constant(std::numeric_limits<double>::quiet_NaN());
  registration::RegistrationOptions again = icp;
  again.initial = r.transform;
  registration::RegistrationResult second = registration::register_to_offset_model(
      *prepared.offset, *prepared.locator, kept, again, prepared.radii.beyond_smallest());
  if (!second.converged()) return;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    if (!kept[k].allFinite()) second.matches[k] = r.matches[k];
  }
  second.iterations += r.iterations;
  second.searches += r.searches;
  second.coarse_iterations = r.coarse_iterations;
  second.starts = r.starts;
  second.left_out = static_cast<int>(flagged.size());
  second.notes = std::move(r.notes);
  r = std::move(second);
}

// Rows whose u is mostly the doubt about the fit's normal next to points left out or between scan lines
// (compensation/normal_support.hpp): one warning per face, with the largest angle and what it makes.
void normal_warnings(const FitResult& fits, const geometry::TipRadii& radii, std::span<const CompensatedPoint> points,
                     std::vector<std::string>& warnings) {
  for (const FaceFit& ff : fits.faces) {
    if (!ff.report.fitted || ff.normal_angle.empty()) continue;
    int doubtful = 0, unknown = 0;
    double largest_angle = 0.0, largest_doubt = 0.0;
    for (std::size_t i = 0; i < ff.members.size(); ++i) {
      const std::size_t k = ff.members[i];
      if (!points[k].computed()) continue;
      const double theta = ff.normal_angle[i], doubt = normal_doubt(radii[k], theta);
      if (std::isnan(theta)) {
        ++unknown;
      } else if (doubt > 0.5 * points[k].uncertainty && doubt > kNormalDoubtReported) {
        ++doubtful;
        largest_angle = std::max(largest_angle, theta);
        largest_doubt = std::max(largest_doubt, doubt);
      }
    }
    const std::string face = "face " + std::to_string(ff.report.face) + ": ";
    const bool lines = ff.normal_checked_along_lines;
    if (doubtful > 0) {
      char angle[32];
      std::snprintf(angle, sizeof angle, "%.1f", largest_angle * 180.0 / std::numbers::pi);
      const std::string rows = std::to_string(doubtful) + " row" + (doubtful == 1 ? "'s u holds" : "s' u hold") +
                               " the r(1 - cos θ) that makes, up to " + mm(largest_doubt) + " mm; ";
      warnings.push_back(
          lines ? face + "its points lie along lines, and between them the fitted normal is up to " + angle +
                      "° from what the neighbouring lines show (only the smoothing holds the fit across them): " + rows +
                      "measure lines closer together, or across these, to settle it"
                : face + "next to the points left out of its fit, the fitted normal is up to " + angle +
                      "° from what the centres around them show (the fit swings across the gap they leave): " + rows +
                      "measure more points there (with the outliers' cause removed) to settle it");
    }
    if (unknown > 0) {
      warnings.push_back(face + std::to_string(unknown) + " row" + (unknown == 1 ? "" : "s") +
                         (lines ? " along its scan lines" : " next to the points left out of its fit") +
                         " could not be checked against the centres around them (too few, or along one line): their "
                         "u holds the whole tip radius");
    }
  }
}

}  // namespace

CompensationResult compensate(const cad::Model& model, std::span<const Point3> raw,
                              std::optional<std::span<const Vector3>> approach_normals,
                              const CompensateOptions& options) {
  const geometry::TipRadii radii = tip_radii(options, raw.size());
  check_model_and_radii(model, radii, raw.size());
  if (raw.empty()) throw InputError("no points to compensate");
  // Points are indexed with 32 bits (the fit's members, the k-d trees).
  if (raw.size() > std::numeric_limits<std::uint32_t>::max()) throw InputError("more than 4 294 967 295 points");
  if (approach_normals && approach_normals->size() != raw.size()) {
    throw InputError("the approach normals do not match the points in number");
  }
  if (options.method == Method::Conventional && !approach_normals) {
    throw InputError(
        "the conventional method needs each point's approach normal (i,j,k) and the points have none; the CAD-based "
        "method does not need them");
  }
  check_point_spread(raw);
  auto step = [&](const std::string& name, double fraction) {
    if (options.progress) options.progress(name, fraction);
  };
  if (options.method == Method::Conventional) {
    CompensationResult out = compensate_conventional(model, raw, *approach_normals, radii, options);
    out.statistics = statistics(out.points);
    out.warnings = model.read_warnings;
    registration_warnings(out.registration, out.warnings);
    return out;
  }

  CompensationResult out;
  out.method = Method::Cad;
  step("prepare", 0.0);
  // The stages' shares of the time (1 M and 10 M points on the demo's panel: registration about half, the fit a
  // third, the contact points the rest), for a progress bar's time left.
  geometry::Stopwatch clock;
  PreparedRegistration located = prepare_and_register(
      model, radii, raw, approach_normals, {.offset = options.offset, .initial = options.registration.initial},
      {.icp = options.registration,
       .max_initial_distance_fraction = options.max_initial_distance_fraction,
       .accept_doubtful = options.accept_doubtful_registration});
  PreparedModel& prepared = located.prepared;
  out.registration = std::move(located.registration);
  out.seconds.prepare = prepared.seconds;
  out.centre_radius = prepared.probe_radius;
  out.material = prepared.material;
  out.seconds.registration = std::max(clock.restart() - prepared.seconds, 0.0);
  step("registration", 0.02);

  step("fitting", 0.5);
  FitResult fits = fit_faces(prepared, raw, out.registration, options.fit,
                                   [&](double fraction) { step("fitting", 0.5 + 0.33 * fraction); });
  out.seconds.fitting = clock.restart();

  register_without_outliers(prepared, raw, fits, options.registration, out.registration);
  out.seconds.registration += clock.restart();

  step("compensation", 0.83);
  out.points = compensate_points(prepared, raw, out.registration, fits);
  out.seconds.compensation = clock.restart();
  // Every computed point by its face (edge points are not members of their face's fit, but are its points).
  // (Runs of points share a face: its counts are looked up once a run, not once a point: 7 ms fewer at 1 M points.)
  std::map<int, std::array<int, std::size(kPointStatuses)>> by_face;
  int run_face = -1;
  std::array<int, std::size(kPointStatuses)>* run_counts = nullptr;
  for (const CompensatedPoint& c : out.points) {
    if (c.face < 0) continue;
    if (c.face != run_face) {
      run_face = c.face;
      run_counts = &by_face[c.face];
    }
    ++(*run_counts)[static_cast<std::size_t>(c.status)];
  }
  normal_warnings(fits, radii, out.points, out.warnings);
  for (FaceFit& ff : fits.faces) {
    FaceReport rep = std::move(ff.report);  // the fits are not needed past this point
    const auto counts = by_face.find(rep.face);
    if (counts != by_face.end()) std::copy(counts->second.begin(), counts->second.end(), rep.counts);
    double u_sum = 0.0;
    int u_count = 0;
    for (std::size_t i = 0; i < ff.members.size(); ++i) {
      const CompensatedPoint& c = out.points[ff.members[i]];
      if (c.computed()) {
        u_sum += c.uncertainty;
        ++u_count;
      }
    }
    rep.mean_uncertainty = u_count > 0 ? u_sum / u_count : 0.0;
    out.faces.push_back(std::move(rep));
  }
  out.statistics = statistics(out.points);
  out.warnings.insert(out.warnings.begin(), model.read_warnings.begin(), model.read_warnings.end());
  registration_warnings(out.registration, out.warnings);
  unfitted_face_warnings(out.faces, out.warnings);
  int repeated = 0;
  for (const FaceReport& rep : out.faces) repeated += rep.repeated;
  if (repeated > 0) {
    out.warnings.push_back(std::to_string(repeated) + " point" + (repeated == 1 ? " repeats" : "s repeat") +
                           " an earlier point's position exactly (a reading recorded twice): each position was "
                           "fitted once, and every row is compensated and reported");
  }
  step("done", 1.0);
  return out;
}

std::vector<nurbs::Surface> fitted_part_surfaces(const CompensationResult& result, const fitting::OffsetOptions& options) {
  const double probe_radius = result.centre_radius;
  std::vector<nurbs::Surface> out;
  for (const FaceReport& f : result.faces) {
    if (!f.fitted) continue;
    // The contact surface is the centre surface moved by r into the material, against the outward normal.
    const fitting::OffsetResult o = fitting::offset_surface(*f.centre_surface, -probe_radius * f.outward, options);
    if (o.status == fitting::OffsetResult::Status::Degenerate) {
      throw FitError("face " + std::to_string(f.face) + ": the fitted surface has no normal somewhere");
    }
    out.push_back(o.surface);
  }
  return out;
}

}  // namespace probecomp::compensation
