// The compensated points' error split into bias and scatter over noise seeds, per region of a 4 × 4 grid over the
// panel, against the rms u the tool reported there (a command that prints its own figures, not a benchmark):
//   probecomp_fit_bias_variance CASE SIGMA SEEDS      CASE: grid or steep (points at fixed positions); SIGMA in mm
// "bias" is the rms over the region's points of their mean error over the seeds (it still holds scatter²/seeds),
// "scatter" the rms of their standard deviation; ratio = total rms error / rms u (1: u is right on average there).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "probecomp/cad/locator.hpp"
#include "probecomp/simulation/measure.hpp"
#include "probecomp/studies/freeform_study.hpp"
using namespace probecomp;
int main(int argc, char** argv) {
  const std::string which = argc > 1 ? argv[1] : "grid";
  const double sigma = argc > 2 ? std::atof(argv[2]) : 0.0045;
  const int seeds = argc > 3 ? std::atoi(argv[3]) : 8;
  std::vector<double> se, se2, su2;
  std::vector<int> cnt;
  std::vector<int> reg;
  for (int s = 1; s <= seeds; ++s) {
    studies::FreeformStudyOptions o;
    o.seed = s;
    o.noise_sigma = sigma;
    if (which == "steep") o.steep_dent = true;
    const auto r = studies::run_freeform_study(o);
    const cad::Model actual =
        simulation::actual_model(r.freeform.nominal, r.freeform.deformation, r.freeform.placement);
    const cad::ModelLocator loc(actual);
    const std::size_t n = r.cad.points.size();
    if (se.empty()) {
      se.assign(n, 0);
      se2.assign(n, 0);
      su2.assign(n, 0);
      cnt.assign(n, 0);
      reg.assign(n, 0);
    }
    for (std::size_t k = 0; k < n; ++k) {
      auto& p = r.cad.points[k];
      if (p.status != compensation::PointStatus::Ok) continue;
      const double e = loc.closest_point(p.contact).distance;
      se[k] += e;
      se2[k] += e * e;
      su2[k] += p.uncertainty * p.uncertainty;
      ++cnt[k];
      const Point3& x = r.plan[k].point;
      reg[k] = std::clamp(static_cast<int>((x.x() + 50.0) / 25.0), 0, 3) * 4 +
               std::clamp(static_cast<int>((x.y() + 25.0) / 12.5), 0, 3);
    }
  }
  double b2[16] = {}, v2[16] = {}, u2[16] = {};
  int m[16] = {};
  for (std::size_t k = 0; k < se.size(); ++k) {
    if (cnt[k] < 2) continue;
    const double mu = se[k] / cnt[k];
    b2[reg[k]] += mu * mu;
    v2[reg[k]] += (se2[k] / cnt[k] - mu * mu) * cnt[k] / (cnt[k] - 1);
    u2[reg[k]] += su2[k] / cnt[k];
    ++m[reg[k]];
  }
  for (int g = 0; g < 16; ++g)
    if (m[g])
      std::printf("region %d,%d: bias rms %.3f  scatter rms %.3f  total %.3f  u rms %.3f  ratio %.2f\n", g / 4, g % 4,
                  std::sqrt(b2[g] / m[g]) * 1e3, std::sqrt(v2[g] / m[g]) * 1e3, std::sqrt((b2[g] + v2[g]) / m[g]) * 1e3,
                  std::sqrt(u2[g] / m[g]) * 1e3, u2[g] > 0 ? std::sqrt((b2[g] + v2[g]) / u2[g]) : 0.0);
}
