// compensate() and the steps prepare and register; the other steps are in material_sides.cpp (prepare_and_register),
// face_fits.cpp (fit_faces) and contact_points.cpp (compensate_points), with input_checks.cpp and warnings.cpp.

#include "probecomp/compensation/pipeline.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>

#include "probecomp/compensation/conventional.hpp"
#include "probecomp/compensation/qualified_radii.hpp"
#include "probecomp/error.hpp"
#include "probecomp/geometry/stopwatch.hpp"
#include "probecomp/registration/credibility.hpp"
#include "probecomp/registration/routes.hpp"
#include "probecomp/registration/sensitivity.hpp"

#include "input_checks.hpp"
#include "warnings.hpp"

namespace probecomp::compensation {

namespace {

using detail::check_model_and_radii;
using detail::check_point_spread;
using detail::check_points_near;
using detail::folded_offset_warnings;
using detail::normal_warnings;
using detail::outlier_group_warnings;
using detail::registration_warnings;
using detail::tip_radii;
using detail::unfitted_face_warnings;

// Rounds of the coarse alignment at most (each 13 starts on a 512-point subset).
constexpr int kCoarseRounds = 3;
// A start must lower the registration score by this fraction to be taken over the one before.
constexpr double kBetterScore = 0.05;
// A registration nothing fits better is still refused when more than this share of the points sit over r/2 inside
// the material. Measured: the cylinder study's 1.5 mm sine (r = 1 mm), a right registration, has 21 %; the
// die-cast sample 10° off, registered on the wrong side of its walls, 29–45 %.
constexpr double kMaxInsideShareKept = 0.25;

void check_registration(const registration::RegistrationResult& r) {
  if (r.status == registration::Status::TooFewPoints || r.status == registration::Status::NumericalError) {
    throw RegistrationError(std::string("registration failed (") + registration::to_string(r.status) + "): " +
                                r.stop_reason);
  }
}

// The part located by the points on its datum features alone, from `start` (RegisterOptions::datum_faces): kept when
// it converged, is credible on those points and they fix all six motions; else nothing, with why in `why_not`.
std::optional<registration::RegistrationResult> locate_by_datum_features(const PreparedModel& prepared,
                                                                         std::span<const Point3> raw,
                                                                         const geometry::RigidTransform& start,
                                                                         const RegisterOptions& options,
                                                                         std::string& why_not) {
  std::vector<int> positions;  // in the offset model's faces
  const std::vector<cad::Face>& faces = prepared.offset->model.faces;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    if (std::find(options.datum_faces.begin(), options.datum_faces.end(), faces[f].index) != options.datum_faces.end()) {
      positions.push_back(static_cast<int>(f));
    }
  }
  registration::RegistrationOptions icp = options.icp;
  icp.initial = start;
  const std::vector<double> beyond = prepared.radii.beyond_smallest();
  registration::RegistrationResult r =
      registration::register_by_faces(*prepared.offset, *prepared.locator, raw, positions, icp, beyond);
  if (!r.converged()) {
    why_not = "did not converge: " + r.stop_reason;
    return std::nullopt;
  }
  if (!r.constraints.complete()) {
    why_not = "fixes " + std::to_string(r.constraints.fixed) + " of the 6 motions only";
    return std::nullopt;
  }
  const registration::Credibility verdict = registration::assess_registration(r, prepared.radii);
  if (!verdict.ok()) {
    why_not = "is not credible either: " + verdict.reason;
    return std::nullopt;
  }
  return r;
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
  std::string tried = std::to_string(starts - 1) + " starts of a coarse alignment (ICP from the model turned " +
                      "about the points' principal axes)";
  if (verdict.ok()) {
    best.notes.push_back("the registration from the given start was not credible (" + first.reason + "); " + tried +
                         " found a credible one");
    return best;
  }
  if (!options.datum_faces.empty()) {
    std::string why_not;
    std::optional<registration::RegistrationResult> by_datums =
        locate_by_datum_features(prepared, raw, best.transform, options, why_not);
    if (by_datums) {
      by_datums->starts = starts;
      by_datums->notes.push_back("the best fit of all the points was not credible (" + verdict.reason + "; " + tried +
                                 " found none credible): the part was located by the " + std::to_string(by_datums->locating_points()) +
                                 " points on its datum features alone, as its drawing does; the other faces' deviations "
                                 "are from there");
      return *std::move(by_datums);
    }
    tried += "; located by its datum features' points alone, " + why_not;
  }
  // Nothing fits better: the figures may be the part's own form error, unless the data hardly touch the model or
  // most of them sit on its wrong side, where no deviation can be trusted.
  if (verdict.status == registration::Credibility::Status::LittleOverlap || verdict.inside_share > kMaxInsideShareKept) {
    throw RegistrationError("the registration is not credible: " + verdict.reason + "; " + tried + " found none better",
                            Hint::InitialTransform);
  }
  const std::string doubtful = "the registration is doubtful: " + verdict.reason + "; " + tried +
                               (moved ? " improved it but found no credible one" : " found none better");
  if (!options.accept_doubtful) {
    throw RegistrationError(doubtful, Hint::InitialTransformOrAcceptDoubtful);
  }
  best.notes.push_back(doubtful + ", and was accepted as asked: these may be the part's own deviations, or a wrong pose");
  return best;
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
// (The first-order estimate and kMaxSkippedShare: registration/sensitivity.hpp.)
void register_without_outliers(const PreparedModel& prepared, std::span<const Point3> raw, const FitResult& fits,
                               const registration::RegistrationOptions& icp, registration::RegistrationResult& r) {
  // A part located by its datum features' points (register_centres) stays located by them: only theirs pull.
  const bool by_features = !r.located_by.empty();
  std::vector<std::size_t> flagged;
  for (const FaceFit& ff : fits.faces) {
    for (std::size_t i = 0; i < ff.trusted.size(); ++i) {
      if (!ff.trusted[i] && (!by_features || r.located_by[ff.members[i]] != 0)) flagged.push_back(ff.members[i]);
    }
  }
  if (flagged.empty() || !registration::leaving_out_moves(*prepared.locator, raw, icp, r, flagged)) return;
  registration::RegistrationOptions again = icp;
  again.initial = r.transform;
  std::vector<Point3> kept;
  std::vector<std::uint8_t> locating;
  if (by_features) {
    locating = r.located_by;
    for (const std::size_t k : flagged) locating[k] = 0;
    again.located_by = locating;
  } else {
    // Not finite: reported by ICP, never used.
    kept.assign(raw.begin(), raw.end());
    for (const std::size_t k : flagged) kept[k] = Point3::Constant(std::numeric_limits<double>::quiet_NaN());
  }
  const std::span<const Point3> registered = by_features ? raw : std::span<const Point3>(kept);
  registration::RegistrationResult second = registration::register_to_offset_model(
      *prepared.offset, *prepared.locator, registered, again, prepared.radii.beyond_smallest());
  if (!second.converged()) return;
  for (std::size_t k = 0; k < registered.size(); ++k) {
    if (!registered[k].allFinite()) second.matches[k] = r.matches[k];
  }
  second.iterations += r.iterations;
  second.searches += r.searches;
  second.coarse_iterations = r.coarse_iterations;
  second.starts = r.starts;
  second.left_out = static_cast<int>(flagged.size());
  second.notes = std::move(r.notes);
  r = std::move(second);
}

// A qualified radius's uncertainty is along the normal, as u is: they add in quadrature.
void add_radius_uncertainty(std::span<const double> radius_u, std::vector<CompensatedPoint>& points) {
  for (std::size_t k = 0; k < radius_u.size() && k < points.size(); ++k) {
    if (points[k].computed()) points[k].uncertainty = std::hypot(points[k].uncertainty, radius_u[k]);
  }
}

// The run with every point's radius known (options.probe_radius / probe_radii), each point's radius uncertainty
// (mm, k = 1; empty: none) joining its u.
CompensationResult compensate_with_radii(const cad::Model& model, std::span<const Point3> raw,
                                         std::optional<std::span<const Vector3>> approach_normals,
                                         const CompensateOptions& options, std::span<const double> radius_u) {
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
    add_radius_uncertainty(radius_u, out.points);
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
       .accept_doubtful = options.accept_doubtful_registration,
       .datum_faces = options.datum_faces});
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
  out.points = compensate_points(prepared, raw, out.registration, fits, &out.warnings);
  add_radius_uncertainty(radius_u, out.points);
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
  outlier_group_warnings(fits, raw, out.points, out.warnings);
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
  folded_offset_warnings(prepared, out.faces, out.warnings);
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

}  // namespace

