#include "probecomp/compensation/normal_support.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>

#include "probecomp/geometry/point_tree.hpp"
#include "probecomp/geometry/statistics.hpp"

namespace probecomp::compensation {

namespace {

// Points sampled for the spacing's median: plenty for a median, and a fixed cost on a million points.
constexpr std::size_t kSpacingSamples = 2000;
// The smallest pivot of the local models' normal equations (pivoted LDLᵀ, coordinates scaled to the
// neighbourhood's size) must be above this fraction of the largest: below it the neighbours lie along one line (or
// one conic) and do not fix the slope across it. Measured: 1e-4 and up for neighbourhoods on a grid, 0 along a
// line.
constexpr double kMinPivotRatio = 1e-6;
// Neighbours of a point on a scan line are grouped into lines by their coordinate across it: a gap over this many
// point spacings (the median nearest distance: along the lines, on lines) starts another line. The cubic needs four
// lines and the quadric three: through three lines a cubic's t³ is fixed only by the lines' waviness (it passes the
// pivot test above: 1e-6 to 3e-4 measured), and its normal was then 10–66° off where the quadric's was within 2°
// (shape suite D500: 4 735 checks beyond 3°, u 4–10 times the error on 29 scan faces). No pivot threshold tells
// three lines from four: on four to seven lines the ratio is 1.5e-4 to 2e-3.
constexpr double kLineGapSpacings = 3.0;
// Or of more than this share of the neighbours' range across: where the points are sparse (touch points 25–56 mm
// apart round the rim of a plane face, NIST STC-08), three spacings would merge points that differ across by
// tens of millimetres, and fix the models well, into one line.
constexpr double kLineGapShare = 0.05;

// The normals (either sign) of the least-squares quadric and cubic height functions through `near`, over the plane
// of their principal directions, where x projects on that plane (x is among them, or a point left out near them);
// zero where they do not span a surface (the cubic needs ten points spread over it). By the normal equations, in
// coordinates scaled to the neighbourhood's size (the quadric's are the cubic's leading 6 × 6 block): a few
// microseconds a point, where a factorisation of the design matrix took four times as long. Third, the normal of
// that plane itself (the least-squares plane: two lines fix it), zero where the points lie along one line.
std::array<Vector3, 3> local_normals(const Point3& x, std::span<const Point3> near) {
  std::array<Vector3, 3> out{Vector3::Zero(), Vector3::Zero(), Vector3::Zero()};
  Point3 mean = Point3::Zero();
  for (const Point3& p : near) mean += p;
  mean /= static_cast<double>(near.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  double size = 0.0;
  for (const Point3& p : near) {
    cov += (p - mean) * (p - mean).transpose();
    size = std::max(size, (p - mean).norm());
  }
  if (!(size > 0.0)) return out;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca;
  pca.computeDirect(cov / (size * size));
  const Vector3 e1 = pca.eigenvectors().col(2), e2 = pca.eigenvectors().col(1), e3 = pca.eigenvectors().col(0);
  using Row = Eigen::Matrix<double, 10, 1>;
  Eigen::Matrix<double, 10, 10> AtA = Eigen::Matrix<double, 10, 10>::Zero();
  Row Atz = Row::Zero();
  for (const Point3& p : near) {
    const Vector3 d = (p - x) / size;
    const double s = d.dot(e1), t = d.dot(e2);
    Row a;
    a << 1.0, s, t, s * s, s * t, t * t, s * s * s, s * s * t, s * t * t, t * t * t;
    AtA.selfadjointView<Eigen::Lower>().rankUpdate(a);
    Atz += d.dot(e3) * a;
  }
  AtA = AtA.selfadjointView<Eigen::Lower>();
  auto slopes = [&](auto block, const auto& rhs) -> std::optional<Eigen::Vector2d> {
    const auto ldlt = block.ldlt();
    // A pivoted LDLᵀ's diagonal reveals the rank (Eigen's solve would quietly skip a zero pivot).
    const auto& D = ldlt.vectorD();
    if (ldlt.info() != Eigen::Success || !(D.minCoeff() > kMinPivotRatio * D.maxCoeff())) return std::nullopt;
    const auto c = ldlt.solve(rhs).eval();
    return Eigen::Vector2d(c[1], c[2]);
  };
  const std::optional<Eigen::Vector2d> quadric =
      near.size() >= 6 ? slopes(Eigen::Matrix<double, 6, 6>(AtA.topLeftCorner<6, 6>()), Eigen::Matrix<double, 6, 1>(Atz.head<6>()))
                       : std::nullopt;
  const std::optional<Eigen::Vector2d> cubic = near.size() >= 10 ? slopes(AtA, Atz) : std::nullopt;
  // The slopes at x (s = t = 0); scaling both coordinates by `size` leaves them as they are.
  if (pca.eigenvalues()[1] > kMinPivotRatio * pca.eigenvalues()[2]) out[2] = e3;
  if (quadric) out[0] = (e3 - (*quadric)[0] * e1 - (*quadric)[1] * e2).normalized();
  if (cubic) out[1] = (e3 - (*cubic)[0] * e1 - (*cubic)[1] * e2).normalized();
  return out;
}

// The direction of the line the in-fit point i's nearest neighbours lie along (NormalCheck::line_variance_ratio);
// zero where they do not.
Vector3 line_direction(const geometry::OwnedPointTree& tree, std::size_t i, const NormalCheck& check,
                       std::vector<std::uint32_t>& idx, std::vector<double>& dist_sq) {
  const std::vector<Point3>& pts = tree.cloud.points;
  const std::size_t wanted = std::min<std::size_t>(static_cast<std::size_t>(check.line_neighbours), pts.size());
  idx.resize(wanted);
  dist_sq.resize(wanted);
  nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(wanted);
  knn.init(idx.data(), dist_sq.data());  // squared distances (nanoflann's L2 adaptor)
  const double q[3] = {pts[i].x(), pts[i].y(), pts[i].z()};
  tree.tree.findNeighbors(knn, q, nanoflann::SearchParams());
  if (knn.size() < 3) return Vector3::Zero();
  Point3 mean = Point3::Zero();
  for (std::size_t j = 0; j < knn.size(); ++j) mean += pts[idx[j]];
  mean /= static_cast<double>(knn.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t j = 0; j < knn.size(); ++j) cov += (pts[idx[j]] - mean) * (pts[idx[j]] - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca;
  pca.computeDirect(cov);
  const Eigen::Vector3d e = pca.eigenvalues();  // ascending
  return e[2] > 0.0 && e[1] < check.line_variance_ratio * e[2] ? Vector3(pca.eigenvectors().col(2)) : Vector3::Zero();
}

// How many lines the neighbours `near` of x lie on: their coordinates along `across` (in the surface, across the
// lines), a new line past every gap wider than `gap` or than kLineGapShare of their range.
int lines_spanned(const Point3& x, const Vector3& across, std::span<const Point3> near, double gap,
                  std::vector<double>& coordinate) {
  coordinate.clear();
  for (const Point3& p : near) coordinate.push_back((p - x).dot(across));
  std::sort(coordinate.begin(), coordinate.end());
  if (coordinate.empty()) return 0;
  gap = std::min(gap, kLineGapShare * (coordinate.back() - coordinate.front()));
  int lines = 1;
  for (std::size_t j = 1; j < coordinate.size(); ++j) lines += coordinate[j] - coordinate[j - 1] > gap;
  return lines;
}

}  // namespace

bool sampled_along_lines(std::span<const Point3> centres, const NormalCheck& check) {
  const std::size_t n = centres.size();
  if (n < 3) return false;
  // Blocks of points about kLineBlocks seeds spread over the input, each a cube about kLineBlockSpacings typical
  // spacings wide (the spacing from the bounding box's two largest sides over the number of points): small trees,
  // whatever the face's size (one tree over a million points: 0.27 s). Each block's inner half is tested.
  constexpr std::size_t kLineBlocks = 16;
  constexpr double kLineBlockSpacings = 15.0;
  BoundingBox box;
  for (const Point3& p : centres) box.extend(p);
  Vector3 sides = box.max - box.min;
  std::sort(sides.data(), sides.data() + 3);
  // (Points along one line span no area: their spacing along it.)
  const double spacing = std::max(std::sqrt(sides[1] * sides[2] / static_cast<double>(n)), sides[2] / static_cast<double>(n));
  if (!(spacing > 0.0)) return false;
  const double half = kLineBlockSpacings * spacing;
  std::vector<std::size_t> tested(kLineBlocks, 0), lined(kLineBlocks, 0);
  tbb::parallel_for(std::size_t{0}, kLineBlocks, [&](std::size_t b) {
    const Point3 seed = centres[b * n / kLineBlocks];
    std::vector<Point3> block;
    for (const Point3& p : centres) {
      if (((p - seed).cwiseAbs().array() <= half).all()) block.push_back(p);
    }
    if (block.size() < 3) return;
    const geometry::OwnedPointTree tree(block);
    std::vector<std::uint32_t> idx;
    std::vector<double> dist_sq;
    const std::vector<Point3>& pts = tree.cloud.points;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (!((pts[i] - seed).cwiseAbs().array() <= 0.5 * half).all()) continue;
      ++tested[b];
      lined[b] += line_direction(tree, i, check, idx, dist_sq).squaredNorm() > 0.0;
    }
  });
  std::size_t all_tested = 0, all_lined = 0;
  for (std::size_t b = 0; b < kLineBlocks; ++b) {
    all_tested += tested[b];
    all_lined += lined[b];
  }
  return all_tested > 0 && static_cast<double>(all_lined) >= check.line_share * static_cast<double>(all_tested);
}

NormalDisagreement normal_disagreement(const nurbs::Surface& fit, std::span<const Point3> centres,
                                        std::span<const fitting::SurfaceParameter> params,
                                        std::span<const double> weights, const NormalCheck& check) {
  const std::size_t n = centres.size();
  std::vector<std::uint32_t> kept, left_out;
  for (std::size_t k = 0; k < n; ++k) (weights.empty() || weights[k] > 0.0 ? kept : left_out).push_back(static_cast<std::uint32_t>(k));
  NormalDisagreement out;
  const auto quiet_nan = std::numeric_limits<double>::quiet_NaN();
  if (kept.size() < 6) {
    if (left_out.empty()) return out;
    out.angle.assign(n, 0.0);
    for (std::uint32_t k : kept) out.angle[k] = quiet_nan;
    return out;
  }
  // Sampled along lines? Then each point on one is found below.
  out.along_lines = check.along_lines ? *check.along_lines : sampled_along_lines(centres, check);
  if (left_out.empty() && !out.along_lines) return out;
  // The in-fit centres' tree; its point i is fitted point kept[i].
  std::vector<Point3> kept_centres;
  kept_centres.reserve(kept.size());
  for (std::uint32_t k : kept) kept_centres.push_back(centres[k]);
  const geometry::OwnedPointTree in_fit(std::move(kept_centres));
  const std::vector<Point3>& pts = in_fit.cloud.points;

  // In-fit point i's line direction (zero off lines), and whether it is on one.
  std::vector<Vector3> direction;
  std::vector<char> on_line;
  if (out.along_lines) {
    direction.assign(pts.size(), Vector3::Zero());
    on_line.assign(pts.size(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pts.size(), 1024), [&](const auto& range) {
      std::vector<std::uint32_t> i2;
      std::vector<double> d2;
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        direction[i] = line_direction(in_fit, i, check, i2, d2);
        on_line[i] = direction[i].squaredNorm() > 0.0;
      }
    });
  }
  std::vector<double>& angle = out.angle;
  angle.assign(n, 0.0);

