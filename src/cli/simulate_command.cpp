// probecomp simulate: a CMM measurement of a part as the paper simulates it (§7; simulation/measure.hpp), so that
// users can try the method on their own parts: raw.csv to feed `compensate`, truth.csv to score it, the actual
// surfaces as IGES.

#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/model.hpp"
#include "probecomp/cad/plan.hpp"
#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "probecomp/io/format.hpp"
#include "probecomp/io/dmis.hpp"
#include "probecomp/io/output_files.hpp"
#include "probecomp/io/point_files.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/simulation/measure.hpp"

namespace probecomp::cli {

const char* const kDeformHelp =
    "Shape deviation of the actual part along the nominal outward normal (repeatable; they add up):\n"
    "  bump:X,Y,Z,A,W  Gaussian A*exp(-|x-c|^2/(2W^2)) about c = (X,Y,Z): amplitude A mm (negative: a dent), width W mm\n"
    "  sine:A,L,DX,DY,DZ[,OX,OY,OZ[,W[,PHASE[,BX,BY,BZ]]]]  A*sin(2*pi*d.(x-o)/L + PHASE deg) along the direction d = (DX,DY,DZ),\n"
    "      origin o (default 0,0,0), under a Gaussian window of width W mm about o when W > 0 (a local wave); with\n"
    "      B = (BX,BY,BZ) the window is over the distance along B only (a band of waves across B)\n"
    "  crease:OX,OY,OZ,DX,DY,DZ,H,W  a smoothed step H*(1+tanh(2*d.(x-o)/W))/2 of height H mm rising over W mm\n"
    "      across the plane through o normal to d\n"
    "  twist:OX,OY,OZ,D1X,D1Y,D1Z,D2X,D2Y,D2Z,A,L  A*(d1.(x-o))*(d2.(x-o))/L^2: a twist (d1 normal to d2), a saddle\n"
    "      when turned 45 degrees\n"
    "Positions in the CAD frame, mm.";

namespace {

std::vector<simulation::ProgrammedPoint> programmed_points(const SimulateArgs& a, const cad::Model& model) {
  std::vector<simulation::ProgrammedPoint> plan;
  if (!a.plan.empty()) {
    const io::PointTable t = io::read_points(a.plan);
    if (!t.normals) {
      throw std::invalid_argument(a.plan + ": a plan needs i,j,k (the outward normal the probe approaches along)");
    }
    int face_column = -1;
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
      if (t.columns[c] == "face") face_column = static_cast<int>(c);
    }
    for (std::size_t k = 0; k < t.points.size(); ++k) {
      const Vector3& n = (*t.normals)[k];
      if (!(n.norm() > 0.5 && n.norm() < 1.5)) {
        throw std::invalid_argument(a.plan + ":" + std::to_string(t.line[k]) + ": i,j,k is not a unit vector");
      }
      int face = -1;
      if (face_column >= 0) {
        try {
          face = std::stoi(std::string(t.rows[k][static_cast<std::size_t>(face_column)]));
        } catch (const std::logic_error&) {
          face = -1;
        }
      }
      plan.push_back({t.points[k], n.normalized(), face});
    }
    return plan;
  }
  if (!(a.spacing > 0.0)) throw std::invalid_argument("--spacing must be a positive number of mm");
  for (const cad::PlannedPoint& p : cad::plan_points(model, a.spacing, parse_face_list(a.faces))) {
    plan.push_back({p.point, p.normal, p.face});
  }
  if (plan.empty()) throw std::invalid_argument("no points fit on the chosen faces at spacing " + fmt("%g", a.spacing) + " mm");
  return plan;
}

std::string truth_csv(const std::vector<simulation::Touch>& touches) {
  std::ostringstream out;
  out << "point,status,x,y,z,nx,ny,nz,cx,cy,cz,face,u,v,travel\n";
  for (std::size_t k = 0; k < touches.size(); ++k) {
    const simulation::Touch& t = touches[k];
    out << k + 1 << ',' << simulation::to_string(t.status);
    if (t.status == simulation::Touch::Status::Missed) {
      out << ",,,,,,,,,,,,,\n";
      continue;
    }
    out << ',' << mm(t.contact.x()) << ',' << mm(t.contact.y()) << ',' << mm(t.contact.z()) << ',' << unit(t.normal.x())
        << ',' << unit(t.normal.y()) << ',' << unit(t.normal.z()) << ',' << mm(t.centre.x()) << ',' << mm(t.centre.y())
        << ',' << mm(t.centre.z()) << ',' << t.face << ',' << unit(t.u) << ',' << unit(t.v) << ',' << mm(t.travel)
        << '\n';
  }
  return out.str();
}

}  // namespace

