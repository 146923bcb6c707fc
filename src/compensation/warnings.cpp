#include "warnings.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <string_view>

#include "probecomp/cad/offset_model.hpp"

#include "contact_points.hpp"

namespace probecomp::compensation::detail {

std::string mm(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

std::string um(double v_mm) { return mm(1e3 * v_mm) + " um"; }

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

void unfitted_face_warnings(const std::vector<FaceReport>& faces, std::vector<std::string>& warnings) {
  constexpr std::size_t kListedFaces = 5;
  std::vector<const FaceReport*> unfitted;
  int points = 0;
  for (const FaceReport& f : faces) {
    if (f.fitted || f.fitted_as || f.points == 0) continue;
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
  if (unfitted.size() > kListedFaces) w += "; ... (every face in the JSON statistics)";
  warnings.push_back(w);
}

void folded_offset_warnings(const PreparedModel& prepared, const std::vector<FaceReport>& faces,
                            std::vector<std::string>& warnings) {
  std::map<int, std::size_t> position;  // cad::Face::index → position in the model
  for (std::size_t f = 0; f < prepared.nominal->faces.size(); ++f) position[prepared.nominal->faces[f].index] = f;
  for (const FaceReport& rep : faces) {
    if (!rep.fitted) continue;
    const auto at = position.find(rep.face);
    if (at == position.end()) continue;
    const fitting::OffsetResult& o = prepared.offset->faces[at->second];
    if (o.status != fitting::OffsetResult::Status::FoldsOver) continue;
    char where[64];
    std::snprintf(where, sizeof where, "u %.4g, v %.4g", o.at_u, o.at_v);
    warnings.push_back("face " + std::to_string(rep.face) + " bends tighter than the tip (a radius of " +
                       mm(o.min_radius_towards_offset) + " mm at " + where +
                       "): its radius offset folds over there and is up to " + mm(o.deviation) +
                       " mm off, and the registration and the fit start from it; rows whose fitted normal it turned "
                       "say so");
  }
}

void normal_warnings(const FitResult& fits, const geometry::TipRadii& radii, std::span<const CompensatedPoint> points,
                     std::vector<std::string>& warnings) {
  // Per angle of a face's rows: those that could not be told, and those whose r(1 − cos θ) is most of their u
  // (their count, largest angle and largest doubt).
  struct Tally {
    int doubtful = 0, unknown = 0;
    double angle = 0.0, doubt = 0.0;
  };
  auto tally = [&](const FaceFit& ff, const std::vector<double>& angle) {
    Tally t;
    for (std::size_t i = 0; i < ff.members.size(); ++i) {
      const std::size_t k = ff.members[i];
      if (!points[k].computed()) continue;
      const double theta = angle[i], doubt = normal_doubt(radii[k], theta);
      if (std::isnan(theta)) {
        ++t.unknown;
      } else if (doubt > 0.5 * points[k].uncertainty && doubt > kNormalDoubtReported) {
        ++t.doubtful;
        t.angle = std::max(t.angle, theta);
        t.doubt = std::max(t.doubt, doubt);
      }
    }
    return t;
  };
  // "… 5.2°…", and "N rows' u hold the r(1 - cos θ) that makes, up to D mm; ".
  auto degrees = [](double radians) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f", radians * 180.0 / std::numbers::pi);
    return std::string(text);
  };
  auto rows_holding = [](const Tally& t) {
    return std::to_string(t.doubtful) + " row" + (t.doubtful == 1 ? "'s u holds" : "s' u hold") +
           " the r(1 - cos θ) that makes, up to " + mm(t.doubt) + " mm; ";
  };
  for (const FaceFit& ff : fits.faces) {
    if (!ff.report.fitted || ff.normal_angle.empty()) continue;
    const Tally checked = tally(ff, ff.normal_angle);
    const int unknown = checked.unknown;
    const std::string face = "face " + std::to_string(ff.report.face) + ": ";
    const bool lines = ff.normal_checked_along_lines;
    if (checked.doubtful > 0) {
      const std::string angle = degrees(checked.angle), rows = rows_holding(checked);
      warnings.push_back(
          lines ? face + "its points lie along lines, and between them the fitted normal is up to " + angle +
                      "° from what the neighbouring lines show (only the smoothing holds the fit across them): " + rows +
                      "measure lines closer together, or across these, to settle it"
                : face + "next to the points left out of its fit, the fitted normal is up to " + angle +
                      "° from what the centres around them show (the fit swings across the gap they leave): " + rows +
                      "measure more points there (with the outliers' cause removed) to settle it");
    }
    if (!ff.normal_unseen_angle.empty()) {
      const Tally unseen = tally(ff, ff.normal_unseen_angle);
      if (unseen.doubtful > 0) {
        warnings.push_back(face + "its points lie along lines " + mm(ff.line_spacing) +
                           " mm apart, and along them the shape turns by up to " + degrees(unseen.angle) +
                           "° within half that: across the lines, where nothing was measured, the normal may be as "
                           "far off; " + rows_holding(unseen) + "measure lines closer together there to settle it");
      }
    }
    if (unknown > 0) {
      warnings.push_back(face + std::to_string(unknown) + " row" + (unknown == 1 ? "" : "s") +
                         (lines ? " along its scan lines" : " next to the points left out of its fit") +
                         " could not be checked against the centres around them (too few, or along one line): their "
                         "u holds the whole tip radius");
    }
  }
}

}  // namespace probecomp::compensation::detail