  // The spacing: the median distance from a kept point to its nearest other kept point, over a fixed sample.
  const std::size_t stride = std::max<std::size_t>(1, kept.size() / kSpacingSamples);
  std::vector<double> nearest;
  for (std::size_t i = 0; i < pts.size(); i += stride) {
    std::uint32_t idx[2];
    double dist_sq[2];  // squared distances (nanoflann's L2 adaptor)
    nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(2);
    knn.init(idx, dist_sq);
    const double q[3] = {pts[i].x(), pts[i].y(), pts[i].z()};
    in_fit.tree.findNeighbors(knn, q, nanoflann::SearchParams());
    if (knn.size() == 2) nearest.push_back(std::sqrt(dist_sq[1]));
  }
  const double spacing = nearest.empty() ? 0.0 : geometry::median_in_place(nearest);
  const double reach = check.reach_spacings * spacing;

  // Kept points within reach of a left-out point.
  std::vector<char> near_gap(pts.size(), 0);
  std::vector<std::pair<std::uint32_t, double>> found;
  for (std::uint32_t k : left_out) {
    const double q[3] = {centres[k].x(), centres[k].y(), centres[k].z()};
    found.clear();
    in_fit.tree.radiusSearch(q, reach * reach, found, nanoflann::SearchParams(32, 0.0, false));  // squared radius
    for (const auto& f : found) near_gap[f.first] = 1;
  }
  // Those in the tree's leaf order (neighbouring queries share cached nodes: twice as fast as in input order on
  // scattered points), then the left-out points themselves (whose normal is the gap's), as fitted points. Each
  // result is the point's own, whatever the order.
  // Points on lines beyond check.max_line_checks are checked every stride-th in that order, and the others take the angle of
  // the last one checked before them (a neighbour in the tree's leaf: the angle changes over the lines' spacing, not
  // from point to point along a line).
  // In-fit point i is checked for being on a line, not for being near a gap.
  auto line_only = [&](std::uint32_t i) { return !on_line.empty() && on_line[i] && !near_gap[i]; };
  // line_of_checked: the line's direction for each point checked for being on one (not near a gap), else zero.
  std::vector<std::uint32_t> checked, copied_from_previous;
  std::vector<Vector3> line_of_checked;
  {
    std::size_t on_lines = 0;
    for (const std::uint32_t i : in_fit.tree.vAcc) on_lines += line_only(i);
    const std::size_t most = std::max<std::size_t>(check.max_line_checks, 1);
    const std::size_t stride = (on_lines + most - 1) / most;
    std::size_t seen = 0;
    for (const std::uint32_t i : in_fit.tree.vAcc) {
      if (near_gap[i]) {
        checked.push_back(kept[i]);
        line_of_checked.push_back(Vector3::Zero());
      } else if (line_only(i)) {
        if (seen++ % std::max<std::size_t>(stride, 1) == 0) {
          checked.push_back(kept[i]);
          line_of_checked.push_back(direction[i]);
        } else {
          copied_from_previous.push_back(kept[i]);
        }
      }
    }
  }
  checked.insert(checked.end(), left_out.begin(), left_out.end());
  line_of_checked.resize(checked.size(), Vector3::Zero());
  const double line_gap = kLineGapSpacings * spacing;

