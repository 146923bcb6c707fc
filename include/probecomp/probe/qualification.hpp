#pragma once
// A stylus qualified on a reference sphere (DESIGN.md §8): the sphere of known diameter fitted to the recorded tip
// centres, and the tip's effective radius as a function of the direction the probe travelled to touch.
//
// The centres lie at |c − C| = R + r(d), R the sphere's radius, r(d) the effective radius for travel direction d (the
// nominal radius less the pre-travel in that direction). r(d) is modelled by real spherical harmonics of d of
// degrees 0 and 2..L (spherical_harmonics.hpp), penalised by λ·Σ (l(l+1))² a_lm² (the surface Laplacian's energy:
// Wahba's splines on the sphere, truncated), L and λ chosen by leave-one-out cross-validation.
//
// What the model cannot see: degree 1. A term a·d of the effective radius moves every centre by the same vector,
// exactly as a shift of the sphere's centre does, so the fit puts it in the centre (`sphere_centre`). On a part it is
// one translation of every point taken with that stylus: registration absorbs it and no form, profile or size
// changes, but positions in the machine frame, and between styli, carry it. A pre-travel growing with the angle from
// the stylus is partly such a term (the part that goes as cos θ), partly degrees 0 and 2 (seen). Nor can it see
// directions it was not touched from: a part's point approached from farther than `support_angle` from every
// qualification touch gets no model value (see effective_radius).

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "probecomp/geometry/types.hpp"
#include "probecomp/probe/spherical_harmonics.hpp"

namespace probecomp::probe {

struct QualificationOptions {
  // The highest degree tried; the data choose L ≤ this, and the penalty's weight. Degree 8 holds a three-lobed
  // pattern's main terms (3, 5 and 7, and their change with the angle from the stylus).
  int max_degree = 8;
  // A degree is tried when the touches number at least this many per parameter (81 + 3 at degree 8: 168 touches);
  // the penalty, not this, keeps the model's variance down.
  int touches_per_parameter = 2;
};

enum class QualificationStatus {
  OK,
  TooFewTouches,   // fewer than kMinimumTouches: no sphere can be told from the noise
  NumericalError,  // the sphere fit did not converge
};
[[nodiscard]] const char* to_string(QualificationStatus s);

// The smallest qualification: the centre (3) and radius (1) of a sphere with one redundant touch. ISO 10360-5's
// probing test takes 25.
inline constexpr int kMinimumTouches = 5;

// r(d) = Σ coefficient_k · Y_k(d), mm; d the travel direction (into the sphere), machine frame.
struct RadiusModel {
  std::vector<HarmonicIndex> terms{};
  std::vector<double> coefficients{};
  // Of the coefficients (mm²), from the fit's residual variance and its linearisation at the solution, with the
  // centre's correlation taken in: the model's own uncertainty in a direction is √(yᵀ Σ y).
  std::vector<std::vector<double>> covariance{};
  double log10_smoothing = 0.0;  // log10(λ / touches) of the chosen fit (0 for degree 0)
  [[nodiscard]] int degree() const;
  [[nodiscard]] double radius(const Vector3& travel) const;
  [[nodiscard]] double uncertainty(const Vector3& travel) const;
  // The rms over all directions of the terms above degree 0: how much the radius varies with direction.
  [[nodiscard]] double variation() const;
};

struct StylusQualification {
  std::string stylus;
  QualificationStatus status = QualificationStatus::TooFewTouches;
  std::string reason;  // empty when OK
  int touches = 0;
  double sphere_diameter = 0.0;             // given, mm
  Point3 sphere_centre = Point3::Zero();    // fitted, machine frame
  double effective_radius = 0.0;            // the plain sphere fit's: mean |c − C| − R, mm
  double effective_radius_u = 0.0;          // its standard uncertainty, mm
  // ISO 10360-5 style figures of the plain sphere fit (centre and one radius): the range of the radial residuals
  // (the touches' form error) and their rms.
  double form_error = 0.0, sphere_rms = 0.0;
  RadiusModel model{};
  double residual = 0.0;                    // rms of the touches' residuals about the model, mm
  double loo_residual = 0.0;                // its leave-one-out rms, which chose the degree, mm
  // The travel directions touched (unit), and the largest angle a direction may be from the nearest of them and
  // still take the model's value (1.5 × the widest gap a touch has to its nearest neighbour, at least 10°): the
  // model is not extrapolated.
  std::vector<Vector3> directions{};
  double support_angle_deg = 0.0;
};

// The stylus's qualification from the recorded centres and, where given, the programmed outward normals (i,j,k);
// without them the travel direction is taken towards the fitted centre.
[[nodiscard]] StylusQualification qualify_stylus(std::string stylus, std::span<const Point3> centres,
                                                 std::span<const Vector3> normals, double sphere_diameter,
                                                 const QualificationOptions& options = {});

struct EffectiveRadius {
  double radius = 0.0;       // mm
  double uncertainty = 0.0;  // the model's, mm (k = 1)
  // The direction is farther than support_angle_deg from every qualification touch: `radius` is then the plain
  // sphere fit's and `uncertainty` includes the model's variation over all directions.
  bool unsupported = false;
};
[[nodiscard]] EffectiveRadius effective_radius(const StylusQualification& q, const Vector3& travel);

struct Qualification {
  std::vector<StylusQualification> styli{};
  // The stylus of that name (exact match), or null.
  [[nodiscard]] const StylusQualification* find(const std::string& stylus) const;
  // The sphere-fit effective radius of each stylus qualified (status OK), in file order, mm.
  [[nodiscard]] std::vector<double> effective_radii() const;
};

}  // namespace probecomp::probe
