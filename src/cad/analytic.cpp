#include "probecomp/cad/analytic.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace probecomp::cad {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// A tangent shorter than this fraction of the surface's size is a pole's or an apex's: its direction says nothing,
// so the tangent check skips it.
constexpr double kPoleTangent = 1e-9;

double positive_mod_2pi(double x) { return x - kTwoPi * std::floor(x / kTwoPi); }

// The angle in [lo, hi] (hi − lo ≤ 2π, unwrapped) nearest to θ around the circle: θ itself, moved by turns,
// when it falls inside, else the nearer end (a distance that falls as cos(angle apart) rises, so the nearer
// end around the circle is the nearer point).
double closest_angle(double theta, double lo, double hi, bool& clamped) {
  const double t = lo + positive_mod_2pi(theta - lo);
  if (t <= hi) return t;
  clamped = true;
  return (t - hi) <= (lo + kTwoPi - t) ? hi : lo;
}

double clamp_to(double t, double lo, double hi, bool& clamped) {
  if (t < lo) {
    clamped = true;
    return lo;
  }
  if (t > hi) {
    clamped = true;
    return hi;
  }
  return t;
}

// +1 when the frame is right-handed (z = x × y), −1 when left-handed.
double handedness(const ElementarySurface& s) { return s.x.cross(s.y).dot(s.z) >= 0.0 ? 1.0 : -1.0; }

}  // namespace

const char* to_string(ElementaryKind k) {
  switch (k) {
    case ElementaryKind::Plane: return "plane";
    case ElementaryKind::Cylinder: return "cylinder";
    case ElementaryKind::Cone: return "cone";
    case ElementaryKind::Sphere: return "sphere";
    case ElementaryKind::Torus: return "torus";
  }
  return "unknown";
}

nurbs::SurfaceD1 ElementarySurface::derivatives(double a, double b) const {
  return derivatives(a, std::cos(a), std::sin(a), b, std::cos(b), std::sin(b));
}

nurbs::SurfaceD1 ElementarySurface::derivatives(double a, double ca, double sa, double b, double cb, double sb) const {
  if (kind == ElementaryKind::Plane) return {origin + a * x + b * y, x, y};
  const Vector3 e = ca * x + sa * y;    // radial direction at angle a
  const Vector3 e1 = -sa * x + ca * y;  // its derivative
  switch (kind) {
    case ElementaryKind::Cylinder: return {origin + radius * e + b * z, radius * e1, z};
    case ElementaryKind::Cone: {
      const double s = std::sin(half_angle), c = std::cos(half_angle);
      const double rho = radius + b * s;
      return {origin + rho * e + b * c * z, rho * e1, s * e + c * z};
    }
    case ElementaryKind::Sphere: return {origin + radius * (cb * e + sb * z), radius * cb * e1, radius * (-sb * e + cb * z)};
    case ElementaryKind::Torus: {
      const double rho = radius + minor_radius * cb;
      return {origin + rho * e + minor_radius * sb * z, rho * e1, minor_radius * (-sb * e + cb * z)};
    }
    default: return {origin, x, y};
  }
}

std::pair<double, double> ElementarySurface::parameters(const Point3& p) const {
  const Vector3 d = p - origin;
  const double px = d.dot(x), py = d.dot(y), pz = d.dot(z);
  if (kind == ElementaryKind::Plane) return {px, py};
  const double a = std::atan2(py, px);
  const double rho = std::sqrt(px * px + py * py);
  switch (kind) {
    case ElementaryKind::Cylinder: return {a, pz};
    case ElementaryKind::Cone: return {a, (rho - radius) * std::sin(half_angle) + pz * std::cos(half_angle)};
    case ElementaryKind::Sphere: return {a, std::atan2(pz, rho)};
    case ElementaryKind::Torus: return {a, std::atan2(pz, rho - radius)};
    default: return {px, py};
  }
}