CompensationResult compensate(const cad::Model& model, std::span<const Point3> raw,
                              std::optional<std::span<const Vector3>> approach_normals,
                              const CompensateOptions& options) {
  // No points: the run's own refusal, before any radius is looked up.
  if (options.qualification == nullptr || raw.empty()) {
    return compensate_with_radii(model, raw, approach_normals, options, {});
  }
  if (approach_normals && approach_normals->size() != raw.size()) {
    throw InputError("the approach normals do not match the points in number");
  }
  CompensateOptions qualified = options;
  qualified.qualification = nullptr;
  const auto radii_for = [&](const std::vector<Vector3>& travel) {
    QualifiedRadii q = qualified_radii(*options.qualification, options.styli, travel, options.probe_radii,
                                       options.probe_radius);
    qualified.probe_radii = q.radius;
    qualified.probe_radius = *std::min_element(q.radius.begin(), q.radius.end());
    return q;
  };
  // The run with the radii for these travel directions, and what the qualification says about them.
  const auto run_qualified = [&](const std::vector<Vector3>& travel) {
    const QualifiedRadii q = radii_for(travel);
    CompensationResult out = compensate_with_radii(model, raw, approach_normals, qualified, q.uncertainty);
    out.styli = q.styli;
    out.warnings.insert(out.warnings.end(), q.warnings.begin(), q.warnings.end());
    return out;
  };
  std::vector<Vector3> travel(raw.size());
  if (approach_normals) {
    for (std::size_t k = 0; k < raw.size(); ++k) travel[k] = -(*approach_normals)[k];
    return run_qualified(travel);
  }
  // Without approach normals the travel is taken against the fitted normal, which needs a run: the first takes each
  // stylus's sphere-fit radius (a travel not known yet), the second the radius against the first's normals.
  (void)radii_for(std::vector<Vector3>(raw.size(), Vector3::Zero()));
  const CompensationResult rough = compensate_with_radii(model, raw, std::nullopt, qualified, {});
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const Vector3& n = rough.points[k].normal;
    travel[k] = rough.points[k].computed() && n.squaredNorm() > 0.5 ? Vector3(-n) : Vector3::Zero();
  }
  return run_qualified(travel);
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
