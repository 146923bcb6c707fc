#include "probecomp/studies/registration_study.hpp"

#include <cmath>
#include <random>

#include "probecomp/cad/offset_model.hpp"
#include "probecomp/compensation/conventional.hpp"
#include "probecomp/nurbs/constructors.hpp"
#include "probecomp/registration/routes.hpp"
#include "probecomp/simulation/random.hpp"

namespace probecomp::studies {

cad::Model cube_corner_model(double size) {
  cad::Model model;
  model.path = "cube-corner";
  model.file_units = "mm";
  // S_u × S_v = a × b is the outward normal (out of the cube) on each face.
  const std::array<std::pair<Vector3, Vector3>, 3> sides = {{
      {Vector3(0, 0, size), Vector3(0, size, 0)},  // x = 0: z × y = −x
      {Vector3(size, 0, 0), Vector3(0, 0, size)},  // y = 0: x × z = −y
      {Vector3(0, size, 0), Vector3(size, 0, 0)},  // z = 0: y × x = −z
  }};
  for (int k = 0; k < 3; ++k) {
    model.faces.push_back(cad::Face{
        .index = k,
        .name = std::string("corner ") + "xyz"[k] + "=0",
        .source_type = "plane",
        .surface = nurbs::make_plane_patch(Point3::Zero(), sides[static_cast<std::size_t>(k)].first,
                                           sides[static_cast<std::size_t>(k)].second),
        .trim = nullptr,
        .outward = 1,
        .material_known = true,
        .exact = true,
    });
  }
  return model;
}

namespace {

// Two-sided 97.5 % quantile of Student's t with ν degrees of freedom: the Cornish–Fisher expansion about the
// normal quantile (Abramowitz and Stegun 26.7.5), good to 1e-3 for ν ≥ 3.
double t975(int nu) {
  const double z = 1.959963984540054;
  const double z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z;
  const double n = nu;
  return z + (z3 + z) / (4 * n) + (5 * z5 + 16 * z3 + 3 * z) / (96 * n * n) +
         (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * n * n * n);
}

PoseError pose_error(const geometry::RigidTransform& estimated, const geometry::RigidTransform& truth) {
  const geometry::Pose e = geometry::to_pose(estimated);
  const geometry::Pose t = geometry::to_pose(truth);
  return {e.rx - t.rx, e.ry - t.ry, e.rz - t.rz, e.t.x() - t.t.x(), e.t.y() - t.t.y(), e.t.z() - t.t.z()};
}

}  // namespace

ErrorStatistics error_statistics(const std::vector<PoseError>& errors) {
  ErrorStatistics s;
  const double n = static_cast<double>(errors.size());
  if (errors.empty()) return s;
  for (std::size_t c = 0; c < 6; ++c) {
    double sum = 0.0;
    for (const PoseError& e : errors) sum += e[c];
    const double mean = sum / n;
    double ss = 0.0;
    for (const PoseError& e : errors) ss += (e[c] - mean) * (e[c] - mean);
    s.mean[c] = mean;
    s.std[c] = errors.size() > 1 ? std::sqrt(ss / (n - 1.0)) : 0.0;
    s.ci95[c] = errors.size() > 1 ? t975(static_cast<int>(errors.size()) - 1) * s.std[c] / std::sqrt(n) : 0.0;
  }
  return s;
}

RegistrationStudyResult run_registration_study(const RegistrationStudyOptions& options) {
  const cad::Model nominal = cube_corner_model();
  const cad::OffsetModel offset = cad::offset_model(nominal, options.probe_radius);

  // Nominal points and normals: cell centres of a grid per face, as close to square cells as the count allows.
  std::vector<Point3> points;
  std::vector<Vector3> normals;
  const int per_face = std::max(options.points_per_face, 1);
  int nu = static_cast<int>(std::lround(std::sqrt(per_face * 4.0 / 3.0)));  // 20 × 15 for 300
  nu = std::max(nu, 1);
  const int nv = std::max((per_face + nu - 1) / nu, 1);
  for (const cad::Face& f : nominal.faces) {
    for (int i = 0; i < nu; ++i) {
      for (int j = 0; j < nv; ++j) {
        const double u = (i + 0.5) / nu, v = (j + 0.5) / nv;
        points.push_back(nurbs::evaluate(f.surface, u, v));
        normals.push_back(static_cast<double>(f.outward) * nurbs::unit_normal(f.surface, u, v).n);
      }
    }
  }

  RegistrationStudyResult result;
  result.points = static_cast<int>(points.size());
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (int trial = 0; trial < options.trials; ++trial) {
    geometry::Pose misalignment;
    misalignment.rx = options.max_rotation * unit(rng);
    misalignment.ry = options.max_rotation * unit(rng);
    misalignment.rz = options.max_rotation * unit(rng);
    misalignment.t = simulation::draw_vector(unit, rng) * options.max_translation;
    const geometry::RigidTransform M = geometry::from_pose(misalignment);
    std::vector<Point3> raw(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      raw[i] = M * (points[i] + options.probe_radius * normals[i]);
      if (options.noise > 0.0) raw[i] += options.noise * simulation::draw_vector(gauss, rng);
    }
    registration::RegistrationOptions reg = options.registration;
    reg.initial = geometry::RigidTransform::Identity();
    const registration::RegistrationResult p = registration::register_to_offset_model(offset, raw, reg);
    // The approach normals are the unperturbed model's: the CMM was programmed from the nominal.
    const registration::RegistrationResult c =
        compensation::register_conventional(nominal, raw, normals, options.probe_radius, reg);
    for (auto [route, r] : {std::pair{&result.proposed, &p}, std::pair{&result.conventional, &c}}) {
      route->errors.push_back(pose_error(r->transform, M));
      route->converged += r->converged();
      route->max_iterations = std::max(route->max_iterations, r->iterations);
    }
  }
  result.proposed.stats = error_statistics(result.proposed.errors);
  result.conventional.stats = error_statistics(result.conventional.errors);
  return result;
}

PaperTable1 paper_table1() {
  PaperTable1 t;
  t.proposed.std = {0.0014, 0.0004, 0.0020, 0.0084, 0.0095, 0.0121};
  t.conventional.std = {0.1783, 0.0820, 0.0676, 0.0167, 0.0239, 0.0166};
  t.proposed.mean = {0.0001, 0.0001, 0.0006, 0.0037, 0.0006, 0.0032};
  t.conventional.mean = {0.0153, 0.0268, 0.0152, 0.0100, 0.0220, 0.0193};
  t.proposed.ci95 = {0.0009, 0.0003, 0.0012, 0.0052, 0.0059, 0.0075};
  t.conventional.ci95 = {0.1105, 0.0508, 0.0419, 0.0103, 0.0148, 0.0103};
  return t;
}

}  // namespace probecomp::studies
