// second_contacts and fit_faces: each face's points, and its centre surface fitted through them.

#include "probecomp/compensation/pipeline.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "probecomp/compensation/normal_support.hpp"
#include "probecomp/compensation/outliers.hpp"
#include "probecomp/fitting/held_out.hpp"
#include "probecomp/fitting/noise_estimate.hpp"
#include "probecomp/geometry/neighbours.hpp"
#include "probecomp/geometry/parallel.hpp"
#include "probecomp/geometry/statistics.hpp"
#include "probecomp/geometry/stopwatch.hpp"
#include "probecomp/nurbs/degree_elevation.hpp"

#include "contact_points.hpp"
#include "element_faces.hpp"
#include "input_checks.hpp"
#include "scan_lines.hpp"
#include "warnings.hpp"

namespace probecomp::compensation {

namespace {

using detail::as_smallest_tip;
using detail::kNotFitted;
using detail::kOffsetAlongNominal;
using detail::kSamePosition;
using detail::mm;

// The fit starts from the registered offset face. A degree-1 direction (a plane, a cylinder's rulings) could
// follow a deformation only by creases at the knots refinement inserts, so it is raised to degree 3 first
// (same shape and parameters, so the registration's (u, v) still hold).
nurbs::Surface fit_start(const nurbs::Surface& offset_face, const geometry::RigidTransform& T) {
  nurbs::Surface s = nurbs::transformed(offset_face, T);
  if (s.p() < 2) s = nurbs::elevate_degree_u(s, 3 - s.p());
  if (s.q() < 2) s = nurbs::elevate_degree_v(s, 3 - s.q());
  return s;
}

// On a scanning probe's lines without noise, the floor of a knot span's penalty weight (fitting::AdaptiveFitOptions::
// min_span_weight_noise_free). Exact data leave every span the fit misses by a tenth of a micrometre unexplained, and
// its weight went down to 1e-6: between the lines, where no point is, nothing then held the control points, and the
// fit rang there (the contacts' normals come from across the lines). Shape suite, lines 4 mm apart without noise:
// S13 std 4.65 µm (largest 142 µm) at 1e-6, 0.28 (6.2) at 1e-3, 0.33 (9.2) at 1e-2, 0.30 (7.8) with no lowering;
// S29 49.4 (550), 6.6 (113), 2.35 (46), 2.45 (50). With noise it stays 1e-6: at 1e-3 S25 (σ = 3 µm) went
// 0.76 -> 0.93 µm.
constexpr double kNoiseFreeLinesMinSpanWeight = 1e-2;

// Scan lines left out to check an anisotropic energy (fit_faces): every kLineGroups-th interior line in turn, so
// that each line left out still has kept lines on either side.
constexpr int kLineGroups = 4;
// The anisotropic fit is refused where it predicts the lines left out worse than the isotropic fit by more than
// this many standard errors of the mean difference over the lines (about one chance in forty that noise alone did
// it, the lines taken as independent). Refused, not required to win: where the lines are too far apart for either
// fit to predict one from its neighbours, the comparison tells nothing (D409, a wave 13 mm long across lines 4 mm
// apart: both fits miss the lines left out by 58 µm rms), and the anisotropy still follows the wave on the lines.
constexpr double kLinesHeldOutSignificance = 2.0;

// Two fits' held-out errors (fitting::held_out_errors, per point) compared line by line: each line's mean squared
// error under either fit, and the mean and standard error over the lines of the first's less the second's.
struct LinesHeldOut {
  double first = 0.0, second = 0.0;  // mean over the lines, mm²
  double better_by = 0.0;            // first − second: how much better the second predicts, mm²
  double standard_error = std::numeric_limits<double>::infinity();
};
LinesHeldOut lines_held_out(const std::vector<double>& first, const std::vector<double>& second,
                            const std::vector<int>& line) {
  LinesHeldOut out;
  if (first.size() != line.size() || second.size() != line.size() || line.empty()) return out;
  const std::size_t lines = static_cast<std::size_t>(*std::max_element(line.begin(), line.end())) + 1;
  std::vector<double> a(lines, 0.0), b(lines, 0.0);
  std::vector<int> n(lines, 0);
  for (std::size_t k = 0; k < line.size(); ++k) {
    if (!std::isfinite(first[k]) || !std::isfinite(second[k])) continue;
    const auto j = static_cast<std::size_t>(line[k]);
    a[j] += first[k];
    b[j] += second[k];
    ++n[j];
  }
  std::vector<double> d;
  for (std::size_t j = 0; j < lines; ++j) {
    if (n[j] == 0) continue;
    out.first += a[j] / n[j];
    out.second += b[j] / n[j];
    d.push_back((a[j] - b[j]) / n[j]);
  }
  if (d.size() < 2) return out;
  const double m = static_cast<double>(d.size());
  out.first /= m;
  out.second /= m;
  out.better_by = out.first - out.second;
  double ss = 0.0;
  for (const double x : d) ss += (x - out.better_by) * (x - out.better_by);
  out.standard_error = std::sqrt(ss / (m - 1.0) / m);
  return out;
}

// A point whose distance from the registered offset face stands out alone from what its neighbours predict by more
// than this (mm), and by the outlier test's bound, is left out of the face's first fit
// (fitting::screen_for_gross_errors): a gross error in a fit bends it, and the first fit's refinement followed the
// bend round after round (the paper's 120 × 60 grid with 1 % of the points moved 0.1–5 mm: 8 rounds to 3 600
// control points, 7–10 s, against 2 rounds and 0.2 s without them). Feature points the local quadratic cannot
// follow stand out too, and a fit without a feature's peak does not follow it (leaving them out with the outlier
// bound alone flagged good points on S17, S18, S22 and S29 of the shape suite and S22's std went 0.74 -> 0.96 µm):
// their prediction errors there are 4–41 µm, and what a chip or a stuck probe leaves is 0.1 mm and more (read as
// 0.08 mm or more: a prediction error is scaled by 1/√(1 + Σa²), LocalPredictionNoise). Gross errors below it are
// found by the first fit's verdict as before, at the cost of the rounds it spends on them.
constexpr double kPeelFloor = 0.05;
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

// Why a face's fit stopped.
std::string fit_stop_cause(const fitting::AdaptiveFitResult& fit, const fitting::AdaptiveFitOptions& options) {
  using S = fitting::AdaptiveFitResult::Status;
  switch (fit.status) {
    case S::OK: return "every span's residuals are consistent with the noise estimate";
    case S::NoiseNotReached:
      return std::to_string(fit.spans_above_noise) + " span(s) still above the noise: " +
             (fit.refinement_rejected         ? "more control points did not predict left-out points better"
              : fit.rounds >= options.max_rounds ? "the refinement rounds ran out"
                                                 : "the points support no more control points");
    case S::NotDone: return "the fit could not be set up (too few usable points for its control points)";
    case S::NumericalError: return "the fit's normal equations could not be solved";
  }
  return "?";
}

// Why a face's fit stopped, in one line, and where it began.
std::string fit_stop_reason(const fitting::AdaptiveFitResult& fit, const fitting::AdaptiveFitOptions& options) {
  // (AdaptiveFitOptions::dense_start_points_per_control_point)
  const std::string start = fit.dense_start ? " (begun from the nominal's knot spans halved, which predicted "
                                              "left-out points better)"
                                            : "";
  return fit_stop_cause(fit, options) + start;
}

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
    // (each residual against its neighbours') would read low, the cross-validation would take the copies as
    // confirming each other, and the fit would chase the noise (10 % repeated on the free-form case: 1 927
    // control points instead of 783).
    const std::vector<std::uint32_t> first = geometry::first_at_same_position(member_points, kSamePosition);
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
    std::vector<char> in_fit;  // per fitted point: 1 where the last fit used it
    // Points along a scanning probe's lines are predicted from their own line's neighbours whatever the fit does
    // between the lines: their smoothing is chosen by leaving a knot span's points out at once (penalized.hpp).
    // Elsewhere a point alone: a narrow, steep feature on a grid wants the fit that leave-one-out chooses (a dent of
    // 19° flanks without noise: largest error 0.5 µm, against 4.5 µm left out by spans).
    fitting::AdaptiveFitOptions surface = options.surface;
    NormalCheck normal_check;
    normal_check.along_lines = sampled_along_lines(pts);
    // Nor is the energy made anisotropic there at first: a penalty that lets the fit bend freely across the lines
    // lets it ring between them (shape suite, S13 without noise: std 4.6 -> 31 um with it; on noisy lines an
    // anisotropic fit is tried too, and checked by lines left out: see refit below). For the same reason, on exact
    // data a span's penalty is not lowered below kNoiseFreeLinesMinSpanWeight; nor, with noise, is a span split
    // between two lines.
    if (*normal_check.along_lines) {
      surface.fit.cross_validation = fitting::CrossValidation::LeaveSpanOut;
      surface.fit.anisotropic = false;
      surface.min_span_weight_noise_free = std::max(surface.min_span_weight_noise_free, kNoiseFreeLinesMinSpanWeight);
      surface.split_only_where_points_either_side = true;
    }
    // With the balance of data and penalty (AdaptiveFitOptions::SpatialPenalty::Balance), a face that may hold gross
    // errors is first fitted with the roughness rule: the balance lowers the penalty where the fitted shape holds
    // energy, and a gross error's bend is such energy, so the fit followed the errors until the verdict no longer saw
    // them all (the paper's 120 × 60 grid, 1 % of the points moved 0.1–5 mm, σ = 0.5 µm: contacts 9.0 and 84.7 µm
    // off and three good points flagged, against 1.4 and 1.2 µm with this first fit; keeping the roughness rule only
    // around points that stand out from the spread around them: 922 µm at 145 u at σ = 1.5 µm, a moved point
    // trusted). The refits, made without the points that verdict left out, use the balance; such a face whose first
    // fit leaves nothing out is refitted once with it.
    const bool balance = surface.spatial_penalty == fitting::AdaptiveFitOptions::SpatialPenalty::Balance &&
                         surface.fit.cross_validation == fitting::CrossValidation::LeaveOneOut;
    fitting::AdaptiveFitOptions first_fit = surface;
    first_fit.spatial_penalty = fitting::AdaptiveFitOptions::SpatialPenalty::Roughness;
    // Its u is never used when a balanced refit follows (on noisy data off scan lines): no representation check.
    if (balance) first_fit.representation_bias = false;
    // Where no centre stands out from what its neighbours predict for its distance from the registered offset face
    // (fitting::GrossErrorScreen::may_hold, with the outlier test's bound), there is no gross error for the balance to
    // follow, and the first fit is the balanced one: one fit of the face, not two (BM_Compensate10k, whose face is
    // such: 1.7 times the roughness rule's time with two fits, 1.0 with one). Its verdict is made as any first fit's,
    // and the refits without what it leaves out are balanced as above: no point stood out by the test's 5 σ before
    // the fit, so what it leaves out lies at that edge (the noise's tail: a million points hold about one, which
    // restarting with the roughness rule would have cost a million-point face a third fit: BM_Compensate1M20x20
    // 161 s against 70 s).
    // The gate's LocalPredictionNoise is the one the first fit builds over the same points (every weight 1, and
    // every point below its kMaxPoints): built once for both, unless the screen leaves points out of that fit.
    // (Without the balance only the screen's peel uses it: a sample of a large face, as the fits' own.)
    const fitting::LocalPredictionNoise gate(pts, std::span<const double>{},
                                             balance ? pts.size() : fitting::LocalPredictionNoise::kMaxPoints);
    const fitting::GrossErrorScreen screen = fitting::screen_for_gross_errors(
        gate, start, pts, params, options.outliers.sigmas, options.outliers.min_residual, kPeelFloor);
    const bool balanced_first = balance && !screen.may_hold;
    // Across lines millimetres apart an anisotropic energy may let the fit bend where no data are (S16 of the shape
    // suite: std 0.772 -> 3.024 µm with θ chosen by leave-span-out, whose left-out pieces of a line are predicted by
    // the rest of the same line), yet it follows a feature crossing the lines (D409: 1.234 -> 0.782 µm). What it
    // does between the lines shows when whole lines are left out (kLineGroups, kLinesHeldOutSignificance), each fit
    // refitted without them at its own λ, θ and net (fitting/held_out.hpp).
    const std::vector<int> line_numbers =
        *normal_check.along_lines ? detail::scan_line_numbers(pts, 2 * kLineGroups) : std::vector<int>{};
    // (The first and last lines are in every refit: left out, they would be extrapolated, not predicted between
    // lines, and their errors would swamp the comparison.)
    std::vector<int> line_groups = line_numbers;
    if (!line_numbers.empty()) {
      const int last = *std::max_element(line_numbers.begin(), line_numbers.end());
      for (int& g : line_groups) g = g == 0 || g == last ? -1 : (g - 1) % kLineGroups;
    }
    std::string anisotropy_note;
    const bool gate_serves_first_fit = screen.isolated.empty() && pts.size() <= fitting::LocalPredictionNoise::kMaxPoints;
    auto refit = [&](const nurbs::Surface& from, std::span<const fitting::SurfaceParameter> at, bool is_first = false) {
      in_fit.resize(pts.size());
      for (std::size_t j = 0; j < pts.size(); ++j) in_fit[j] = weights[j] > 0.0;
      // (The first fit's weights are all 1 and its points not yet moved: the gate's structure is its.)
      fit = fitting::fit_surface(from, pts, at, weights, is_first && !balanced_first ? first_fit : surface,
                                 is_first && gate_serves_first_fit ? &gate : nullptr);
      ++rep.fits;
      rep.rounds += fit->rounds;
      anisotropy_note.clear();
      // On noisy scan lines the energy's anisotropy is chosen too, and refused where it predicts lines it did not
      // see worse than the isotropic fit (kLinesHeldOutSignificance). Not on exact data: there the anisotropic fit
      // rang between lines where the isotropic one held (S13 without noise: std 0.33 -> 1.04 µm).
      if (!options.anisotropy_on_scan_lines || line_groups.empty() || !fit->fitted() ||
          !(fit->noise_sigma > surface.noise_floor)) {
        return;
      }
      fitting::AdaptiveFitOptions free = is_first && !balanced_first ? first_fit : surface;
      free.fit.anisotropic = true;
      fitting::AdaptiveFitResult other = fitting::fit_surface(from, pts, at, weights, free, nullptr);
      ++rep.fits;
      rep.rounds += other.rounds;
      if (!other.fitted() || other.log10_anisotropy == 0.0) return;
      std::vector<double> other_errors =
          fitting::held_out_errors(other, from, pts, weights, line_groups, kLineGroups, free.fit);
      // θ is chosen afresh on each of the fit's nets (fitting/adaptive.cpp), and the coarse first nets', which
      // cannot show the direction, steer where the later ones refine and what smoothing they search: the θ of its
      // last net, held from the first, may predict the lines left out better (shape suite S16, a twist and a 25 mm
      // wave on a cylinder: 4.51 µm rms against 5.71, std 0.772 -> 0.638 µm against the reference's 0.615). The
      // better of the two predicting lines left out is the one weighed against the isotropic fit.
      fitting::AdaptiveFitOptions held_theta = free;
      held_theta.fit.log10_anisotropy = other.log10_anisotropy;
      fitting::AdaptiveFitResult steady = fitting::fit_surface(from, pts, at, weights, held_theta, nullptr);
      ++rep.fits;
      rep.rounds += steady.rounds;
      bool theta_held = false;
      if (steady.fitted()) {
        std::vector<double> steady_errors =
            fitting::held_out_errors(steady, from, pts, weights, line_groups, kLineGroups, held_theta.fit);
        if (lines_held_out(other_errors, steady_errors, line_numbers).better_by > 0.0) {
          other = std::move(steady);
          other_errors = std::move(steady_errors);
          theta_held = true;
        }
      }
      const LinesHeldOut held = lines_held_out(
          fitting::held_out_errors(*fit, from, pts, weights, line_groups, kLineGroups, surface.fit), other_errors,
          line_numbers);
      // (Not told, as where a refit failed: the isotropic fit stays.)
      if (!std::isfinite(held.standard_error)) return;
      const bool refused = held.better_by < -kLinesHeldOutSignificance * held.standard_error;
      char theta[16];
      std::snprintf(theta, sizeof theta, "%+.2f", other.log10_anisotropy);
      anisotropy_note = std::string(refused ? "; an anisotropic energy (log10 theta " : "; anisotropic (log10 theta ") +
                        theta + (theta_held ? ", held from the first net" : "") + (refused ? ") refused" : ")") +
                        ": interior lines left out, every fourth in turn, predicted within " +
                        um(std::sqrt(held.second)) + " rms by it, " + um(std::sqrt(held.first)) + " isotropic";
      if (!refused) fit = std::move(other);
    };
    std::vector<char> outlier(pts.size(), 0);
    if (static_cast<double>(pts.size()) >= needed) {
      // Outliers are decided against the fit itself (compensation/outliers.hpp), left out, and the face refitted,
      // until the set left out no longer changes: a point left out is taken back when the fit made without it
      // predicts it within its bound (a point a fit bent by a gross error had pushed out), so that the set left
      // out is the one the final fit agrees with.
      bool moved_along_fit = false;
      // The first fit without the points that stand out alone by more than kPeelFloor; its verdict, as for any
      // point left out, takes back those it predicts within their bound.
      for (std::size_t k = 0; k < screen.isolated.size(); ++k) {
        if (screen.isolated[k]) weights[k] = 0.0;
      }
      for (int attempt = 0; attempt < kMaxOutlierFits + (balance ? 1 : 0); ++attempt) {
        // A refit starts over from the registered offset face: the first fit's refinement and adaptive penalty
        // may have followed the gross errors it then found, and would keep their marks.
        refit(start, params, attempt == 0);
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
        // (The balance is not used on exact data nor along scan lines: fitting/adaptive.cpp.)
        const bool balance_next = attempt == 0 && balance && !balanced_first && fit->noise_sigma > surface.noise_floor;
        if (!move_again && !balance_next && (changed == 0 || !moves_fit(largest, pts.size(), *fit))) break;
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
      if (check.along_lines) {
        const detail::ScanLineDoubts doubts = detail::scan_line_doubts(
            fit->surface, start, pts, fit->params, fit->residuals, last_weights, fit->noise_sigma,
            normal_check.line_variance_ratio, !(fit->noise_sigma > surface.noise_floor));
        ff.line_bias.resize(members.size());
        ff.normal_unseen_angle.resize(members.size());
        ff.line_spacing = doubts.line_spacing;
        for (std::size_t i = 0; i < members.size(); ++i) {
          ff.line_bias[i] = doubts.bias[position[i]];
          ff.normal_unseen_angle[i] = doubts.normal_angle[position[i]];
        }
      }
      if (!check.angle.empty()) {
        ff.normal_angle.resize(members.size());
        for (std::size_t i = 0; i < members.size(); ++i) ff.normal_angle[i] = check.angle[position[i]];
      }
      per_member(*fit, position);
      rep.fit_status = fit->status;
      rep.stop_reason = fit_stop_reason(*fit, options.surface) + anisotropy_note;
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
        const std::string too_few = std::to_string(pts.size()) + " points off the edges for " +
                                    std::to_string(start.num_u() * start.num_v()) + " control points (" + mm(needed) +
                                    " needed)";
        // Too few for the NURBS, but an elementary surface is fixed by a handful: fitted as that, its points
        // offset along its normal (contact_points.cpp), not the nominal's.
        std::vector<char> left_out;
        // The registration's residual scale stands for the centres' noise: the element's own residuals would judge
        // the fit by itself.
        ff.element = detail::fit_element_face(face, pts, registration.transform, prepared.radii.smallest(),
                                              registration.scale, left_out);
        if (ff.element) {
          rep.fitted_as = ff.element->kind;
          for (std::size_t i = 0; i < members.size(); ++i) ff.trusted[i] = !left_out[position[i]];
          rep.rms = ff.element->rms;
          rep.stop_reason = std::string("fitted as a ") + cad::to_string(ff.element->kind) + ": " + too_few +
                            "; " + std::to_string(ff.element->used) + " points used, rms " + mm(ff.element->rms) +
                            (ff.element->held > 0 ? ", " + std::to_string(ff.element->held) +
                                                        " of its parameters' combinations held at the nominal's"
                                                  : "");
        } else {
          rep.stop_reason = kNotFitted + too_few + kOffsetAlongNominal;
        }
      }
    }
    done += members.size();
    if (progress) progress(static_cast<double>(done) / static_cast<double>(std::max<std::size_t>(raw.size(), 1)));
  }
  // The noise of the rows on element faces, from all of them at once (element_faces.hpp).
  {
    std::vector<ElementFaceFit*> elements;
    std::vector<FaceReport*> reports;
    std::vector<double> fitted;
    for (auto& [f, ff] : by_face) {
      if (ff.element) {
        elements.push_back(&*ff.element);
        reports.push_back(&ff.report);
      }
      if (ff.report.fitted) fitted.push_back(ff.fit->noise_sigma);
    }
    std::optional<double> fitted_noise;
    if (!fitted.empty()) fitted_noise = geometry::median_in_place(fitted);
    const detail::ElementNoise noise = detail::element_face_noise(elements, fitted_noise);
    for (std::size_t i = 0; i < elements.size(); ++i) {
      elements[i]->noise = noise.face[i];
      if (std::isfinite(noise.face[i])) reports[i]->noise_sigma = noise.face[i];
    }
    out.noise_sigma = noise.shared;
  }
  out.faces.reserve(by_face.size());
  for (auto& [f, ff] : by_face) out.faces.push_back(std::move(ff));
  out.seconds = clock.seconds();
  return out;
}

}  // namespace probecomp::compensation
