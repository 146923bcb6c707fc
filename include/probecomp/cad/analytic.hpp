#pragma once
// Elementary faces in closed form. A CAD file gives most prismatic faces as planes, cylinders, cones, spheres and
// tori; OpenCASCADE converts them to NURBS exactly (straight directions stay linear, circles become rational
// quadratic arcs), and the rest of probecomp works on that NURBS. Their closest point, though, has a closed form:
// the distance separates into the angle about the axis and the position along the meridian, so the nearest point
// of a parameter box is the query's own angle and meridian position, each clamped to the box. An AnalyticFace
// keeps the elementary surface beside the NURBS with the map from the surface's parameters to the NURBS's, and
// gives the face's closest point as the NURBS solver would (same u, v, point, tangents), about 100 times faster.
// It is made only where the map is checked to reproduce the NURBS (make_analytic_face).

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "probecomp/nurbs/closest_point.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::cad {

enum class ElementaryKind : std::uint8_t { Plane, Cylinder, Cone, Sphere, Torus };

[[nodiscard]] const char* to_string(ElementaryKind k);

// OpenCASCADE's parametrisations (ElSLib; gp_Pln, gp_Cylinder, gp_Cone, gp_Sphere, gp_Torus), in a frame whose
// axes x, y, z are orthonormal but may be left-handed (gp_Ax3):
//   plane     O + a x + b y
//   cylinder  O + R (cos a x + sin a y) + b z
//   cone      O + (R + b sin α)(cos a x + sin a y) + b cos α z
//   sphere    O + R cos b (cos a x + sin a y) + R sin b z
//   torus     O + (R + r cos b)(cos a x + sin a y) + r sin b z
struct ElementarySurface {
  ElementaryKind kind = ElementaryKind::Plane;
  Point3 origin = Point3::Zero();
  Vector3 x = Vector3::UnitX(), y = Vector3::UnitY(), z = Vector3::UnitZ();
  double radius = 0.0;        // R: cylinder, cone at b = 0, sphere, torus (major)
  double minor_radius = 0.0;  // r: torus
  double half_angle = 0.0;    // α: cone, radians

  [[nodiscard]] bool a_is_angle() const { return kind != ElementaryKind::Plane; }
  [[nodiscard]] bool b_is_angle() const { return kind == ElementaryKind::Sphere || kind == ElementaryKind::Torus; }
  [[nodiscard]] nurbs::SurfaceD1 derivatives(double a, double b) const;  // S, S_a (in Su), S_b (in Sv)
  // The same from the cosines and sines of the angles among a and b (b alone where b is a length).
  [[nodiscard]] nurbs::SurfaceD1 derivatives(double a, double cos_a, double sin_a, double b, double cos_b,
                                             double sin_b) const;
  // The surface's parameters of a point on it; for a point off it, those of its projection onto the unbounded
  // surface (on the axis, where every angle is as near, the angle is 0).
  [[nodiscard]] std::pair<double, double> parameters(const Point3& p) const;
  // The parallel surface at signed distance d along S_a × S_b, with the same parameters; none where it
  // degenerates (a radius reaching zero).
  [[nodiscard]] std::optional<ElementarySurface> offset(double d) const;
};

// One direction's map from the elementary parameter t to the NURBS parameter u: linear pieces (a straight
// direction), or rational quadratic circular arcs, each a Bézier span of the NURBS.
class ParameterMap {
 public:
  struct Piece {
    double t0 = 0.0, t1 = 0.0;  // the elementary parameter at the span's start and end (t1 < t0 if reversed)
    double u0 = 0.0, u1 = 0.0;  // the NURBS parameter there
    // Arcs only: tan of a quarter of the arc's angle, and sqrt(w0 / w2) of the span's end weights.
    double tan_quarter = 0.0, weight_ratio = 1.0;
    double cos_mid = 1.0, sin_mid = 0.0;  // of the arc's middle angle (set by the map)
  };
  ParameterMap() = default;
  ParameterMap(std::vector<Piece> pieces, bool arcs);

