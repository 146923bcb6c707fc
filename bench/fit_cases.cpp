// Accuracy of the CAD method on the free-form case and its variants, over noise seeds: a command that prints its
// own figures (issue 19's bars), not a timed benchmark.
//   [REPEATS=f [REMEASURED=1]] probecomp_fit_cases CASE SIGMA SEEDS      CASE: grid (7 200 points), random (6 000 shuffled, no i,j,k),
//                                             random3000, steep (the dent narrowed to 19° flanks); SIGMA in mm
// Errors are signed distances of the compensated points from the actual surface the simulator made; "maxall"
// includes flagged rows; coverage is the share of ok rows whose error is within ±2u, overall and in the worst of
// a 4 × 4 grid of regions over the panel. REGIONS=1 prints each region: its rms error, rms u, the true centre's
// rms distance from the fitted centre surface (the fit's own error) and its coverage; WORST=1 the largest errors.
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <string>
#include <algorithm>
#include "probecomp/studies/freeform_study.hpp"
#include "probecomp/cad/locator.hpp"
#include "probecomp/simulation/measure.hpp"
#include "probecomp/nurbs/closest_point.hpp"
using namespace probecomp;
int main(int argc, char** argv) {
  const std::string which = argc > 1 ? argv[1] : "grid";
  const double sigma = argc > 2 ? std::atof(argv[2]) : 0.0045;
  const int seeds = argc > 3 ? std::atoi(argv[3]) : 1;
  double sum_centre = 0, sum_std = 0, sum_max = 0, sum_mean = 0, sum_cov = 0, min_region = 100;
  for (int s = 1; s <= seeds; ++s) {
    studies::FreeformStudyOptions o = which == "random"       ? studies::scattered_points(6000)
                                      : which == "random3000" ? studies::scattered_points(3000)
                                                              : studies::FreeformStudyOptions{};
    o.seed = s;
    o.noise_sigma = sigma;
    if (which == "steep") o.steep_dent = true;
    // REPEATS=f: a fraction f of the points recorded twice (REMEASURED=1: a second touch with its own noise).
    if (const char* f = std::getenv("REPEATS")) o.repeated_fraction = std::atof(f);
    o.exact_repeats = std::getenv("REMEASURED") == nullptr;
    const auto r = studies::run_freeform_study(o);
    const auto& c = r.cad_summary;
    int flagged = 0; for (auto& p : r.cad.points) flagged += p.status != compensation::PointStatus::Ok;
    // max over all computed points (flagged included)
    double maxall = 0; 
    const cad::Model actual = simulation::actual_model(r.freeform.nominal, r.freeform.deformation, r.freeform.placement);
    const cad::ModelLocator loc(actual);
    int inside = 0, counted = 0;
    int region_in[16] = {}, region_n[16] = {};
    std::size_t worst = 0;
    for (std::size_t k = 0; k < r.cad.points.size(); ++k) {
      auto& p = r.cad.points[k];
      if (!p.computed()) continue;
      double e = std::abs(loc.closest_point(p.contact).distance);
      if (e > maxall) { maxall = e; worst = k; }
      if (p.status != compensation::PointStatus::Ok) continue;
      const Point3& x = r.plan[k].point;
      const int ru = std::clamp(static_cast<int>((x.x() + 50.0) / 25.0), 0, 3), rv = std::clamp(static_cast<int>((x.y() + 25.0) / 12.5), 0, 3);
      const bool in = e <= 2.0 * p.uncertainty;
      inside += in; ++counted; region_in[ru * 4 + rv] += in; ++region_n[ru * 4 + rv];
    }
    // The fitted centre surface (what `probecomp fit` writes) against the truth: each true tip centre's distance
    // from it, rms over all points.
    double centre2 = 0.0;
    {
      const nurbs::ClosestPointSolver solver(*r.cad.faces[0].centre_surface);
      for (std::size_t k = 0; k < r.touches.size(); ++k) {
        const double cd = solver.closest_point(r.touches[k].centre).distance;
        centre2 += cd * cd;
      }
      centre2 /= static_cast<double>(r.touches.size());
      sum_centre += std::sqrt(centre2);
    }
    if (std::getenv("REGIONS")) {
      double e2[16] = {}, u2[16] = {}, c2[16] = {};
      const nurbs::ClosestPointSolver solver(*r.cad.faces[0].centre_surface);
      for (std::size_t k = 0; k < r.cad.points.size(); ++k) {
        auto& p = r.cad.points[k];
        if (p.status != compensation::PointStatus::Ok) continue;
        const Point3& x = r.plan[k].point;
        const int ru = std::clamp(static_cast<int>((x.x() + 50.0) / 25.0), 0, 3), rv = std::clamp(static_cast<int>((x.y() + 25.0) / 12.5), 0, 3);
        const double e = loc.closest_point(p.contact).distance;
        e2[ru * 4 + rv] += e * e; u2[ru * 4 + rv] += p.uncertainty * p.uncertainty;
        const double cd = solver.closest_point(r.touches[k].centre).distance; c2[ru * 4 + rv] += cd * cd;
      }
      for (int g = 0; g < 16; ++g) if (region_n[g] > 0) std::printf("  region %d,%d: n %d rms err %.3f rms u %.3f centre %.3f coverage %.1f %%\n", g / 4, g % 4, region_n[g],
          std::sqrt(e2[g] / region_n[g]) * 1e3, std::sqrt(u2[g] / region_n[g]) * 1e3, std::sqrt(c2[g] / region_n[g]) * 1e3, 100.0 * region_in[g] / region_n[g]);
    }
    double worst_region = 1.0;
    for (int g = 0; g < 16; ++g) if (region_n[g] > 0) worst_region = std::min(worst_region, static_cast<double>(region_in[g]) / region_n[g]);
    double mean_u = 0; for (auto& p : r.cad.points) if (p.computed()) mean_u += p.uncertainty; mean_u /= static_cast<double>(r.cad.points.size());
    if (std::getenv("WORST")) { auto& p = r.cad.points[worst]; std::printf("  worst %zu at %.3f %.3f %.3f status %s dev %.4f\n", worst, p.contact.x(), p.contact.y(), p.contact.z(), compensation::to_string(p.status), p.deviation);
      for (std::size_t k = 0; k < r.cad.points.size(); ++k) { auto& q = r.cad.points[k]; if (!q.computed()) continue; double e = loc.closest_point(q.contact).distance; if (std::abs(e) > 0.008) {
        const nurbs::ClosestPointSolver solver(*r.cad.faces[0].centre_surface);
        auto f1 = solver.closest_point(r.touches[k].centre); auto f2 = solver.closest_point(r.touches[k].measured);
        auto fn = nurbs::unit_normal(*r.cad.faces[0].centre_surface, f2.u, f2.v).n;
        std::printf("    %zu %.3f %.3f err %.1f um %s | true centre off fit %.1f um, raw off fit %.1f, normal angle %.2f deg\n", k, q.contact.x(), q.contact.y(), e*1e3, compensation::to_string(q.status), f1.distance*1e3, f2.distance*1e3, std::acos(std::min(1.0, std::abs(fn.dot(r.touches[k].normal))))*57.3); } } }
    const auto& f = r.cad.faces.at(0);
    std::printf("%s sigma %.4f seed %d: std %.3f mean %.3f max %.3f maxall %.3f um, flagged %d, cps %d, edf %.0f, l10 %.2f, noise %.3f um, "
                "mean u %.3f um, coverage 2u %.1f %% (worst region %.1f %%), %.3f s (%s)\n",
      which.c_str(), sigma, s, c.std*1e3, c.mean*1e3, c.max_abs()*1e3, maxall*1e3, flagged, f.control_points, f.effective_dof, f.log10_smoothing, f.noise_sigma*1e3,
      mean_u*1e3, 100.0 * inside / std::max(counted, 1), 100.0 * worst_region, r.cad_seconds, f.stop_reason.c_str());
    sum_cov += 100.0 * inside / std::max(counted, 1); min_region = std::min(min_region, 100.0 * worst_region);
    sum_std += c.std; sum_max += maxall; sum_mean += c.mean;
  }
  std::printf("MEAN over %d seeds: fitted centre surface rms %.3f um, std %.3f mean %.3f maxall %.3f um, coverage %.1f %%, worst region %.1f %%\n", seeds,
              sum_centre/seeds*1e3, sum_std/seeds*1e3, sum_mean/seeds*1e3, sum_max/seeds*1e3, sum_cov/seeds, min_region);
}
