#pragma once
// A simulated CMM measurement as the paper makes it (§7; DESIGN.md §3): the machine is programmed with nominal
// points and their outward normals; the probe travels along each normal line towards the part until its tip
// sphere touches the actual (misaligned, deformed) part, i.e. until the line meets the actual surface offset by
// the tip radius; noise is then added to that centre.

#include <cstdint>
#include <span>
#include <vector>

#include "probecomp/cad/locator.hpp"
#include "probecomp/geometry/rigid.hpp"
#include "probecomp/simulation/deformation.hpp"
#include "probecomp/simulation/pretravel.hpp"

namespace probecomp::simulation {

// A programmed point: nominal position and unit outward normal, machine frame (as the part program has them).
struct ProgrammedPoint {
  Point3 point = Point3::Zero();
  Vector3 normal = Vector3::UnitZ();
  int face = -1;  // the nominal face it was planned on, when known
};

struct Touch {
  enum class Status {
    OK,      // the tip touched the inside of a face
    Edge,    // the tip touched a face's edge: the contact is on the boundary, not where the normal says
    Missed,  // no touch along the line near the programmed point (the part is not there, or is met grazing)
  };
  Status status = Status::Missed;
  Point3 centre = Point3::Zero();    // the probe centre at the touch, exact
  Point3 measured = Point3::Zero();  // centre + pre-travel + noise: what the machine reports
  Point3 contact = Point3::Zero();   // the touched point of the actual part
  Vector3 normal = Vector3::Zero();  // the actual part's outward unit normal there
  int face = -1;
  double u = 0.0, v = 0.0;           // on the actual face
  double travel = 0.0;               // centre = programmed point + travel · normal, mm
};
[[nodiscard]] const char* to_string(Touch::Status s);

// Programmed points on one face, outward normals from its material side: an nu × nv grid evenly spaced in
// (u, v) (nu along u), or n points at random (u, v). Both keep a margin (a fraction of the domain in u and in
// v) that keeps the tip off the edges after misalignment and deformation. The face's trim is not consulted.
struct PlanMargin {
  double u = 0.04, v = 0.04;
};
[[nodiscard]] std::vector<ProgrammedPoint> grid_plan(const cad::Face& face, int nu, int nv, PlanMargin margin = {});
[[nodiscard]] std::vector<ProgrammedPoint> random_plan(const cad::Face& face, int n, std::uint64_t seed,
                                                       PlanMargin margin = {});
// A scanning probe's lines: `lines` iso-parameter lines evenly spaced in v, each running along u with `per_line`
// points evenly spaced (along_u false: the roles of u and v exchanged), in the order a scan takes them, back and
// forth line after line.
[[nodiscard]] std::vector<ProgrammedPoint> scan_line_plan(const cad::Face& face, int lines, int per_line, bool along_u,
                                                          PlanMargin margin = {});

struct MeasurementOptions {
  double probe_radius = 1.0;  // mm
  std::vector<double> probe_radii{};  // per programmed point (mm) when several tips measure; empty: probe_radius
  double noise_sigma = 0.0;   // standard deviation of Gaussian noise on each coordinate of the centre, mm
  std::uint64_t seed = 1;
  // The switch triggers p(d) after the contact (pretravel.hpp): the machine reports centre + p(d)·d, d the unit
  // travel direction −normal. None by default: the reported centre is the touched one (plus noise).
  Pretravel pretravel{};
};

// The touch of each programmed point on the actual part (`actual`: its faces in the machine frame). The line's
// parameter solves dist(centre, part) = r by Newton: the derivative of the distance along the line is the cosine
// between the line and the direction from the foot point, both exact. Parallel; the noise is drawn in point order
// from `seed`, so the result does not depend on the thread count.
[[nodiscard]] std::vector<Touch> simulate_touches(const cad::ModelLocator& actual, std::span<const ProgrammedPoint> plan,
                                                  const MeasurementOptions& options);

// The actual part: each nominal face deformed along its outward normal (see deformed_surface), then moved by
// `placement` (CAD to machine). Faces keep their index, trim, material side and names.
[[nodiscard]] cad::Model actual_model(const cad::Model& nominal, const Deformation& deformation,
                                      const geometry::RigidTransform& placement);

}  // namespace probecomp::simulation
