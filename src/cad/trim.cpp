#include "probecomp/cad/trim.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace probecomp::cad {

namespace {
// Bisection depth limit per starting interval: 2^12 samples per knot span is far beyond any real pcurve's need.
constexpr int kMaxBisections = 12;

Eigen::Vector2d uv_at(const nurbs::Curve& c, double t) { return nurbs::evaluate(c, t).head<2>(); }

void bisect(const nurbs::Curve& c, double t0, double t1, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
            double tol, int depth, std::vector<double>& out) {
  const double tm = 0.5 * (t0 + t1);
  const Eigen::Vector2d m = uv_at(c, tm);
  const Eigen::Vector2d chord = b - a;
  const double len = chord.norm();
  const double dev = len > 0.0 ? std::abs(chord.x() * (m - a).y() - chord.y() * (m - a).x()) / len : (m - a).norm();
  if (depth < kMaxBisections && dev > tol) {
    bisect(c, t0, tm, a, m, tol, depth + 1, out);
    bisect(c, tm, t1, m, b, tol, depth + 1, out);
  } else {
    out.push_back(t1);
  }
}
}  // namespace

std::vector<double> boundary_samples(const nurbs::Curve& uv, double chord_tolerance) {
  const std::vector<double> breaks = uv.knots().breakpoints();
  // A straight segment (degree 1) is exact with its breakpoints; curved spans start from 4 pieces each so
  // that an S-shaped span is not mistaken for straight by its midpoint alone.
  const int pieces = uv.degree() == 1 ? 1 : 4;
  std::vector<double> t{breaks.front()};
  for (std::size_t s = 0; s + 1 < breaks.size(); ++s) {
    for (int k = 0; k < pieces; ++k) {
      const double t0 = breaks[s] + (breaks[s + 1] - breaks[s]) * k / pieces;
      const double t1 = k + 1 == pieces ? breaks[s + 1] : breaks[s] + (breaks[s + 1] - breaks[s]) * (k + 1) / pieces;
      bisect(uv, t0, t1, uv_at(uv, t0), uv_at(uv, t1), chord_tolerance, 0, t);
    }
  }
  return t;
}

// The pcurves of a loop meet only to the file's tolerance (1e-9 in v on the die-cast sample's torus fillets). A
// ray through such a gap crosses one side of it and not the other, and a point on the line of a domain edge
// (where the closest-point search clamps) is then taken as inside: a phantom face beyond the trim. Each curve
// end is joined to the nearest other curve end, nearest pairs first, so the polygon is closed.
void Trim::close_loops() {
  struct End {
    Eigen::Vector2d at;
    bool paired = false;
  };
  std::vector<End> ends;
  for (const BoundaryCurve& c : curves_) {
    if (c.t.size() < 2) continue;
    ends.push_back({uv_at(c.uv, c.t.front())});
    ends.push_back({uv_at(c.uv, c.t.back())});
  }
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;  // (squared gap, end, end)
  for (std::size_t i = 0; i < ends.size(); ++i) {
    for (std::size_t j = i + 1; j < ends.size(); ++j) pairs.emplace_back((ends[i].at - ends[j].at).squaredNorm(), i, j);
  }
  std::sort(pairs.begin(), pairs.end());
  for (const auto& [gap, i, j] : pairs) {
    if (ends[i].paired || ends[j].paired) continue;
    ends[i].paired = ends[j].paired = true;
    if (gap > 0.0) segments_.push_back({ends[i].at.x(), ends[i].at.y(), ends[j].at.x(), ends[j].at.y()});
  }
}