std::optional<ElementarySurface> ElementarySurface::offset(double d) const {
  // S_a × S_b is σ z for the plane and σ times the outward radial direction (of the meridian's circle or line) for
  // the others, σ the frame's handedness; so the offset changes one radius, and for the cone the origin too.
  const double s = handedness(*this) * d;
  ElementarySurface o = *this;
  switch (kind) {
    case ElementaryKind::Plane: o.origin += d * x.cross(y); return o;
    case ElementaryKind::Cylinder:
    case ElementaryKind::Sphere:
      o.radius = radius + s;
      if (!(o.radius > 0.0)) return std::nullopt;
      return o;
    case ElementaryKind::Cone:
      // S + d n = O − σ d sin α z + (R + σ d cos α + b sin α) e + b cos α z: a cone of the same angle.
      o.radius = radius + s * std::cos(half_angle);
      o.origin -= s * std::sin(half_angle) * z;
      return o;
    case ElementaryKind::Torus:
      o.minor_radius = minor_radius + s;
      if (!(o.minor_radius > 0.0)) return std::nullopt;
      return o;
  }
  return std::nullopt;
}

ParameterMap::ParameterMap(std::vector<Piece> pieces, bool arcs) : pieces_(std::move(pieces)), arcs_(arcs) {
  if (pieces_.empty()) return;
  if (pieces_.front().t1 < pieces_.front().t0) std::reverse(pieces_.begin(), pieces_.end());
  lo_ = std::min(pieces_.front().t0, pieces_.front().t1);
  hi_ = std::max(pieces_.back().t0, pieces_.back().t1);
  starts_.reserve(pieces_.size());
  for (Piece& p : pieces_) {
    starts_.push_back(std::min(p.t0, p.t1));
    p.cos_mid = std::cos(0.5 * (p.t0 + p.t1));
    p.sin_mid = std::sin(0.5 * (p.t0 + p.t1));
  }
}

std::pair<double, double> ParameterMap::operator()(double t) const {
  if (!arcs_) return (*this)(t, 0.0, 0.0);
  return (*this)(t, std::cos(t), std::sin(t));
}

std::pair<double, double> ParameterMap::operator()(double t, double cos_t, double sin_t) const {
  const auto it = std::upper_bound(starts_.begin(), starts_.end(), t);
  const std::size_t k = it == starts_.begin() ? 0 : static_cast<std::size_t>(it - starts_.begin() - 1);
  const Piece& p = pieces_[k];
  if (!arcs_) {
    const double slope = (p.u1 - p.u0) / (p.t1 - p.t0);
    return {p.u0 + (t - p.t0) * slope, slope};
  }
  // A rational quadratic arc of angle 2h with weights (1, cos h, 1) passes the angle ψ from its middle at the
  // parameter τ' with tan(ψ/2) = tan(h/2)(2τ' − 1) (its Bézier form, The NURBS Book §7.3, with the half-angle
  // identities); end weights w0, w2 rescale τ'/(1 − τ') by μ = sqrt(w0/w2), the reparametrisation that makes them
  // equal (ibid. §6.3). tan(ψ/2) = sin ψ / (1 + cos ψ), with |ψ| < π/2 on an arc of under π.
  const double cos_psi = cos_t * p.cos_mid + sin_t * p.sin_mid;
  const double sin_psi = sin_t * p.cos_mid - cos_t * p.sin_mid;
  const double half = sin_psi / (1.0 + cos_psi);
  const double s = 0.5 * (1.0 + half / p.tan_quarter);
  const double mu = p.weight_ratio;
  const double denominator = 1.0 - s + mu * s;
  const double tau = mu * s / denominator;
  const double dtau_dt = mu / (denominator * denominator) * (1.0 + half * half) / (4.0 * p.tan_quarter);
  return {p.u0 + tau * (p.u1 - p.u0), dtau_dt * (p.u1 - p.u0)};
}