std::string raw_points_csv(const std::vector<simulation::Touch>& touches,
                           const std::vector<simulation::ProgrammedPoint>& plan, bool numbered) {
  std::ostringstream out;
  out << "x,y,z,i,j,k" << (numbered ? ",point" : "") << '\n';
  for (std::size_t k = 0; k < touches.size(); ++k) {
    if (touches[k].status == simulation::Touch::Status::Missed) continue;
    const Point3& x = touches[k].measured;
    const Vector3& n = plan[k].normal;
    out << mm(x.x()) << ',' << mm(x.y()) << ',' << mm(x.z()) << ',' << unit(n.x()) << ',' << unit(n.y()) << ','
        << unit(n.z());
    if (numbered) out << ',' << k + 1;
    out << '\n';
  }
  return out.str();
}

int run_simulate(const SimulateArgs& a) {
  check_probe_radius(a.probe_radius);
  if (!(a.noise >= 0.0)) throw std::invalid_argument("--noise must be a non-negative number of mm");
  simulation::Deformation deformation;
  for (const std::string& spec : a.deform) add_deformation(spec, deformation);
  const geometry::RigidTransform placement =
      a.misalign.empty() ? geometry::RigidTransform::Identity() : parse_misalignment(a.misalign);
  const simulation::Pretravel pretravel = a.pretravel.empty() ? simulation::Pretravel{} : parse_pretravel(a.pretravel);
  {
    const std::filesystem::path dir(a.output_dir);
    io::check_outputs_spare_inputs(
        {{"--output-dir's actual.igs", dir / "actual.igs"}, {"--output-dir's truth.csv", dir / "truth.csv"},
         {"--output-dir's raw.csv", dir / "raw.csv"}},
        {{"--cad", a.cad}, {"--plan", a.plan}});
  }
  const cad::Model nominal = read_part(a.cad);
  const std::vector<simulation::ProgrammedPoint> plan = programmed_points(a, nominal);

  const cad::Model actual = simulation::actual_model(nominal, deformation, placement);
  const cad::ModelLocator locator(actual);
  const std::vector<simulation::Touch> touches =
      simulation::simulate_touches(locator, plan, {.probe_radius = a.probe_radius, .noise_sigma = a.noise, .seed = a.seed,
                                                   .pretravel = pretravel});
  int touched = 0, edge = 0, two_faces = 0;
  for (const simulation::Touch& t : touches) {
    touched += t.status != simulation::Touch::Status::Missed;
    edge += t.status == simulation::Touch::Status::Edge;
    two_faces += t.status == simulation::Touch::Status::TwoFaces;
  }
  if (touched == 0) throw std::invalid_argument("no programmed point touches the actual part (misalignment too large?)");

  // All three files or none (io/output_files.hpp).
  const std::filesystem::path dir(a.output_dir);
  std::filesystem::create_directories(dir);
  std::vector<nurbs::Surface> surfaces;
  for (const cad::Face& f : actual.faces) surfaces.push_back(f.surface);
  io::OutputFiles files;
  files.add(dir / "actual.igs", [&](const std::filesystem::path& temporary) { cad::write_surfaces(temporary, surfaces); });
  files.add(dir / "truth.csv", truth_csv(touches));
  files.add(dir / "raw.csv", raw_points_csv(touches, plan, true));
  files.commit();
  std::cout << "probecomp simulate: " << plan.size() << " programmed points, " << touched << " touched (" << edge
            << " on a face edge, " << two_faces << " against two faces), " << plan.size() - static_cast<std::size_t>(touched)
            << " missed; probe radius " << a.probe_radius << " mm, noise sigma " << a.noise << " mm, seed " << a.seed
            << (pretravel.none() ? std::string() : std::string("; pre-travel ").append(a.pretravel).append(" mm"))
            << ".\n"
            << "Wrote " << (dir / "raw.csv").string() << " (x,y,z,i,j,k,point), truth.csv (contact, actual normal, "
            << "exact centre per point) and actual.igs (" << surfaces.size() << " untrimmed NURBS faces).\n";
  return 0;
}

}  // namespace probecomp::cli
