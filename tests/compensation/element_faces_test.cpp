// Sparse touches on the planes, cylinders, cones and tori of real parts (NIST STC-06 and CTC-04, AP242), as a CMM
// measures a prismatic face: 12–20 points a face, too few for the face's NURBS net. Each such face is fitted as the
// element the file says it is, and its rows come back ok with the simulator's truth within ±2u.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <map>
#include <random>

#include "probecomp/cad/analytic.hpp"
#include "probecomp/cad/locator.hpp"
#include "probecomp/cad/model.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/simulation/measure.hpp"
#include "probecomp/studies/comparison.hpp"
#include "support/data_files.hpp"

namespace probecomp::compensation {
namespace {

// Up to `count` programmed points on the face, at random inside its trim and at least `margin` mm from its boundary,
// approached along its outward normal.
std::vector<simulation::ProgrammedPoint> sparse_plan(const cad::Face& face, int count, double margin, std::mt19937_64& rng) {
  const cad::TrimmedFaceLocator located(face);
  const nurbs::Domain d = face.surface.domain();
  std::uniform_real_distribution<double> a(0.0, 1.0);
  std::vector<simulation::ProgrammedPoint> out;
  for (int attempt = 0; attempt < 400 && static_cast<int>(out.size()) < count; ++attempt) {
    const double u = d.u0 + a(rng) * (d.u1 - d.u0), v = d.v0 + a(rng) * (d.v1 - d.v0);
    if (face.trimmed() && !face.trim->contains(u, v)) continue;
    const nurbs::SurfaceD1 e = nurbs::derivatives_d1(face.surface, u, v);
    const Vector3 n = e.Su.cross(e.Sv);
    if (!(n.norm() > 0.0)) continue;
    if (located.closest_point_on_boundary(e.S, margin).distance < margin) continue;
    out.push_back({e.S, face.outward * n.normalized(), face.index});
  }
  return out;
}

// Up to `faces` faces of each kind (in the model's order) whose sparse_plan of `points` holds at least 12 points.
struct KindQuota {
  cad::ElementaryKind kind;
  int faces = 0;
  int points = 0;
};
struct SparsePlan {
  std::vector<simulation::ProgrammedPoint> plan;
  std::vector<int> faces;              // cad::Face::index of each face planned
  std::map<cad::ElementaryKind, int> count;  // faces planned, by kind
};
SparsePlan plan_faces_of_kinds(const cad::Model& part, const std::vector<KindQuota>& quotas, double margin,
                               std::mt19937_64& rng) {
  SparsePlan out;
  for (const cad::Face& face : part.faces) {
    if (!face.analytic) continue;
    const cad::ElementaryKind kind = face.analytic->surface().kind;
    const auto q = std::find_if(quotas.begin(), quotas.end(), [&](const KindQuota& k) { return k.kind == kind; });
    if (q == quotas.end() || out.count[kind] >= q->faces) continue;
    const std::vector<simulation::ProgrammedPoint> p = sparse_plan(face, q->points, margin, rng);
    if (p.size() < 12) continue;
    out.plan.insert(out.plan.end(), p.begin(), p.end());
    out.faces.push_back(face.index);
    ++out.count[kind];
  }
  return out;
}

// The plan measured on the part placed 0.2, −0.1, 0.15 mm and `tilt` rad off, σ = 2 µm, and compensated (both methods).
studies::MethodComparison measure_sparse(const cad::Model& part, const std::vector<simulation::ProgrammedPoint>& plan,
                                         double tilt, double probe_radius, std::uint64_t seed) {
  const studies::SimulatedMeasurement m{
      .nominal = part,
      .deformation = {},
      .placement = geometry::RigidTransform(Eigen::Translation3d(0.2, -0.1, 0.15) *
                                            Eigen::AngleAxisd(tilt, Vector3(0.3, 1, 0.6).normalized())),
      .plan = plan,
      .probe_radius = probe_radius,
      .noise_sigma = 0.002,
      .seed = seed};
  return studies::compare_methods(m, {.approach_normals = true});
}

// The ok rows' errors against the simulator's truth: how many, rms, largest, mean u, how many within ±2u.
struct OkRows {
  int ok = 0, covered = 0;
  double ss = 0.0, worst = 0.0, u_sum = 0.0;
  void add(double error, double u) {
    ++ok;
    ss += error * error;
    worst = std::max(worst, std::abs(error));
    u_sum += u;
    covered += std::abs(error) <= 2.0 * u;
  }
  [[nodiscard]] double rms() const { return std::sqrt(ss / std::max(ok, 1)); }
  [[nodiscard]] double mean_u() const { return u_sum / std::max(ok, 1); }
};

TEST(ElementFaces, SparseTouchesOnPlanesAndCylindersAreFittedAsThoseAndOk) {
  const cad::Model part = cad::read_model(test::kCadDir / "nist_stc_06_asme1_ap242-e3.stp");
  // The largest plane and cylinder faces (by their NURBS's parameter area on the part: their extent), 12–20 points
  // each.
  std::mt19937_64 rng(31);
  SparsePlan planned = plan_faces_of_kinds(
      part, {{cad::ElementaryKind::Plane, 8, 16}, {cad::ElementaryKind::Cylinder, 6, 14}}, 3.0, rng);
  const std::vector<simulation::ProgrammedPoint>& plan = planned.plan;
  const int planes = planned.count[cad::ElementaryKind::Plane];
  const int cylinders = planned.count[cad::ElementaryKind::Cylinder];
  ASSERT_GE(planes, 6);
  ASSERT_GE(cylinders, 4);
  const studies::MethodComparison r = measure_sparse(part, plan, 0.008, 1.0, 41);
  int touched = 0, few = 0;
  OkRows rows;
  for (std::size_t k = 0; k < plan.size(); ++k) {
    if (r.touches[k].status != simulation::Touch::Status::OK) continue;
    ++touched;
    const CompensatedPoint& c = r.cad.points[k];
    few += c.status == PointStatus::FewPoints;
    if (c.status == PointStatus::Ok) rows.add(r.cad_error[k], c.uncertainty);
  }
  std::printf("%d planes, %d cylinders: %d touches, %d ok (%d few-points); error rms %.2f um, largest %.2f um; mean u %.2f "
              "um; within 2u %d\n",
              planes, cylinders, touched, rows.ok, few, rows.rms() * 1e3, rows.worst * 1e3, rows.mean_u() * 1e3,
              rows.covered);
  EXPECT_GE(rows.ok, 0.95 * touched);
  EXPECT_LT(rows.worst, 0.012);  // 6 σ of the noise
  EXPECT_GE(rows.covered, 0.9 * rows.ok);
  EXPECT_LT(rows.mean_u(), 0.005);  // honest: about the noise, not the 9–80 µm of the nominal's normal
}

// Cones (chamfers, countersinks, tapers) and tori (fillets) of CTC-04: 12–16 touches each with a 0.5 mm tip, which
// reaches into fillets of 0.5 mm and more. A cone or torus fit starts from the nominal's offset, holds there what its
// points fix too poorly and must stay near it (element_faces.hpp); its rows are ok, within their u of the truth.
TEST(ElementFaces, SparseTouchesOnConesAndToriAreFittedAsThoseAndOk) {
  const cad::Model part = cad::read_model(test::kCadDir / "nist_ctc_04_asme1_ap242-e1.stp");
  std::mt19937_64 rng(37);
  SparsePlan planned = plan_faces_of_kinds(
      part, {{cad::ElementaryKind::Cone, 8, 16}, {cad::ElementaryKind::Torus, 6, 16}}, 0.5, rng);
  const std::vector<simulation::ProgrammedPoint>& plan = planned.plan;
  const std::vector<int>& chosen = planned.faces;
  const int cones = planned.count[cad::ElementaryKind::Cone], tori = planned.count[cad::ElementaryKind::Torus];
  ASSERT_GE(cones, 6);
  ASSERT_GE(tori, 4);
  const studies::MethodComparison r = measure_sparse(part, plan, 0.004, 0.5, 43);
  int fitted_cones = 0, fitted_tori = 0;
  std::vector<int> fitted;
  for (const FaceReport& f : r.cad.faces) {
    if (std::find(chosen.begin(), chosen.end(), f.face) == chosen.end()) continue;
    std::printf("face %d (%d points): %s\n", f.face, f.points, f.stop_reason.c_str());
    if (!f.fitted_as) continue;
    fitted.push_back(f.face);
    fitted_cones += *f.fitted_as == cad::ElementaryKind::Cone;
    fitted_tori += *f.fitted_as == cad::ElementaryKind::Torus;
  }
  // On the fitted faces their touches ok (but for edges), within their u of the truth; on the others flagged.
  int touched = 0, elsewhere = 0, elsewhere_ok = 0;
  OkRows rows;
  for (std::size_t k = 0; k < plan.size(); ++k) {
    if (r.touches[k].status != simulation::Touch::Status::OK) continue;
    const CompensatedPoint& c = r.cad.points[k];
    if (std::find(fitted.begin(), fitted.end(), plan[k].face) == fitted.end()) {
      ++elsewhere;
      // Ok only where its correspondence put it on another face (a neighbour's), never on the face not fitted.
      elsewhere_ok += c.status == PointStatus::Ok && c.face == plan[k].face;
      continue;
    }
    ++touched;
    if (c.status == PointStatus::Ok) rows.add(r.cad_error[k], c.uncertainty);
  }
  std::printf("%d cones (%d fitted as such), %d tori (%d): %d touches on them, %d ok; error rms %.2f um, largest %.2f "
              "um; mean u %.2f um; within 2u %d; %d touches on the faces not fitted, %d ok on them\n",
              cones, fitted_cones, tori, fitted_tori, touched, rows.ok, rows.rms() * 1e3, rows.worst * 1e3,
              rows.mean_u() * 1e3, rows.covered, elsewhere, elsewhere_ok);
  // Measured: every cone and every torus, 207 of 222 touches ok. Three of the tori, on a short arc of their fillet
  // (8–16 points), fix their major radius and their centre's place together, not apart: fitted free they moved the
  // radius 0.2–0.26 mm or turned 3.3° and were refused; those combinations are now held at the nominal's.
  EXPECT_EQ(fitted_cones, cones);
  EXPECT_EQ(fitted_tori, tori);
  EXPECT_GE(rows.ok, 0.9 * touched);
  EXPECT_LT(rows.worst, 0.012);  // 6 σ of the noise
  EXPECT_GE(rows.covered, 0.9 * rows.ok);
  EXPECT_LT(rows.mean_u(), 0.005);
  EXPECT_EQ(elsewhere_ok, 0);
}

// The same probe measured every face: the rows on faces fitted as their elements take the noise pooled over them all
// (Σ rss / Σ (n − k), compensation/element_faces.hpp), not each face's own estimate from its 12–20 points (5–17
// degrees of freedom: a fifth off or more). A face whose points hold form error its element does not follow (here a
// ripple of 6 µm added to one plane's centres) is left out of the pool and keeps its own, larger, estimate.
TEST(ElementFaces, TheirNoiseIsPooledOverThemAndAFaceWithFormErrorKeepsItsOwn) {
  const cad::Model part = cad::read_model(test::kCadDir / "nist_stc_06_asme1_ap242-e3.stp");
  std::mt19937_64 rng(31);
  const SparsePlan planned = plan_faces_of_kinds(
      part, {{cad::ElementaryKind::Plane, 8, 16}, {cad::ElementaryKind::Cylinder, 6, 14}}, 3.0, rng);
  const int rippled = planned.faces.front();
  ASSERT_EQ(part.faces[static_cast<std::size_t>(rippled)].analytic->surface().kind, cad::ElementaryKind::Plane);
  constexpr double kSigma = 0.002, kRipple = 0.006;  // mm
  const geometry::RigidTransform placement(Eigen::Translation3d(0.2, -0.1, 0.15) *
                                           Eigen::AngleAxisd(0.008, Vector3(0.3, 1, 0.6).normalized()));
  const cad::Model placed = simulation::actual_model(part, {}, placement);
  std::vector<simulation::ProgrammedPoint> followed = planned.plan;
  for (simulation::ProgrammedPoint& p : followed) {
    p.point = placement * p.point;
    p.normal = placement.linear() * p.normal;
  }
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    const std::vector<simulation::Touch> touches = simulation::simulate_touches(
        cad::ModelLocator(placed), followed, {.probe_radius = 1.0, .noise_sigma = kSigma, .seed = seed});
    std::vector<Point3> centres;
    std::vector<Vector3> normals;
    for (std::size_t i = 0; i < touches.size(); ++i) {
      if (touches[i].status == simulation::Touch::Status::Missed) continue;
      Point3 c = touches[i].measured;
      // Form error across the plane: a ripple of 10 mm wavelength along its points' first coordinate.
      if (planned.plan[i].face == rippled) {
        c += kRipple * std::sin(2.0 * M_PI * planned.plan[i].point.x() / 10.0) * followed[i].normal;
      }
      centres.push_back(c);
      normals.push_back(followed[i].normal);
    }
    CompensateOptions options;
    options.probe_radius = 1.0;
    const CompensationResult result = compensate(part, centres, normals, options);
    std::vector<double> pooled;
    double own = 0.0;
    for (const FaceReport& f : result.faces) {
      if (!f.fitted_as) continue;
      if (f.face == rippled) {
        own = f.noise_sigma;
      } else {
        pooled.push_back(f.noise_sigma);
      }
    }
    ASSERT_GE(pooled.size(), 10u);
    const double shared = *std::min_element(pooled.begin(), pooled.end());
    const auto sharing = std::count(pooled.begin(), pooled.end(), shared);
    std::printf("seed %llu: %td of %zu faces share %.3f um (the largest %.3f); the rippled plane's own %.3f um\n",
                static_cast<unsigned long long>(seed), sharing, pooled.size(), shared * 1e3,
                *std::max_element(pooled.begin(), pooled.end()) * 1e3, own * 1e3);
    // One noise for every face consistent with it. The test leaves a face out on noise alone 1 time in 100 (here
    // seed 3 leaves one out, at 3.08 µm, and it keeps that larger estimate): one such face among 13 is allowed.
    EXPECT_GE(sharing, static_cast<std::ptrdiff_t>(pooled.size()) - 1);
    // About 200 degrees of freedom: σ within 5 % (one standard deviation); 15 % is three.
    EXPECT_NEAR(shared, kSigma, 0.15 * kSigma);
    // Its residuals hold the ripple's 6/√2 µm rms with the noise: about 4.7 µm.
    EXPECT_GT(own, 0.0035);
  }
}

}  // namespace
}  // namespace probecomp::compensation
