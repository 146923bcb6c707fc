#include "probecomp/cad/material_side.hpp"

#include <algorithm>
#include <optional>
#include <stdexcept>

#include "probecomp/cad/locator.hpp"
#include "probecomp/geometry/point_set.hpp"
#include "probecomp/geometry/statistics.hpp"

namespace probecomp::cad {

namespace {
// A spread subset of a quarter of the points, at most this many, votes first (see decide_material_side)...
constexpr std::size_t kVoteSubset = 1 << 16;
// ... and decides a face that holds at least this many of its votes, this share of them for one side. A face with
// fewer (a small face, or one no point is nearest to) is decided by all the points, as without the subset.
constexpr int kDecisiveVotes = 1000;
constexpr double kDecisiveShare = 0.9;
}  // namespace

const char* to_string(MaterialSource s) {
  switch (s) {
    case MaterialSource::Solid: return "solid";
    case MaterialSource::ApproachNormals: return "approach-normals";
    case MaterialSource::Data: return "data";
    case MaterialSource::NoPoints: return "no-points";
    case MaterialSource::File: return "file";
  }
  return "?";
}

namespace {

// `given`: a locator of `model`, or null to make one when there is something to decide.
std::vector<MaterialSide> decide(Model& model, const ModelLocator* given, std::span<const Point3> raw_centres,
                                 std::optional<std::span<const Vector3>> approach_normals,
                                 const geometry::RigidTransform& initial) {
  std::vector<MaterialSide> sides(model.faces.size());
  for (std::size_t f = 0; f < model.faces.size(); ++f) {
    sides[f].outward = model.faces[f].outward;
    if (model.faces[f].material_known) sides[f].source = MaterialSource::Solid;
  }
  const bool any_unknown = std::any_of(model.faces.begin(), model.faces.end(), [](const Face& f) { return !f.material_known; });
  if (!any_unknown || raw_centres.empty()) return sides;

  const geometry::RigidTransform to_cad = initial.inverse();
  std::optional<ModelLocator> own;
  if (given == nullptr) own.emplace(model);
  const ModelLocator& locator = given != nullptr ? *given : *own;
  // Votes relative to the file's orientation (ModelPoint normals and distances use the current `outward`), of the
  // points at `indices` (all when empty).
  std::vector<int> plus, minus;
  std::vector<std::vector<double>> distances;
  auto vote = [&](const std::vector<std::size_t>& indices) {
    const std::size_t n = indices.empty() ? raw_centres.size() : indices.size();
    auto at = [&](std::size_t i) { return indices.empty() ? i : indices[i]; };
    std::vector<Point3> x(n);
    for (std::size_t i = 0; i < n; ++i) x[i] = to_cad * raw_centres[at(i)];
    const std::vector<ModelPoint> feet = locator.closest_points(x);
    plus.assign(model.faces.size(), 0);
    minus.assign(model.faces.size(), 0);
    distances.assign(model.faces.size(), {});
    for (std::size_t i = 0; i < n; ++i) {
      const ModelPoint& m = feet[i];
      if (!m.ok() || m.on_trim_edge) continue;
      const std::size_t f = static_cast<std::size_t>(m.face);
      if (model.faces[f].material_known) continue;
      double v = 0.0;
      if (approach_normals) {
        v = m.normal.dot(to_cad.linear() * (*approach_normals)[at(i)]);
      } else {
        v = m.distance;
        distances[f].push_back(m.distance);
      }
      if (v > 0.0) ++plus[f];
      if (v < 0.0) ++minus[f];
    }
  };
  // Many points: a spread subset votes first, a closest-point search for each of its points instead of a million.
  // It decides when every undecided face holds enough of its votes and a clear majority; else all points vote.
  // (From 4 000 points, where the subset can hold a decisive count: 10 000 points, 2 500 searches instead of 10 000.)
  bool decided = false;
  const std::size_t subset = std::min(kVoteSubset, raw_centres.size() / 4);
  if (subset >= static_cast<std::size_t>(kDecisiveVotes)) {
    vote(geometry::spread_subset_indices(raw_centres, subset));
    decided = true;
    for (std::size_t f = 0; f < model.faces.size(); ++f) {
      if (model.faces[f].material_known) continue;
      const int votes = plus[f] + minus[f];
      if (votes < kDecisiveVotes || std::max(plus[f], minus[f]) < kDecisiveShare * votes) decided = false;
    }
  }
  if (!decided) vote({});
  for (std::size_t f = 0; f < model.faces.size(); ++f) {
    Face& face = model.faces[f];
    if (face.material_known) continue;
    MaterialSide& s = sides[f];
    s.points = plus[f] + minus[f];
    if (s.points == 0) continue;
    s.source = approach_normals ? MaterialSource::ApproachNormals : MaterialSource::Data;
    // The probe side is where most approach normals point, or where most centres lie.
    const int flip = minus[f] > plus[f] ? -1 : 1;
    face.outward *= flip;
    s.outward = face.outward;
    s.agreeing = std::max(plus[f], minus[f]);
    if (!distances[f].empty()) {
      std::vector<double>& d = distances[f];
      s.median_distance = flip * geometry::upper_median_in_place(d);
    }
  }
  return sides;
}

}  // namespace

std::vector<MaterialSide> decide_material_side(Model& model, std::span<const Point3> raw_centres,
                                               std::optional<std::span<const Vector3>> approach_normals,
                                               const geometry::RigidTransform& initial) {
  return decide(model, nullptr, raw_centres, approach_normals, initial);
}

std::vector<MaterialSide> decide_material_side(Model& model, const ModelLocator& locator,
                                               std::span<const Point3> raw_centres,
                                               std::optional<std::span<const Vector3>> approach_normals,
                                               const geometry::RigidTransform& initial) {
  if (&locator.model() != &model) throw std::invalid_argument("decide_material_side: the locator is of another model");
  return decide(model, &locator, raw_centres, approach_normals, initial);
}

}  // namespace probecomp::cad
