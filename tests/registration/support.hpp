#pragma once
// Models and point sets for the registration tests.

#include <cmath>
#include <random>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/geometry/rigid.hpp"

namespace probecomp::testing {

inline cad::Model single_face_model(nurbs::Surface s, int outward = 1, bool material_known = true) {
  cad::Model m;
  m.path = "in-memory";
  m.file_units = "mm";
  m.faces.push_back(cad::Face{.index = 0, .name = "", .source_type = "bspline", .surface = std::move(s), .trim = nullptr,
                              .outward = outward, .material_known = material_known, .exact = true});
  return m;
}

struct Probed {
  std::vector<Point3> contacts, centres;  // machine frame
  std::vector<Vector3> approach;          // the nominal outward normals the CMM was programmed with
};

// An n × n grid of probe centres a radius r off the surface on the side `side` (+1: along S_u × S_v), over
// (u, v) in [0.05, 0.95]², all moved by `placement` (CAD to machine).
inline Probed probe(const geometry::RigidTransform& placement, const nurbs::Surface& s, double r, int side, int n) {
  Probed p;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double u = 0.05 + 0.9 * i / (n - 1.0), v = 0.05 + 0.9 * j / (n - 1.0);
      const Vector3 out = side * nurbs::unit_normal(s, u, v).n;
      const Point3 c = nurbs::evaluate(s, u, v);
      p.contacts.push_back(placement * c);
      p.centres.push_back(placement * (c + r * out));
      p.approach.push_back(out);
    }
  }
  return p;
}

// n points S(u,v) with (u,v) uniform in [margin, 1 − margin]², and their (u,v).
inline std::vector<Point3> points_on(const nurbs::Surface& s, int n, double margin, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> t(margin, 1.0 - margin);
  std::vector<Point3> out;
  for (int k = 0; k < n; ++k) {
    const double u = t(rng), v = t(rng);
    out.push_back(nurbs::evaluate(s, u, v));
  }
  return out;
}

inline std::vector<Point3> moved(const geometry::RigidTransform& T, const std::vector<Point3>& points) {
  std::vector<Point3> out;
  for (const Point3& p : points) out.push_back(T * p);
  return out;
}

// The largest distance between where `estimated` and `truth` put the points, mm.
inline double largest_disagreement(const geometry::RigidTransform& estimated, const geometry::RigidTransform& truth,
                                   const std::vector<Point3>& points) {
  double worst = 0.0;
  for (const Point3& p : points) worst = std::max(worst, (estimated * p - truth * p).norm());
  return worst;
}

// The angle of the rotation between the two transforms, degrees.
inline double rotation_disagreement_deg(const geometry::RigidTransform& estimated,
                                        const geometry::RigidTransform& truth) {
  return Eigen::AngleAxisd(estimated.rotation().transpose() * truth.rotation()).angle() * 180.0 / M_PI;
}

}  // namespace probecomp::testing