AnalyticFace::AnalyticFace(ElementarySurface surface, ParameterMap a_map, ParameterMap b_map)
    : surface_(std::move(surface)), a_map_(std::move(a_map)), b_map_(std::move(b_map)) {
  const double du = a_map_(0.5 * (a_map_.lo() + a_map_.hi())).second;
  const double dv = b_map_(0.5 * (b_map_.lo() + b_map_.hi())).second;
  normal_sign_ = (du > 0.0) == (dv > 0.0) ? 1 : -1;
}

nurbs::ClosestPointResult AnalyticFace::at(double a, double b) const {
  return at(Angle{a, std::cos(a), std::sin(a)}, Angle{b, std::cos(b), std::sin(b)});
}

nurbs::ClosestPointResult AnalyticFace::at(const Angle& a, const Angle& b) const {
  const nurbs::SurfaceD1 d = surface_.derivatives(a.t, a.c, a.s, b.t, b.c, b.s);
  const auto [u, du] = a_map_(a.t, a.c, a.s);
  const auto [v, dv] = b_map_(b.t, b.c, b.s);
  nurbs::ClosestPointResult r;
  r.status = nurbs::ClosestPointStatus::Converged;
  r.u = u;
  r.v = v;
  r.point = d.S;
  r.Su = d.Su / du;
  r.Sv = d.Sv / dv;
  return r;
}

namespace {

// The angle of (c, s) (not both zero: then the angle 0) nearest to it in [lo, hi], with its cosine and sine: the
// direction's own where it falls inside, so no trigonometric function is needed but atan2. `norm` is |(c, s)|,
// which the caller often has already.
AnalyticFace::Angle closest_angle_of(double c, double s, double norm, double lo, double hi, bool& clamped) {
  if (!(norm > 0.0)) c = 1.0, s = 0.0;
  else c /= norm, s /= norm;
  bool out = false;
  const double t = closest_angle(std::atan2(s, c), lo, hi, out);
  if (!out) return {t, c, s};
  clamped = true;
  return {t, std::cos(t), std::sin(t)};
}

AnalyticFace::Angle length(double t) { return {t, 0.0, 0.0}; }

}  // namespace

nurbs::ClosestPointResult AnalyticFace::closest_point(const Point3& query) const {
  if (!query.allFinite()) {
    nurbs::ClosestPointResult r;
    r.status = nurbs::ClosestPointStatus::NumericalError;
    return r;
  }
  const ElementarySurface& s = surface_;
  const Vector3 d = query - s.origin;
  const double px = d.dot(s.x), py = d.dot(s.y), pz = d.dot(s.z);
  bool clamped = false;
  Angle a{}, b{};
  if (s.kind == ElementaryKind::Plane) {
    a = length(clamp_to(px, a_map_.lo(), a_map_.hi(), clamped));
    b = length(clamp_to(py, b_map_.lo(), b_map_.hi(), clamped));
  } else {
    // The distance to the point at (a, b) falls as cos(θ − a) rises, whatever b (the radius at b is positive on
    // the face: make_analytic_face checks it), so a is the query's angle θ, or the nearer end; then b is the
    // nearest point of the meridian, a line or a circle, in the half-plane at a, where the query stands at
    // ρ cos(θ − a) from the axis.
    const double rho = std::sqrt(px * px + py * py);
    bool a_clamped = false;
    a = closest_angle_of(px, py, rho, a_map_.lo(), a_map_.hi(), a_clamped);
    const double rho_a = a_clamped ? px * a.c + py * a.s : rho;
    switch (s.kind) {
      case ElementaryKind::Cylinder: b = length(clamp_to(pz, b_map_.lo(), b_map_.hi(), clamped)); break;
      case ElementaryKind::Cone:
        b = length(clamp_to((rho_a - s.radius) * std::sin(s.half_angle) + pz * std::cos(s.half_angle), b_map_.lo(),
                            b_map_.hi(), clamped));
        break;
      case ElementaryKind::Sphere:
        b = closest_angle_of(rho_a, pz, std::sqrt(rho_a * rho_a + pz * pz), b_map_.lo(), b_map_.hi(), clamped);
        break;
      case ElementaryKind::Torus: {
        const double from_tube = rho_a - s.radius;  // in the meridian half-plane, from the tube's centre
        b = closest_angle_of(from_tube, pz, std::sqrt(from_tube * from_tube + pz * pz), b_map_.lo(), b_map_.hi(), clamped);
        break;
      }
      default: break;
    }
    clamped = clamped || a_clamped;
  }
  nurbs::ClosestPointResult r = at(a, b);
  if (clamped) r.status = nurbs::ClosestPointStatus::OnBoundary;
  r.distance = (query - r.point).norm();
  r.starts = 1;
  return r;
}

