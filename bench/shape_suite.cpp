// The shape suite of issue 48, scored: a command that prints its own figures, not a timed benchmark.
//   probecomp_shape_suite [--sigma S] [--case NAME[,NAME…]] [--draw N [--first SEED]] [--no-reference]
//                         [--plain-reference] [--regions] [--stops] [--oracle] [--seeds N] [--noise-draw D]
//                         [--no-local-refinement] [--levels L] [--min-cover C] [--dense-start K]
//                         [--roughness-penalty] [--isotropic-scan-lines]
// Each case of simulation::shape_suite() (or N cases drawn at random from its families, seeds FIRST, FIRST+1, …)
// is simulated, compensated by the CAD method and scored against the actual part: std, mean and largest error
// (µm, ok rows), the rows flagged, ±2u coverage overall and in the worst of 6 × 6 regions, the fitted centre
// surface's rms distance from the true centres (what `probecomp fit` writes), and the same std for the reference
// smoother (tests/support/reference_smoother.hpp, a P-spline with GCV written apart from the product's fit) on the
// same points with the same registration, and the ratio of the two. A summary gives the median and worst of each.
// --sigma replaces every case's noise (mm). --regions prints the quantiles of u and each of the 6 × 6 regions' rms
// error, rms u and coverage. --stops prints where each face's refinement stopped and why, and its noise; --oracle
// fits each case again with every fit's cross-validated λ moved by ±0.25, 0.5 and 1 decade, and prints the std at
// each: whether cross-validation over- or under-smooths there (the suite knows the truth; the product does not).
// --seeds N runs each case N times, the noise drawn again each time on the same points (ShapeCase::noise_draw),
// and prints per case the spread of the figures over the draws, the error split into bias and scatter against u
// (rms over the rows), each region's coverage averaged over them (what
// u promises a region on average), and the worst region's coverage had each point's u been its true rms error
// (over the draws): about what a u without fault would reach in the worst region of one draw. --noise-draw D
// runs draw D of each case's noise instead of its own (0). --no-local-refinement fits with
// fitting::AdaptiveFitOptions::local_refinement off (knot lines only, as before it); --levels L lets cells refine
// locally to THB level L (AdaptiveFitOptions::local_refinement_levels), --min-cover C sets
// AdaptiveFitOptions::local_refinement_min_cover, --dense-start K AdaptiveFitOptions::dense_start_points_per_control_point
// (0: the fit from the start's knots only); --roughness-penalty sets AdaptiveFitOptions::spatial_penalty to Roughness
// (the compensation's default is Balance); --isotropic-scan-lines turns off
// compensation::FitOptions::anisotropy_on_scan_lines.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "reference_compensation.hpp"
#include "probecomp/geometry/statistics.hpp"
#include "probecomp/simulation/shape_suite.hpp"
#include "probecomp/studies/shape_suite_study.hpp"

using namespace probecomp;

namespace {

struct Row {
  std::string name;
  double sigma = 0, std = 0, mean = 0, max = 0, coverage = 0, worst_region = 0, fit_rms = 0, mean_u = 0;
  int flagged = 0, rows = 0;
  double reference_std = std::nan(""), reference_max = std::nan(""), seconds = 0;
};

double median(std::vector<double> v) {
  std::erase_if(v, [](double x) { return !std::isfinite(x); });
  return v.empty() ? std::nan("") : geometry::median_in_place(v);
}

double worst(const std::vector<double>& v, bool largest) {
  double w = std::nan("");
  for (double x : v) {
    if (std::isfinite(x)) w = std::isnan(w) ? x : largest ? std::max(w, x) : std::min(w, x);
  }
  return w;
}

}  // namespace

