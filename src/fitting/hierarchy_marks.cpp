#include "hierarchy_marks.hpp"

#include <algorithm>

namespace probecomp::fitting::detail {

namespace {

int cells(const std::vector<double>& breaks) { return static_cast<int>(breaks.size()) - 1; }

}  // namespace

LevelFlags nested_domains(const LevelFlags& marks, const std::vector<double>& bu, const std::vector<double>& bv,
                          int ring) {
  LevelFlags domains;
  for (std::size_t l = 0; l < marks.size(); ++l) {
    const int nu = cells(halved(bu, static_cast<int>(l))), nv = cells(halved(bv, static_cast<int>(l)));
    std::vector<std::uint8_t> d(static_cast<std::size_t>(nu) * nv, 0);
    bool any = false;
    for (int a = 0; a < nu; ++a) {
      for (int b = 0; b < nv; ++b) {
        if (!marks[l][static_cast<std::size_t>(a) * nv + b]) continue;
        for (int x = std::max(0, a - ring); x <= std::min(nu - 1, a + ring); ++x) {
          for (int y = std::max(0, b - ring); y <= std::min(nv - 1, b + ring); ++y) {
            // Inside the domain above: the level-(l − 1) cell (x / 2, y / 2) in Ωˡ.
            if (l > 0 && !domains[l - 1][static_cast<std::size_t>(x / 2) * (nv / 2) + static_cast<std::size_t>(y / 2)]) continue;
            d[static_cast<std::size_t>(x) * nv + y] = 1;
            any = true;
          }
        }
      }
    }
    if (!any) break;
    domains.push_back(std::move(d));
  }
  return domains;
}

int depth_at(const LevelFlags& domains, const std::vector<double>& bu, const std::vector<double>& bv, double u,
             double v) {
  int depth = 0;
  for (std::size_t l = 0; l < domains.size(); ++l) {
    const std::vector<double> hu = halved(bu, static_cast<int>(l)), hv = halved(bv, static_cast<int>(l));
    if (!domains[l][span_at(hu, hv, u, v)]) break;
    depth = static_cast<int>(l) + 1;
  }
  return depth;
}

void mark_at(LevelFlags& marks, int level, const std::vector<double>& bu, const std::vector<double>& bv, double u,
             double v) {
  const std::vector<double> hu = halved(bu, level), hv = halved(bv, level);
  while (static_cast<int>(marks.size()) <= level) {
    const int l = static_cast<int>(marks.size());
    marks.emplace_back(static_cast<std::size_t>(cells(halved(bu, l))) * static_cast<std::size_t>(cells(halved(bv, l))), 0);
  }
  marks[static_cast<std::size_t>(level)][span_at(hu, hv, u, v)] = 1;
}

LevelFlags carried(const LevelFlags& marks, const std::vector<double>& bu, const std::vector<double>& bv,
                   const std::vector<double>& nbu, const std::vector<double>& nbv) {
  LevelFlags out;
  for (std::size_t l = 0; l < marks.size(); ++l) {
    const std::vector<double> hu = halved(bu, static_cast<int>(l)), hv = halved(bv, static_cast<int>(l));
    const std::vector<double> nu = halved(nbu, static_cast<int>(l)), nv = halved(nbv, static_cast<int>(l));
    std::vector<std::uint8_t> m(static_cast<std::size_t>(cells(nu)) * cells(nv), 0);
    for (int a = 0; a < cells(nu); ++a) {
      const int oa = span_of(hu, 0.5 * (nu[static_cast<std::size_t>(a)] + nu[static_cast<std::size_t>(a) + 1]));
      for (int b = 0; b < cells(nv); ++b) {
        const int ob = span_of(hv, 0.5 * (nv[static_cast<std::size_t>(b)] + nv[static_cast<std::size_t>(b) + 1]));
        m[static_cast<std::size_t>(a) * cells(nv) + b] = marks[l][static_cast<std::size_t>(oa) * cells(hv) + static_cast<std::size_t>(ob)];
      }
    }
    out.push_back(std::move(m));
  }
  return out;
}

}  // namespace probecomp::fitting::detail