  [[nodiscard]] double lo() const { return lo_; }  // the elementary parameter's range
  [[nodiscard]] double hi() const { return hi_; }
  // u at t (t inside [lo, hi]), and du/dt.
  [[nodiscard]] std::pair<double, double> operator()(double t) const;
  // The same for an angle whose cosine and sine are known: no trigonometric function is called.
  [[nodiscard]] std::pair<double, double> operator()(double t, double cos_t, double sin_t) const;

 private:
  std::vector<Piece> pieces_;  // in order of increasing t
  std::vector<double> starts_;  // each piece's smaller t, for the search
  bool arcs_ = false;
  double lo_ = 0.0, hi_ = 0.0;
};

class AnalyticFace {
 public:
  AnalyticFace(ElementarySurface surface, ParameterMap a_map, ParameterMap b_map);

  [[nodiscard]] const ElementarySurface& surface() const { return surface_; }
  // The face's closest point over its whole parameter domain (not its trim): status Converged inside, OnBoundary
  // where clamped to an edge; u, v and the tangents S_u, S_v are the NURBS's. Exact, and unique but where the
  // query is on an axis or a centre of curvature (every point of a circle as near: one of them is given).
  [[nodiscard]] nurbs::ClosestPointResult closest_point(const Point3& query) const;
  // The NURBS parameters of the elementary (a, b), and the tangents there.
  [[nodiscard]] nurbs::ClosestPointResult at(double a, double b) const;
  // An angle with its cosine and sine (for a straight direction only the first counts).
  struct Angle {
    double t, c, s;
  };
  // The same face offset by d along S_u × S_v of its NURBS (the parametrisation is kept, as offset_surface keeps
  // it); none where the offset degenerates.
  [[nodiscard]] std::optional<AnalyticFace> offset(double d) const;
  // The unbounded surface offset so, even where it degenerates inside the face's range (a countersink's offset cone
  // whose apex falls inside it): what points off the degenerate part lie on. None where it has no radius at all.
  [[nodiscard]] std::optional<ElementarySurface> offset_surface(double d) const {
    return surface_.offset(normal_sign_ * d);
  }
  // The largest distance (mm) between the NURBS and this face at the same (u, v), and the largest angle between
  // their normals (radians; poles and apexes skipped), over a grid of `per_span` steps per knot span and direction.
  struct Check {
    double distance = 0.0;
    double normal_angle = 0.0;
  };
  [[nodiscard]] Check compare(const nurbs::Surface& nurbs_surface, int per_span = 4) const;

 private:
  [[nodiscard]] nurbs::ClosestPointResult at(const Angle& a, const Angle& b) const;

  ElementarySurface surface_;
  ParameterMap a_map_, b_map_;
  int normal_sign_ = 1;  // S_u × S_v of the NURBS over S_a × S_b of the elementary surface: ±1
};

// Points of the NURBS and of the closed form must agree to this (mm) on the check grid: OpenCASCADE's exact
// conversion reproduces them to rounding (1e-12 relative); anything more means the map is not the NURBS's.
inline constexpr double kAnalyticMatch = 1e-8;
// Their normals must agree to this (radians): 1e-12 relative rounding in the tangents gives about 1e-12 rad, so
// this is loose, yet it refuses a map whose derivative is wrong by anything that matters.
inline constexpr double kAnalyticNormalMatch = 1e-7;

// The face's closed form where the NURBS is `surface` converted exactly and its directions are the elementary
// a and b in that order (straight: degree 1, one weight; circular: degree 2, Bézier spans); null otherwise, or
// when the check grid finds the two farther apart than `tolerance` (mm) or their tangent planes apart.
[[nodiscard]] std::shared_ptr<const AnalyticFace> make_analytic_face(const ElementarySurface& surface,
                                                                     const nurbs::Surface& nurbs_surface,
                                                                     double tolerance = kAnalyticMatch);

}  // namespace probecomp::cad
