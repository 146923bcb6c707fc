// Writes the self-test's stored free-form case (src/selftest/freeform_case.csv) to standard output:
//   cmake --build build --target make_selftest_case && build/make_selftest_case > src/selftest/freeform_case.csv
// The paper's free-form case (simulation::paper_freeform_case: 0.2 mm and 1.5 deg misalignment, 1 mm tip, 4.5 um noise)
// with its broad bulge but not its narrow dent, measured on a 40 x 20 grid. Each row: the measured centre, the programmed (nominal) approach normal
// and the true contact point on the actual part with the actual part's outward normal there, from the simulator's
// exact touch. Run once; the file is the record.

#include <cstdio>
#include <cstdlib>

#include "probecomp/simulation/freeform_case.hpp"
#include "probecomp/simulation/measure.hpp"

int main(int argc, char** argv) {
  const int nu = argc > 2 ? std::atoi(argv[1]) : 40, nv = argc > 2 ? std::atoi(argv[2]) : 20;
  using namespace probecomp;
  simulation::FreeformCase c = simulation::paper_freeform_case();
  // The broad bulge only: the narrow dent (6 mm across) needs the paper's 120 x 60 grid to be resolved, 7 200 rows
  // to store; on 40 x 20 the fit cannot follow it and says so only through the points' uncertainty.
  c.deformation.bumps.resize(1);
  const cad::Model actual = simulation::actual_model(c.nominal, c.deformation, c.placement);
  const cad::ModelLocator locator(actual);
  const std::vector<simulation::ProgrammedPoint> plan = simulation::grid_plan(c.nominal.faces.front(), nu, nv);
  const std::vector<simulation::Touch> touches = simulation::simulate_touches(
      locator, plan, {.probe_radius = c.probe_radius, .noise_sigma = c.noise_sigma, .seed = 2026});
  std::printf("# probecomp selftest's stored case: the paper's free-form panel (simulation::paper_freeform_case) with its\n"
              "# bulge, not its dent; 40 x 20 grid, 1 mm tip, 4.5 um noise (seed 2026); made by src/selftest/make_case.cpp.\n"
              "# mm, machine frame.\n"
              "x,y,z,i,j,k,contact_x,contact_y,contact_z,normal_x,normal_y,normal_z\n");
  for (std::size_t k = 0; k < touches.size(); ++k) {
    const simulation::Touch& t = touches[k];
    if (t.status != simulation::Touch::Status::OK) continue;
    const Vector3& n = plan[k].normal;
    std::printf("%.10f,%.10f,%.10f,%.12f,%.12f,%.12f,%.10f,%.10f,%.10f,%.12f,%.12f,%.12f\n", t.measured.x(), t.measured.y(),
                t.measured.z(), n.x(), n.y(), n.z(), t.contact.x(), t.contact.y(), t.contact.z(), t.normal.x(), t.normal.y(),
                t.normal.z());
  }
  return 0;
}