namespace {

// The closed form takes the query's own angle about the axis as the nearest whatever the meridian position, which
// holds while the radius at every meridian position of the face is positive.
bool radius_positive(const ElementarySurface& s, const ParameterMap& b) {
  if (s.kind == ElementaryKind::Cone) {
    const double sine = std::sin(s.half_angle);
    return std::min(s.radius + b.lo() * sine, s.radius + b.hi() * sine) > 0.0;
  }
  if (s.kind == ElementaryKind::Torus) return s.radius > s.minor_radius;
  return true;
}

}  // namespace

std::optional<AnalyticFace> AnalyticFace::offset(double d) const {
  // The NURBS's unit normal is normal_sign_ times the elementary one (S_u = S_a / (du/da), likewise S_v).
  const std::optional<ElementarySurface> o = surface_.offset(normal_sign_ * d);
  if (!o || !radius_positive(*o, b_map_)) return std::nullopt;
  return AnalyticFace(*o, a_map_, b_map_);
}

AnalyticFace::Check AnalyticFace::compare(const nurbs::Surface& nurbs_surface, int per_span) const {
  Check check;
  const double size = nurbs::bounding_box(nurbs_surface).diagonal();
  auto grid = [per_span](double lo, double hi, int pieces) {
    std::vector<double> t;
    const int n = per_span * std::max(pieces, 1);
    for (int k = 0; k <= n; ++k) t.push_back(lo + (hi - lo) * k / n);
    return t;
  };
  const std::vector<double> ta = grid(a_map_.lo(), a_map_.hi(), nurbs_surface.U().num_spans());
  const std::vector<double> tb = grid(b_map_.lo(), b_map_.hi(), nurbs_surface.V().num_spans());
  for (const double a : ta) {
    for (const double b : tb) {
      const nurbs::ClosestPointResult e = at(a, b);
      const nurbs::SurfaceD1 n = nurbs::derivatives_d1(nurbs_surface, e.u, e.v);
      check.distance = std::max(check.distance, (n.S - e.point).norm());
      const Vector3 ne = e.Su.cross(e.Sv), nn = n.Su.cross(n.Sv);
      if (e.Su.norm() < kPoleTangent * size || e.Sv.norm() < kPoleTangent * size || ne.norm() == 0.0 ||
          nn.norm() == 0.0) {
        continue;
      }
      // atan2 of sine and cosine: acos of a cosine near 1 would floor at 1e-8 rad from rounding.
      const Vector3 me = ne.normalized(), mn = nn.normalized();
      check.normal_angle = std::max(check.normal_angle, std::atan2(me.cross(mn).norm(), me.dot(mn)));
    }
  }
  return check;
}

