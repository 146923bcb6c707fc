// Stylus qualification on a reference sphere against the touches' own truth: spheres touched in closed form by a tip
// whose pre-travel is the simulator's (simulation::Pretravel, not a sum of spherical harmonics), with and without
// noise, over seeds.
#include "probecomp/probe/qualification.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>

#include <Eigen/Dense>

#include "probecomp/error.hpp"
#include "probecomp/probe/qualification_file.hpp"
#include "probecomp/simulation/pretravel.hpp"
#include "probecomp/simulation/reference_sphere.hpp"
#include "support/light.hpp"

namespace probecomp::probe {
namespace {

constexpr double kSphereDiameter = 25.0;  // a usual reference sphere, mm
constexpr double kTip = 1.0;
const Point3 kSphereCentre(312.5, -40.25, 118.0);

using simulation::lobing_probe;  // the issue's probe
using simulation::SphereTouches;  // the simulator's closed-form touches of a reference sphere
using simulation::sphere_cap_normals;
using simulation::touch_reference_sphere;

// The model's error as a part sees it, over travel directions from vertical to horizontal: the model's radius less
// `truth`, less the best-fitting degree-1 part of that difference (a·n for every direction: one translation of every
// point, which the fit cannot tell from the sphere's centre and registration takes). rms, worst, and the fraction of
// directions whose error is within twice the model's u.
struct SeenError {
  double rms = 0.0, worst = 0.0, within_2u = 0.0;
};
SeenError seen_error(const StylusQualification& q, const std::function<double(const Vector3&)>& truth) {
  const std::vector<Vector3> normals = sphere_cap_normals(400, 0.0, 7.0);
  Eigen::MatrixXd a(normals.size(), 3);
  Eigen::VectorXd e(normals.size()), u(normals.size());
  for (std::size_t i = 0; i < normals.size(); ++i) {
    const EffectiveRadius r = effective_radius(q, -normals[i]);
    EXPECT_FALSE(r.unsupported);
    e(static_cast<Eigen::Index>(i)) = r.radius - truth(-normals[i]);
    u(static_cast<Eigen::Index>(i)) = r.uncertainty;
    a.row(static_cast<Eigen::Index>(i)) = normals[i].transpose();
  }
  const Eigen::VectorXd rest = e - a * Eigen::Vector3d(a.colPivHouseholderQr().solve(e));
  SeenError out;
  out.rms = std::sqrt(rest.squaredNorm() / static_cast<double>(rest.size()));
  out.worst = rest.cwiseAbs().maxCoeff();
  out.within_2u = (rest.cwiseAbs().array() <= 2.0 * u.array()).cast<double>().mean();
  return out;
}

// 120 touches from the top to 10° below the equator: a qualification that maps a probe's lobing.
std::vector<Vector3> mapping_normals() { return sphere_cap_normals(120, 10.0); }

TEST(Qualification, AnIdealProbeGivesTheSphereAndItsRadiusExactly) {
  const SphereTouches t = touch_reference_sphere(kSphereCentre, kSphereDiameter / 2, kTip, mapping_normals(),
                                                 [](const Vector3&) { return 0.0; }, 0.0, 1);
  const StylusQualification q = qualify_stylus("T1", t.centres, t.normals, kSphereDiameter);
  ASSERT_EQ(q.status, QualificationStatus::OK) << q.reason;
  EXPECT_LT((q.sphere_centre - kSphereCentre).norm(), 1e-10);
  EXPECT_NEAR(q.effective_radius, kTip, 1e-11);
  EXPECT_LT(q.form_error, 1e-10);
  EXPECT_EQ(q.model.degree(), 0);
  EXPECT_NEAR(q.model.radius(Vector3(0.3, 0.1, -1)), kTip, 1e-11);
}

TEST(Qualification, AnEffectiveRadiusOfDegreeOneIsTheSpheresCentre) {
  // p(d) = b·(d·e) of degree 1: to first order the sphere moved by b·e, its radius unchanged.
  const Vector3 e = Vector3(0.2, -0.3, 0.93).normalized();
  const double b = 0.004;
  const SphereTouches t = touch_reference_sphere(kSphereCentre, kSphereDiameter / 2, kTip, mapping_normals(),
                                                 [&](const Vector3& d) { return b * d.dot(e); }, 0.0, 1);
  const StylusQualification q = qualify_stylus("T1", t.centres, t.normals, kSphereDiameter);
  ASSERT_EQ(q.status, QualificationStatus::OK) << q.reason;
  // centre + (R + r + b n·e) n = (centre + b e) + (R + r) n − b (e − (n·e) n): to first order in b/R the sphere
  // about centre + b e; the tangential part is second order (b²/R = 1.3e-6 mm at most).
  EXPECT_LT((q.sphere_centre - (kSphereCentre + b * e)).norm(), 2e-6);
  EXPECT_NEAR(q.effective_radius, kTip, 2e-6);
  EXPECT_LT(q.model.variation(), 1e-6);
}

TEST(Qualification, ALobingProbeIsModelledWhereItWasTouched) {
  const simulation::Pretravel probe = lobing_probe();
  const SphereTouches t = touch_reference_sphere(kSphereCentre, kSphereDiameter / 2, kTip, mapping_normals(),
                                                 probe, 0.0, 1);
  const StylusQualification q = qualify_stylus("T1", t.centres, t.normals, kSphereDiameter);
  ASSERT_EQ(q.status, QualificationStatus::OK) << q.reason;
  EXPECT_GE(q.model.degree(), 3);
  // The truth r − p(d) is not a finite sum of harmonics (simulation/pretravel.hpp): measured 0.04 µm rms, 0.14 worst.
  const SeenError e = seen_error(q, [&](const Vector3& d) { return kTip - probe(d); });
  std::printf("lobing probe, noise-free touches: degree %d, log10 smoothing %.1f, error rms %.3f um, worst %.3f um\n",
              q.model.degree(), q.model.log10_smoothing, 1e3 * e.rms, 1e3 * e.worst);
  EXPECT_LT(e.rms, 0.1e-3);
  EXPECT_LT(e.worst, 0.3e-3);
}

TEST(Qualification, WithNoiseTheRadiusAndItsModelHoldOverSeeds) {
  const simulation::Pretravel probe = lobing_probe();
  const SphereTouches exact =
      touch_reference_sphere(kSphereCentre, kSphereDiameter / 2, kTip, mapping_normals(), probe, 0.0, 1);
  const StylusQualification truth = qualify_stylus("T1", exact.centres, exact.normals, kSphereDiameter);
  ASSERT_EQ(truth.status, QualificationStatus::OK);
  double worst_radius = 0.0, worst_model = 0.0, sum_rms = 0.0, lowest_within = 1.0;
  int seeds = 0;
  for (std::uint64_t seed : test::cases<std::uint64_t>({1, 2, 3, 4, 5, 6, 7, 8})) {
    const SphereTouches t =
        touch_reference_sphere(kSphereCentre, kSphereDiameter / 2, kTip, mapping_normals(), probe, 0.0003, seed);
    const StylusQualification q = qualify_stylus("T1", t.centres, t.normals, kSphereDiameter);
    ASSERT_EQ(q.status, QualificationStatus::OK);
    // The issue's bar: the effective radius within 0.5 µm of the noise-free touches' sphere fit.
    worst_radius = std::max(worst_radius, std::abs(q.effective_radius - truth.effective_radius));
    const SeenError e = seen_error(q, [&](const Vector3& d) { return kTip - probe(d); });
    worst_model = std::max(worst_model, e.worst);
    lowest_within = std::min(lowest_within, e.within_2u);
    sum_rms += e.rms * e.rms;
    ++seeds;
    std::printf("seed %d: degree %d, radius %+.3f um from the noise-free fit (u %.3f), model error rms %.3f um, worst "
                "%.3f um, within 2u %.1f %%\n",
                static_cast<int>(seed), q.model.degree(), 1e3 * (q.effective_radius - truth.effective_radius),
                1e3 * q.effective_radius_u, 1e3 * e.rms, 1e3 * e.worst, 100 * e.within_2u);
  }
  // Measured over the 8 seeds: radius within 0.06 µm; model error rms 0.15 µm, worst 0.53 µm; all within 2u.
  EXPECT_LT(worst_radius, 0.5e-3);
  EXPECT_LT(std::sqrt(sum_rms / seeds), 0.25e-3);
  EXPECT_LT(worst_model, 0.8e-3);
  EXPECT_GT(lowest_within, 0.9);
}

TEST(Qualification, DirectionsNeverTouchedAreNotExtrapolated) {
  const SphereTouches t = touch_reference_sphere(kSphereCentre, kSphereDiameter / 2, kTip, mapping_normals(),
                                                 lobing_probe(), 0.0, 1);
  const StylusQualification q = qualify_stylus("T1", t.centres, t.normals, kSphereDiameter);
  ASSERT_EQ(q.status, QualificationStatus::OK);
  const EffectiveRadius from_below = effective_radius(q, Vector3(0, 0, 1));  // travelling up: a touch from below
  EXPECT_TRUE(from_below.unsupported);
  EXPECT_DOUBLE_EQ(from_below.radius, q.effective_radius);
  EXPECT_GE(from_below.uncertainty, q.model.variation());
  EXPECT_FALSE(effective_radius(q, Vector3(0, 0, -1)).unsupported);
}

TEST(Qualification, TooFewTouchesAreSaidSo) {
  const SphereTouches t = touch_reference_sphere(kSphereCentre, kSphereDiameter / 2, kTip, sphere_cap_normals(4, -20.0),
                                                 [](const Vector3&) { return 0.0; }, 0.0, 1);
  const StylusQualification q = qualify_stylus("T2", t.centres, t.normals, kSphereDiameter);
  EXPECT_EQ(q.status, QualificationStatus::TooFewTouches);
  EXPECT_NE(q.reason.find("4 touches"), std::string::npos) << q.reason;
}

TEST(Qualification, WithoutNormalsTheDirectionsComeFromTheSphere) {
  const SphereTouches t = touch_reference_sphere(kSphereCentre, kSphereDiameter / 2, kTip, mapping_normals(),
                                                 lobing_probe(), 0.0, 1);
  const StylusQualification with = qualify_stylus("T1", t.centres, t.normals, kSphereDiameter);
  const StylusQualification without = qualify_stylus("T1", t.centres, {}, kSphereDiameter);
  ASSERT_EQ(without.status, QualificationStatus::OK);
  EXPECT_NEAR(without.effective_radius, with.effective_radius, 1e-9);
  // Radial directions from the fitted centre differ from the programmed normals by the pre-travel over R: µrad.
  const SeenError e = seen_error(without, [&](const Vector3& d) { return effective_radius(with, d).radius; });
  EXPECT_LT(e.worst, 0.05e-3);
}

TEST(QualificationFile, ReadsBackWhatItWrites) {
  const SphereTouches t = touch_reference_sphere(kSphereCentre, kSphereDiameter / 2, kTip, mapping_normals(),
                                                 lobing_probe(), 0.0003, 5);
  Qualification q;
  q.styli.push_back(qualify_stylus("T1", t.centres, t.normals, kSphereDiameter));
  q.styli.push_back(qualify_stylus("T2", std::span(t.centres).first(3), std::span(t.normals).first(3), kSphereDiameter));
  const Qualification back = qualification_from_json(io::json_text(to_json(q)), "q.json");
  ASSERT_EQ(back.styli.size(), 2u);
  const StylusQualification* t1 = back.find("T1");
  ASSERT_NE(t1, nullptr);
  EXPECT_EQ(back.find("T2")->status, QualificationStatus::TooFewTouches);
  EXPECT_EQ(back.find("T3"), nullptr);
  for (const Vector3& n : sphere_cap_normals(30, 0.0, 5.0)) {
    const EffectiveRadius a = effective_radius(q.styli[0], -n), b = effective_radius(*t1, -n);
    EXPECT_NEAR(a.radius, b.radius, 1e-11);
    EXPECT_NEAR(a.uncertainty, b.uncertainty, 1e-9);
  }
}

TEST(QualificationFile, BadFilesNameTheirFault) {
  const auto message = [](const std::string& text) {
    try {
      (void)qualification_from_json(text, "q.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("{").find("q.json: not JSON"), std::string::npos);
  EXPECT_NE(message("{\"styli\": []}").find("not a qualification"), std::string::npos);
  EXPECT_NE(message(R"({"format": "probecomp qualification 1", "units": "mm", "sphere_diameter": 25, "styli": [{"stylus": "T1", "status": "ok", "touches": 9}]})")
                .find("stylus T1: has no \"effective_radius\""),
            std::string::npos);
}

}  // namespace
}  // namespace probecomp::probe
