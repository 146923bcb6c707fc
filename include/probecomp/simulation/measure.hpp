#pragma once
// A simulated CMM measurement as the paper makes it (§7; DESIGN.md §3 and §8): the machine is programmed with
// nominal points and their outward normals; the probe comes from outside along each normal line towards the part
// and stops where its tip sphere first meets the actual (misaligned, deformed) part, whichever face that is; the
// switch's pre-travel and noise are then added to that centre.

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
    OK,        // the tip touched the inside of a face
    Edge,      // the tip touched a face's edge: the contact is on the boundary, not where the normal says
    Missed,    // no touch: the part is not within the search distance along the line, or the line is blocked:
               // no clear place to start from near the approach point (see simulate_touches)
    TwoFaces,  // the tip sits against two faces at once, at two distinct points (a concave corner, or a fillet
               // tighter than the tip, which it never touches): `contact` is on one, `other_contact` on the other
  };
  Status status = Status::Missed;
  Point3 centre = Point3::Zero();    // the probe centre at the first contact, exact
  Point3 measured = Point3::Zero();  // what the machine reports: centre + pre-travel + noise
  Point3 contact = Point3::Zero();   // the touched point of the actual part
  Vector3 normal = Vector3::Zero();  // the actual part's outward unit normal there
  int face = -1;
  double u = 0.0, v = 0.0;           // on the actual face
  double travel = 0.0;               // centre = programmed point + travel · normal, mm
  int other_face = -1;               // TwoFaces: the second face touched, and where
  Point3 other_contact = Point3::Zero();
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
  // The switch triggers p(d) after the first contact (pretravel.hpp): the machine reports centre + p(d)·d, d the
  // unit travel direction −normal. None by default: the reported centre is the touched one (plus noise).
  Pretravel pretravel{};
};

// The touch of each programmed point on the actual part (`actual`: its faces in the machine frame). The probe
// starts at the approach point, programmed point + (r + 2 mm)·normal, and travels along −normal until its tip
// sphere first meets any face of the part: sphere tracing on the distance to the whole part (1-Lipschitz, so a
// step of distance − r never jumps a face), with Newton steps on the nearest face where no other face is within
// reach, then a bracketed refinement to 1e-9 mm. The touch is the first contact along the travel, not merely a
// root of dist = r: in a concave corner the tip stops against whichever face it meets first, or against two
// (TwoFaces), never a fillet tighter than the tip. It searches 10 mm past the nominal touch, or down to where the
// line meets the part offset by r nearest the nominal touch (Newton from there, the paper's simulated touch) when
// that is farther, so that a grossly misplaced part is still measured.
// Where the tip overlaps the part at the approach point, the approach point moves along the line to the nearest
// clear place: out when what it overlaps is the programmed face (a part placed nearer than planned; any face when
// `face` is −1), in when it is another face (a space narrower than the clearance), no nearer than the nominal
// touch and not into the programmed face. A line with no such place is blocked, as a real probe's would be: Missed.
// A face of a model with no solid (its material side unknown) counts its distance unsigned, and a tip against its
// back (inside the part as the file orients it) is Missed too.
// `centre` and `contact` are exact; `measured` = centre + p(d)·d + noise. Parallel; the noise is drawn in point
// order from `seed` (for every point, touched or not), so the result does not depend on the thread count.
[[nodiscard]] std::vector<Touch> simulate_touches(const cad::ModelLocator& actual, std::span<const ProgrammedPoint> plan,
                                                  const MeasurementOptions& options);

// The actual part: each nominal face deformed along its outward normal (see deformed_surface), then moved by
// `placement` (CAD to machine). Faces keep their index, trim, material side and names.
[[nodiscard]] cad::Model actual_model(const cad::Model& nominal, const Deformation& deformation,
                                      const geometry::RigidTransform& placement);

}  // namespace probecomp::simulation