  // In fixed chunks of that order, each chunk in turn (a point on a line starts from its predecessor's
  // neighbourhood, below): each result the same whatever the threads.
  constexpr std::size_t kChunk = 64;
  tbb::parallel_for(std::size_t{0}, (checked.size() + kChunk - 1) / kChunk, [&](std::size_t chunk) {
    std::vector<std::uint32_t> idx;
    std::vector<double> dist_sq;  // squared distances (nanoflann's L2 adaptor)
    std::vector<Point3> near;
    std::vector<double> coordinate;
    std::vector<std::pair<std::uint32_t, double>> found;
    double line_radius = line_gap;
    for (std::size_t c = chunk * kChunk; c < std::min(checked.size(), (chunk + 1) * kChunk); ++c) {
      const std::uint32_t k = checked[c];
      const fitting::SurfaceParameter& at = params[k];
      // Both normals where the fit puts the point: at a gross error's own centre, millimetres off, the
      // neighbourhood's plane (tilted from the normal there by its curvature) would put the local models' slope
      // elsewhere.
      const nurbs::SurfaceD1 d = nurbs::derivatives_d1(fit, at.u, at.v);
      const Point3& x = d.S;
      const nurbs::UnitNormal nf = nurbs::unit_normal(fit, at.u, at.v, d.Su, d.Sv);
      double result = quiet_nan;
      const int most = out.along_lines ? check.max_line_neighbours : check.max_neighbours;
      // On a line, the models count the lines their neighbours lie on (kLineGapSpacings), across the line in the
      // fit's tangent plane. (Points near a gap are not: a neighbourhood spread round a gap spans a surface.)
      const Vector3& t = line_of_checked[c];
      const bool line_point = t.squaredNorm() > 0.0 && nf.status != nurbs::UnitNormal::Status::Degenerate;
      const Vector3 across = line_point ? Vector3(nf.n.cross(t).normalized()) : Vector3::Zero();
      // On lines, where no neighbourhood up to the largest fixes a cubic, the smallest neighbourhood's quadric (three
      // lines within reach), else its plane (two): the slope across the lines from as many as there are, which is
      // what the fit's smoothing follows there too. (Two lines 200 mm apart on the NIST part STC-08: unchecked, u
      // would be the whole tip radius on a datum face.)
      Vector3 quadric_only = Vector3::Zero(), plane_only = Vector3::Zero();
      // The local models through `near`: true when they settle the point's angle.
      auto settled_by = [&](std::span<const Point3> near) {
        std::array<Vector3, 3> local = local_normals(x, near);
        if (line_point) {
          const int lines = lines_spanned(x, across, near, line_gap, coordinate);
          if (lines < 4) local[1] = Vector3::Zero();
          if (lines < 3) local[0] = Vector3::Zero();
          if (lines < 2) local[2] = Vector3::Zero();
          if (quadric_only.squaredNorm() == 0.0) quadric_only = local[0];
          if (plane_only.squaredNorm() == 0.0) plane_only = local[2];
        }
        if (!(local[1].squaredNorm() > 0.0)) return false;
        result = 0.0;
        for (int m = 0; m < 2; ++m) {
          if (local[m].squaredNorm() > 0.0) result = std::max(result, std::acos(std::min(std::abs(local[m].dot(nf.n)), 1.0)));
        }
        return true;
      };
      const double q[3] = {x.x(), x.y(), x.z()};
      if (nf.status == nurbs::UnitNormal::Status::Degenerate) {
        // (no normal on the fit: NaN)
      } else if (line_point) {
        // On lines, the neighbours within a radius growing by √2 (twice the points each step), from the one that
        // settled the line point before it in the chunk: four lines take hundreds of points, and a search for the
        // nearest k sorts as it goes (k² work: D500's checks took 0.3 s more a face at k = 320).
        for (double radius = line_radius;; radius *= std::numbers::sqrt2) {
          found.clear();
          in_fit.tree.radiusSearch(q, radius * radius, found, nanoflann::SearchParams(32, 0.0, false));  // squared
          // (Past the most allowed, the nearest that many, and the last try.)
          const bool last = found.size() >= static_cast<std::size_t>(most) || found.size() == pts.size();
          if (found.size() > static_cast<std::size_t>(most)) {
            std::nth_element(found.begin(), found.begin() + most, found.end(), [](const auto& a, const auto& b) {
              return a.second < b.second || (a.second == b.second && a.first < b.first);
            });
            found.resize(static_cast<std::size_t>(most));
          }
          near.clear();
          for (const auto& f : found) near.push_back(pts[f.first]);
          if (settled_by(near)) {
            line_radius = radius;
            break;
          }
          if (last) break;
        }
      } else {
        for (int count = check.neighbours; count <= most; count *= 2) {
          const std::size_t wanted = std::min<std::size_t>(static_cast<std::size_t>(count), pts.size());
          idx.resize(wanted);
          dist_sq.resize(wanted);
          nanoflann::KNNResultSet<double, std::uint32_t, std::uint32_t> knn(wanted);
          knn.init(idx.data(), dist_sq.data());
          in_fit.tree.findNeighbors(knn, q, nanoflann::SearchParams());
          near.clear();
          for (std::size_t j = 0; j < knn.size(); ++j) near.push_back(pts[idx[j]]);
          if (settled_by(near) || wanted == pts.size()) break;
        }
      }
      if (std::isnan(result)) {
        const Vector3& lower = quadric_only.squaredNorm() > 0.0 ? quadric_only : plane_only;
        if (lower.squaredNorm() > 0.0) result = std::acos(std::min(std::abs(lower.dot(nf.n)), 1.0));
      }
      angle[k] = result;
    }
  });
  if (!copied_from_previous.empty()) {
    // In leaf order again: each copied point after the checked one it follows.
    std::vector<char> is_copied(n, 0);
    for (const std::uint32_t k : copied_from_previous) is_copied[k] = 1;
    double last = quiet_nan;
    for (const std::uint32_t i : in_fit.tree.vAcc) {
      const std::uint32_t k = kept[i];
      if (is_copied[k]) {
        angle[k] = last;
      } else if (line_only(i)) {
        last = angle[k];
      }
    }
  }
  return out;
}

}  // namespace probecomp::compensation