int main(int argc, char** argv) {
  double sigma = -1.0;
  int draw = 0, seeds = 0;
  std::uint64_t first = 1, noise_draw = 0;
  bool reference = true, regions = false, plain_reference = false, stops = false, oracle = false;
  std::vector<std::string> only;
  compensation::CompensateOptions options;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    auto next = [&]() -> std::string {
      if (a + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++a];
    };
    if (arg == "--sigma") {
      sigma = std::atof(next().c_str());
    } else if (arg == "--draw") {
      draw = std::atoi(next().c_str());
    } else if (arg == "--first") {
      first = std::strtoull(next().c_str(), nullptr, 10);
    } else if (arg == "--case") {
      std::string list = next();
      for (std::size_t p = 0; p <= list.size();) {
        const std::size_t comma = std::min(list.find(',', p), list.size());
        only.push_back(list.substr(p, comma - p));
        p = comma + 1;
      }
    } else if (arg == "--no-reference") {
      reference = false;
    } else if (arg == "--plain-reference") {
      plain_reference = true;
    } else if (arg == "--regions") {
      regions = true;
    } else if (arg == "--stops") {
      stops = true;
    } else if (arg == "--oracle") {
      oracle = true;
    } else if (arg == "--seeds") {
      seeds = std::atoi(next().c_str());
    } else if (arg == "--no-local-refinement") {
      options.fit.surface.local_refinement = false;
    } else if (arg == "--isotropic-scan-lines") {
      options.fit.anisotropy_on_scan_lines = false;
    } else if (arg == "--roughness-penalty") {
      options.fit.surface.spatial_penalty = fitting::AdaptiveFitOptions::SpatialPenalty::Roughness;
    } else if (arg == "--dense-start") {
      options.fit.surface.dense_start_points_per_control_point = std::atof(next().c_str());
    } else if (arg == "--min-cover") {
      options.fit.surface.local_refinement_min_cover = std::atof(next().c_str());
    } else if (arg == "--levels") {
      options.fit.surface.local_refinement_levels = std::atoi(next().c_str());
    } else if (arg == "--noise-draw") {
      noise_draw = std::strtoull(next().c_str(), nullptr, 10);
    } else {
      std::fprintf(stderr, "usage: %s [--sigma S] [--case NAME,...] [--draw N [--first SEED]] [--no-reference] [--regions] [--stops] [--oracle] [--seeds N] [--noise-draw D] [--no-local-refinement] [--levels L] [--min-cover C] [--dense-start K] [--roughness-penalty] [--isotropic-scan-lines]\n",
                   argv[0]);
      return 2;
    }
  }
  std::vector<simulation::ShapeCase> cases;
  if (draw > 0) {
    for (int k = 0; k < draw; ++k) cases.push_back(simulation::draw_shape_case(first + static_cast<std::uint64_t>(k), 0.0045));
  } else {
    cases = simulation::shape_suite();
  }
  if (!only.empty()) {
    std::erase_if(cases, [&](const simulation::ShapeCase& c) {
      return std::none_of(only.begin(), only.end(), [&](const std::string& n) { return c.name.find(n) != std::string::npos; });
    });
  }
  if (seeds > 0) {
    std::printf("%d draws of the noise per case: median and worst over the draws\n", seeds);
    std::printf("%-22s %5s | %13s | %11s | %11s | %11s | %6s | %s\n", "case", "sigma", "std", "cov2u", "worst region",
                "oracle's", "lowest", "error's bias, scatter; u (rms um)");
    std::vector<double> std_medians, worst_medians, oracle_medians, region_means;
    for (simulation::ShapeCase c : cases) {
      if (sigma >= 0.0) c.noise_sigma = sigma;
      const studies::ReplicatedShapeCase r = studies::replicate_shape_case(c, seeds, options);
      auto scaled = [](std::vector<double> v, double by) {
        for (double& x : v) x *= by;
        return v;
      };
      const auto stds = scaled(r.stds, 1e3), coverages = scaled(r.coverages, 100.0);
      const auto worsts = scaled(r.worst_regions, 100.0), oracles = scaled(r.oracle_worst_regions, 100.0);
      std::printf("%-22s %5.1f | %6.3f %6.3f | %5.1f %5.1f | %5.1f %5.1f | %5.1f %5.1f | %6.1f | %.3f, %.3f; %.3f\n",
                  c.name.c_str(), c.noise_sigma * 1e3, median(stds), worst(stds, true), median(coverages),
                  worst(coverages, false), median(worsts), worst(worsts, false), median(oracles), worst(oracles, false),
                  100.0 * r.lowest_region_mean, r.bias_rms * 1e3, r.scatter_rms * 1e3, r.u_rms * 1e3);
      std::fflush(stdout);
      std_medians.push_back(median(stds));
      worst_medians.push_back(median(worsts));
      oracle_medians.push_back(median(oracles));
      region_means.push_back(100.0 * r.lowest_region_mean);
    }
    std::printf("SUMMARY over %zu cases (medians over draws): std median %.3f worst %.3f | worst region median %.1f lowest %.1f"
                " | oracle's worst region median %.1f lowest %.1f | lowest region mean median %.1f lowest %.1f\n",
                cases.size(), median(std_medians), worst(std_medians, true), median(worst_medians),
                worst(worst_medians, false), median(oracle_medians), worst(oracle_medians, false), median(region_means),
                worst(region_means, false));
    return 0;
  }
  std::printf("%-22s %5s %6s | %6s %6s %6s %4s | %6s %6s %5s | %6s | %6s %6s %5s | features\n", "case", "sigma", "rows", "std",
              "mean", "max", "flag", "cov2u", "worst", "u", "fitrms", "refstd", "refmax", "ratio");
  std::vector<Row> rows;
  for (simulation::ShapeCase c : cases) {
    if (sigma >= 0.0) c.noise_sigma = sigma;
    c.noise_draw = noise_draw;
    Row r;
    r.name = c.name;
    r.sigma = c.noise_sigma * 1e3;
    std::string features;
    for (const simulation::FeatureSpec& f : c.features) features += (features.empty() ? "" : "; ") + simulation::describe(f);
    try {
      const studies::ShapeCaseResult s = studies::run_shape_case(c, options);
      std::optional<bench::ReferenceScore> ref;
      r.rows = static_cast<int>(s.plan.size());
      r.std = s.cad_summary.std * 1e3;
      r.mean = s.cad_summary.mean * 1e3;
      r.max = s.cad_summary.max_abs() * 1e3;
      r.flagged = s.flagged;
      r.coverage = 100.0 * s.coverage_2u;
      r.worst_region = 100.0 * s.worst_region_coverage_2u;
      r.mean_u = s.mean_uncertainty * 1e3;
      r.fit_rms = s.fit_rms * 1e3;
      r.seconds = s.cad_seconds;
      if (reference) {
        ref = bench::score_reference(s, !plain_reference);
        r.reference_std = ref->std * 1e3;
        r.reference_max = ref->max_abs * 1e3;
      }
      std::printf("%-22s %5.1f %6d | %6.3f %6.3f %6.2f %4d | %6.1f %6.1f %5.2f | %6.3f | %6.3f %6.2f %5.2f | %s%s\n",
                  r.name.c_str(), r.sigma, r.rows, r.std, r.mean, r.max, r.flagged, r.coverage, r.worst_region, r.mean_u,
                  r.fit_rms, r.reference_std, r.reference_max, r.std / r.reference_std, features.c_str(),
                  c.sampling == simulation::Sampling::Random && !c.approach_normals ? " (no i,j,k)" : "");
      if (stops) {
        // Where each face's refinement stopped, and why: what a basis with local refinement could change.
        for (const compensation::FaceReport& f : s.cad.faces) {
          std::printf("    face %d: %d points, %d control points (edf %.1f, log10 lambda %+.2f, noise %.2f um), %d rounds, %d fits: %s\n",
                      f.face, f.points, f.control_points, f.effective_dof, f.log10_smoothing, f.noise_sigma * 1e3,
                      f.rounds, f.fits, f.stop_reason.c_str());
        }
        if (ref) {
          std::printf("    reference: edf %.1f, log10 lambda along u %+.2f, along v %+.2f\n", ref->edf, ref->log10_lambda_s,
                      ref->log10_lambda_t);
        }
      }
      if (oracle && !s.cad.faces.empty() && s.cad.faces.front().fitted) {
        // The std against the smoothing: every fit's λ, as cross-validation chose it, moved by a fixed number of
        // decades (PenalizedFitOptions::log10_smoothing_offset).
        std::printf("    oracle: chosen log10 lambda %+.2f, std", s.cad.faces.front().log10_smoothing);
        double best = r.std, best_offset = 0.0;
        for (const double offset : {-1.0, -0.5, -0.25, 0.0, 0.25, 0.5, 1.0}) {
          double std_um = r.std;
          if (offset != 0.0) {
            compensation::CompensateOptions moved = options;
            moved.fit.surface.fit.log10_smoothing_offset = offset;
            std_um = studies::run_shape_case(c, moved).cad_summary.std * 1e3;
          }
          std::printf(" %+.2f: %.3f", offset, std_um);
          if (std_um < best) {
            best = std_um;
            best_offset = offset;
          }
        }
        std::printf(" | best %+.2f at %.3f (%.0f %% of the chosen's)\n", best_offset, best, 100.0 * best / r.std);
      }
      if (regions) {
        std::array<double, 36> e2{}, u2{}, a2{};
        std::array<int, 36> n{}, in{};
        for (std::size_t k = 0; k < s.plan.size(); ++k) {
          if (s.cad.points[k].status != compensation::PointStatus::Ok || !std::isfinite(s.cad_error[k])) continue;
          const auto g = static_cast<std::size_t>(s.region[k]);
          e2[g] += s.cad_error[k] * s.cad_error[k];
          u2[g] += s.cad.points[k].uncertainty * s.cad.points[k].uncertainty;
          const double angle = std::acos(std::min(1.0, s.cad.points[k].normal.dot(s.touches[k].normal))) * 180.0 / M_PI;
          a2[g] += angle * angle;
          ++n[g];
          in[g] += std::abs(s.cad_error[k]) <= 2.0 * s.cad.points[k].uncertainty;
        }
        std::vector<double> us;
        for (std::size_t k = 0; k < s.plan.size(); ++k) {
          if (s.cad.points[k].status == compensation::PointStatus::Ok) us.push_back(s.cad.points[k].uncertainty * 1e3);
        }
        std::sort(us.begin(), us.end());
        if (!us.empty()) {
          auto q = [&](double p) { return us[std::min(us.size() - 1, static_cast<std::size_t>(p * us.size()))]; };
          std::printf("    u (um) quantiles 10 %% %.2f, 50 %% %.2f, 90 %% %.2f, 99 %% %.2f, largest %.2f\n", q(0.1), q(0.5),
                      q(0.9), q(0.99), us.back());
        }
        for (std::size_t g = 0; g < 36; ++g) {
          if (n[g] == 0) continue;
          std::printf("    region %zu,%zu: %4d rows, rms error %6.3f, rms u %6.3f, coverage %5.1f %%, rms normal error %.2f deg\n",
                      g / 6, g % 6, n[g], std::sqrt(e2[g] / n[g]) * 1e3, std::sqrt(u2[g] / n[g]) * 1e3, 100.0 * in[g] / n[g],
                      std::sqrt(a2[g] / n[g]));
        }
      }
    } catch (const std::exception& e) {
      std::printf("%-22s %5.1f FAILED: %s | %s\n", r.name.c_str(), r.sigma, e.what(), features.c_str());
      r.std = r.max = std::nan("");
    }
    std::fflush(stdout);
    rows.push_back(r);
  }
  auto column = [&](auto field) {
    std::vector<double> v;
    for (const Row& r : rows) v.push_back(field(r));
    return v;
  };
  const auto stds = column([](const Row& r) { return r.std; });
  const auto maxs = column([](const Row& r) { return r.max; });
  const auto means = column([](const Row& r) { return std::abs(r.mean); });
  const auto covs = column([](const Row& r) { return r.coverage; });
  const auto worsts = column([](const Row& r) { return r.worst_region; });
  const auto ratios = column([](const Row& r) { return r.std / r.reference_std; });
  const auto fits = column([](const Row& r) { return r.fit_rms; });
  std::printf("SUMMARY over %zu cases: std median %.3f worst %.3f | |mean| median %.3f worst %.3f | max median %.2f worst %.2f"
              " | cov2u median %.1f lowest %.1f | worst region median %.1f lowest %.1f | fit rms median %.3f worst %.3f"
              " | ratio to reference median %.3f worst %.3f\n",
              rows.size(), median(stds), worst(stds, true), median(means), worst(means, true), median(maxs),
              worst(maxs, true), median(covs), worst(covs, false), median(worsts), worst(worsts, false), median(fits),
              worst(fits, true), median(ratios), worst(ratios, true));
  return 0;
}