namespace {

// The map of one direction of `n` (u when along_u) to the elementary parameter a (b), or none when that
// direction is not a straight one of degree 1 with one weight, or circular arcs of degree 2 in Bézier spans.
std::optional<ParameterMap> direction_map(const ElementarySurface& s, const nurbs::Surface& n, bool along_u) {
  const nurbs::KnotVector& K = along_u ? n.U() : n.V();
  const bool angle = along_u ? s.a_is_angle() : s.b_is_angle();
  const std::vector<double> breaks = K.breakpoints();
  if (breaks.size() < 2) return std::nullopt;
  const nurbs::Domain dom = n.domain();
  const double other_mid = along_u ? 0.5 * (dom.v0 + dom.v1) : 0.5 * (dom.u0 + dom.u1);
  auto parameter_at = [&](double t) {
    const Point3 p = along_u ? nurbs::evaluate(n, t, other_mid) : nurbs::evaluate(n, other_mid, t);
    const auto [a, b] = s.parameters(p);
    return along_u ? a : b;
  };
  auto weight = [&](int i, int j) { return along_u ? n.weight(i, j) : n.weight(j, i); };
  const int count = along_u ? n.num_u() : n.num_v();
  const int lines = along_u ? n.num_v() : n.num_u();
  std::vector<ParameterMap::Piece> pieces;
  if (!angle) {
    if (K.degree() != 1) return std::nullopt;
    // One weight along the direction on every line: the map is then linear in each span.
    for (int j = 0; j < lines; ++j) {
      for (int i = 1; i < count; ++i) {
        if (std::abs(weight(i, j) - weight(0, j)) > 1e-12 * std::abs(weight(0, j))) return std::nullopt;
      }
    }
    for (std::size_t k = 0; k + 1 < breaks.size(); ++k) {
      pieces.push_back({parameter_at(breaks[k]), parameter_at(breaks[k + 1]), breaks[k], breaks[k + 1], 0.0, 1.0});
    }
    if (!(pieces.front().t1 != pieces.front().t0)) return std::nullopt;
  } else {
    if (K.degree() != 2 || count != 2 * static_cast<int>(breaks.size()) - 1) return std::nullopt;
    for (std::size_t k = 1; k + 1 < breaks.size(); ++k) {
      if (K.multiplicity(breaks[k]) != 2) return std::nullopt;
    }
    double t0 = parameter_at(breaks[0]);
    for (std::size_t k = 0; k + 1 < breaks.size(); ++k) {
      // An arc of a converted circle spans under π (OpenCASCADE's are at most 2π/3): its end is the nearer turn.
      const double span = std::remainder(parameter_at(breaks[k + 1]) - t0, kTwoPi);
      if (!(std::abs(span) > 0.0 && std::abs(span) < 0.99 * std::numbers::pi)) return std::nullopt;
      const int i = 2 * static_cast<int>(k);
      const double w0 = weight(i, 0), w2 = weight(i + 2, 0);
      if (!(w0 > 0.0 && w2 > 0.0)) return std::nullopt;
      pieces.push_back({t0, t0 + span, breaks[k], breaks[k + 1], std::tan(0.25 * span), std::sqrt(w0 / w2)});
      t0 += span;
    }
  }
  // The elementary parameter must run one way over the whole direction.
  const bool rising = pieces.front().t1 > pieces.front().t0;
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    if ((pieces[k].t1 > pieces[k].t0) != rising) return std::nullopt;
    if (k > 0 && std::abs(pieces[k].t0 - pieces[k - 1].t1) > 1e-9 * (1.0 + std::abs(pieces[k].t0))) return std::nullopt;
  }
  if (angle && std::abs(pieces.back().t1 - pieces.front().t0) > kTwoPi * (1.0 + 1e-12)) return std::nullopt;
  return ParameterMap(std::move(pieces), angle);
}

}  // namespace

std::shared_ptr<const AnalyticFace> make_analytic_face(const ElementarySurface& surface, const nurbs::Surface& nurbs_surface,
                                                       double tolerance) {
  const std::optional<ParameterMap> a = direction_map(surface, nurbs_surface, true);
  if (!a) return nullptr;
  const std::optional<ParameterMap> b = direction_map(surface, nurbs_surface, false);
  if (!b) return nullptr;
  if (!radius_positive(surface, *b)) return nullptr;
  auto face = std::make_shared<const AnalyticFace>(surface, *a, *b);
  const AnalyticFace::Check check = face->compare(nurbs_surface);
  if (!(check.distance <= tolerance) || !(check.normal_angle <= kAnalyticNormalMatch)) return nullptr;
  return face;
}

}  // namespace probecomp::cad
