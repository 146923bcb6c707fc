#pragma once
// Simulated measurements for judging the fit on shapes it was not tuned to (issue 48): families of deformation
// (bulges, dents, windowed waves in bands or over the whole face, smoothed creases along any line, twists and
// saddles) on several base surfaces, sampled as a part program's grid, random points or a scanning probe's lines,
// at any noise. `shape_suite()` is the fixed list the project's figures are quoted on; `draw_shape_case(seed)`
// draws a case from the same families that no one has tuned to.

#include <cstdint>
#include <string>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/geometry/rigid.hpp"
#include "probecomp/simulation/deformation.hpp"
#include "probecomp/simulation/measure.hpp"

namespace probecomp::simulation {

enum class BaseSurface {
  Panel,     // the paper's free-form panel (freeform_case.hpp): rational bicubic, 100 × 50 mm
  Hood,      // a non-rational bicubic, 80 × 70 mm, doubly curved with a twist: another designer's panel
  Cylinder,  // an exact rational cylinder section, R 40 mm, 100° of arc, 60 mm long (the convex side)
};
[[nodiscard]] const char* to_string(BaseSurface b);
// One face, CAD frame, material side not in the file (a lone surface: decided from i,j,k or the data).
[[nodiscard]] cad::Model base_model(BaseSurface b);

// One feature of the deformation, placed on the base surface by its parameters so that it means the same on
// every base. Directions are angles in the tangent plane at (u, v), from S_u towards S_v.
struct FeatureSpec {
  enum class Kind {
    Bump,    // amplitude a (< 0: a dent), size = the Gaussian's standard deviation
    Wave,    // amplitude a, size = wavelength, travelling along `angle`; window > 0: Gaussian window of that
             // standard deviation, radial about (u, v), or across a band (band_angle from the wave's direction)
    Crease,  // a smoothed step of height a rising over `size` mm across the line through (u, v) normal to `angle`
    Twist,   // a·s·t / size², s along `angle`, t along angle + 90° (a saddle when `angle` is 45° off the axes)
  };
  Kind kind = Kind::Bump;
  double u = 0.5, v = 0.5;  // fractions of the base's domain
  double angle = 0.0;       // degrees
  double amplitude = 0.0;   // mm
  double size = 1.0;        // mm
  double window = 0.0;      // Wave: mm, 0 for the whole face
  bool band = false;        // Wave: the window over the distance along band_angle only
  double band_angle = 0.0;  // degrees from the wave's direction
};
[[nodiscard]] std::string describe(const FeatureSpec& f);

enum class Sampling {
  Grid,       // evenly in (u, v), with the programmed normals (a part program)
  Random,     // uniform in (u, v), shuffled
  ScanLines,  // lines `line_spacing` mm apart, dense along, without i,j,k (a scanning probe)
};
[[nodiscard]] const char* to_string(Sampling s);

struct ShapeCase {
  std::string name;
  BaseSurface base = BaseSurface::Panel;
  std::vector<FeatureSpec> features;
  Sampling sampling = Sampling::Grid;
  int points = 7000;           // about this many (grids and scan lines round to whole rows)
  double line_spacing = 4.0;   // ScanLines, mm
  bool approach_normals = true;  // grids and random points: whether the CAD method gets i,j,k (scan lines never do)
  double noise_sigma = 0.0045;   // mm
  double probe_radius = 1.0;     // mm
  // CAD to machine: rotations about x, y, z (degrees, in that order) and a translation (mm).
  double rx = 0.0, ry = 0.0, rz = 0.0;
  Vector3 t = Vector3::Zero();
  std::uint64_t seed = 1;  // noise and random points
  // Which realisation of the noise: 0 is the case's own; others draw the noise again on the same points and the
  // same part, to tell what a fit does on average from what one draw of the noise happens to do.
  std::uint64_t noise_draw = 0;
  [[nodiscard]] geometry::RigidTransform placement() const;
};

// The length of a face along u at its middle v (along_u), or along v at its middle u, mm: its size in each
// direction of its parameters.
[[nodiscard]] double length_along(const nurbs::Surface& s, bool along_u);

// The deformation of `c`'s features on its base surface (positions and directions taken on the nominal face).
[[nodiscard]] Deformation deformation_of(const ShapeCase& c, const cad::Model& nominal);
// Its programmed points, in measurement order.
[[nodiscard]] std::vector<ProgrammedPoint> plan_of(const ShapeCase& c, const cad::Model& nominal);

// The fixed suite: 30 cases over the three bases, the three samplings, every family, σ = 0 to 10 µm.
[[nodiscard]] std::vector<ShapeCase> shape_suite();
// A case drawn at random from the families (one to three features, any base and sampling, σ as given), for
// checking a claim on shapes no one has looked at.
[[nodiscard]] ShapeCase draw_shape_case(std::uint64_t seed, double noise_sigma);

}  // namespace probecomp::simulation
