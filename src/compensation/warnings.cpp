#include "warnings.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <numbers>
#include <string_view>

#include "probecomp/cad/offset_model.hpp"
#include "probecomp/geometry/point_tree.hpp"

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

namespace {

// Outliers are side by side when one is among another's this many nearest centres (a grid's ring of eight).
constexpr int kGroupNeighbours = 8;
// Groups this large are told. Random gross errors make small ones by chance: 1 % of the paper's 120 × 60 grid moved
// made a group of three in 16 of 24 runs (Pipeline.GrossOutliersAtLowAndHighNoise), none of five; a crease the fit
// does not follow leaves groups of 7 to 98 (ShapeSuite.OutliersSideBySideAreToldAsPossiblyShape).
constexpr std::size_t kMinGroup = 5;

std::size_t root(std::vector<std::size_t>& parent, std::size_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

void outlier_group_warnings(const FitResult& fits, std::span<const Point3> raw, std::span<const CompensatedPoint> points,
                            std::vector<std::string>& warnings) {
  for (const FaceFit& ff : fits.faces) {
    std::vector<std::size_t> outliers;  // positions among the face's members
    for (std::size_t i = 0; i < ff.members.size(); ++i) {
      if (points[ff.members[i]].status == PointStatus::Outlier) outliers.push_back(i);
    }
    if (outliers.size() < kMinGroup || ff.members.size() <= static_cast<std::size_t>(kGroupNeighbours)) continue;
    std::vector<Point3> centres(ff.members.size());
    for (std::size_t i = 0; i < ff.members.size(); ++i) centres[i] = raw[ff.members[i]];
    const geometry::OwnedPointTree tree(std::move(centres));
    std::vector<std::size_t> outlier_at(ff.members.size(), SIZE_MAX);  // member position → index in outliers
    for (std::size_t o = 0; o < outliers.size(); ++o) outlier_at[outliers[o]] = o;
    std::vector<std::size_t> parent(outliers.size());
    std::iota(parent.begin(), parent.end(), std::size_t{0});
    constexpr int kQueried = kGroupNeighbours + 1;  // the point itself is found first
    for (std::size_t o = 0; o < outliers.size(); ++o) {
      std::uint32_t found[kQueried];
      double squared[kQueried];  // nanoflann's L2 adaptor: squared distances (unused)
      const std::size_t n = tree.tree.knnSearch(tree.cloud.points[outliers[o]].data(), kQueried, found, squared);
      for (std::size_t j = 0; j < n; ++j) {
        const std::size_t other = outlier_at[found[j]];
        if (other == SIZE_MAX || other == o) continue;
        parent[root(parent, o)] = root(parent, other);
      }
    }
    std::vector<std::size_t> size(outliers.size(), 0);
    for (std::size_t o = 0; o < outliers.size(); ++o) ++size[root(parent, o)];
    std::size_t grouped = 0, groups = 0, largest = 0;
    for (std::size_t o = 0; o < outliers.size(); ++o) {
      if (size[o] < kMinGroup) continue;
      grouped += size[o];
      ++groups;
      if (size[o] > size[largest] || size[largest] < kMinGroup) largest = o;
    }
    if (groups == 0) continue;
    // The largest group's centre and extent (the largest distance of its centres from their mean).
    Point3 mean = Point3::Zero();
    std::vector<Point3> members;
    for (std::size_t o = 0; o < outliers.size(); ++o) {
      if (root(parent, o) != largest) continue;
      members.push_back(tree.cloud.points[outliers[o]]);
      mean += members.back();
    }
    mean /= static_cast<double>(members.size());
    double reach = 0.0;
    for (const Point3& c : members) reach = std::max(reach, (c - mean).norm());
    warnings.push_back("face " + std::to_string(ff.report.face) + ": " + std::to_string(grouped) + " of its " +
                       std::to_string(outliers.size()) + " outliers lie side by side, in " + std::to_string(groups) +
                       (groups == 1 ? " group" : " groups") + " of " + std::to_string(kMinGroup) +
                       " or more (the largest, " + std::to_string(members.size()) + " centres within " + mm(reach) +
                       " mm of (" + mm(mean.x()) + ", " + mm(mean.y()) + ", " + mm(mean.z()) +
                       ")); gross errors seldom do: where the part has a crease or a feature narrower than the "
                       "points' spacing the fit may not follow it, and those readings may be right. Look at the part "
                       "there before discarding them (their u holds their residual)");
  }
}

}  // namespace probecomp::compensation::detail