Trim::Trim(std::vector<BoundaryCurve> curves) : curves_(std::move(curves)) {
  for (const BoundaryCurve& c : curves_) {
    for (std::size_t k = 0; k + 1 < c.t.size(); ++k) {
      const Eigen::Vector2d a = uv_at(c.uv, c.t[k]);
      const Eigen::Vector2d b = uv_at(c.uv, c.t[k + 1]);
      segments_.push_back(c.reversed ? Segment{b.x(), b.y(), a.x(), a.y()} : Segment{a.x(), a.y(), b.x(), b.y()});
    }
  }
  if (segments_.empty()) return;
  close_loops();
  v_min_ = std::numeric_limits<double>::infinity();
  v_max_ = -std::numeric_limits<double>::infinity();
  for (const Segment& s : segments_) {
    v_min_ = std::min({v_min_, s.v0, s.v1});
    v_max_ = std::max({v_max_, s.v0, s.v1});
  }
  // About 8 segments per band on average keeps a membership test at a few dozen crossings.
  const int n_bands = std::clamp(static_cast<int>(segments_.size() / 8), 1, 4096);
  band_height_ = std::max((v_max_ - v_min_) / n_bands, std::numeric_limits<double>::min());
  bands_.assign(static_cast<std::size_t>(n_bands), {});
  for (std::uint32_t i = 0; i < segments_.size(); ++i) {
    const Segment& s = segments_[i];
    const int b0 = std::clamp(static_cast<int>((std::min(s.v0, s.v1) - v_min_) / band_height_), 0, n_bands - 1);
    const int b1 = std::clamp(static_cast<int>((std::max(s.v0, s.v1) - v_min_) / band_height_), 0, n_bands - 1);
    for (int b = b0; b <= b1; ++b) bands_[static_cast<std::size_t>(b)].push_back(i);
  }
}

bool Trim::contains(double u, double v) const {
  if (segments_.empty()) return true;
  if (!(v >= v_min_ && v <= v_max_)) return false;
  // v = v_max lies on the top edge of the last band.
  const int band = std::min(static_cast<int>((v - v_min_) / band_height_), static_cast<int>(bands_.size()) - 1);
  const auto& ids = bands_[static_cast<std::size_t>(band)];
  // Even-odd rule with a ray towards +u; half-open in v so a ray through a vertex counts it once.
  bool inside = false;
  for (std::uint32_t i : ids) {
    const Segment& s = segments_[i];
    if ((s.v0 > v) != (s.v1 > v)) {
      const double ux = s.u0 + (v - s.v0) * (s.u1 - s.u0) / (s.v1 - s.v0);
      if (ux > u) inside = !inside;
    }
  }
  return inside;
}

bool Trim::meets(const nurbs::Domain& box) const {
  if (segments_.empty()) return true;
  // The box meets the region if a boundary segment enters it, or else if the box lies wholly inside (then
  // its centre is inside). Segment-box overlap is tested on the segment's bounding box: conservative.
  const int n_bands = static_cast<int>(bands_.size());
  const int b0 = std::clamp(static_cast<int>(std::floor((box.v0 - v_min_) / band_height_)), 0, n_bands - 1);
  const int b1 = std::clamp(static_cast<int>(std::floor((box.v1 - v_min_) / band_height_)), 0, n_bands - 1);
  for (int b = b0; b <= b1; ++b) {
    for (std::uint32_t i : bands_[static_cast<std::size_t>(b)]) {
      const Segment& s = segments_[i];
      if (std::max(s.u0, s.u1) >= box.u0 && std::min(s.u0, s.u1) <= box.u1 && std::max(s.v0, s.v1) >= box.v0 &&
          std::min(s.v0, s.v1) <= box.v1) {
        return true;
      }
    }
  }
  return contains(0.5 * (box.u0 + box.u1), 0.5 * (box.v0 + box.v1));
}

nurbs::Domain Trim::parameter_bounds() const {
  nurbs::Domain d{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (const Segment& s : segments_) {
    d.u0 = std::min({d.u0, s.u0, s.u1});
    d.u1 = std::max({d.u1, s.u0, s.u1});
    d.v0 = std::min({d.v0, s.v0, s.v1});
    d.v1 = std::max({d.v1, s.v0, s.v1});
  }
  return d;
}

double Trim::parameter_area() const {
  // Shoelace over all segments: in a valid B-rep, holes run opposite to the outer loop and subtract.
  double a = 0.0;
  for (const Segment& s : segments_) a += s.u0 * s.v1 - s.u1 * s.v0;
  return 0.5 * std::abs(a);
}

}  // namespace probecomp::cad
