#include "penalty.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "hierarchical_rows.hpp"
#include "rational_basis.hpp"

namespace probecomp::fitting::detail {

using nurbs::Surface;

namespace {

// Gauss–Legendre on [−1, 1], five nodes: exact for the polynomial (non-rational) energy up to degree 5 surfaces.
constexpr std::array<double, 5> kGaussNodes = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                                               0.9061798459386640};
constexpr std::array<double, 5> kGaussWeights = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                                                 0.4786286704993665, 0.2369268850561891};

}  // namespace

MeanSpeeds mean_speeds(const Surface& s) {
  double Lu = 0.0, Lv = 0.0;
  const nurbs::Domain d = s.domain();
  constexpr int kSamples = 9;
  for (int a = 0; a < kSamples; ++a) {
    for (int c = 0; c < kSamples; ++c) {
      const nurbs::SurfaceD1 e = nurbs::derivatives_d1(s, d.u0 + (d.u1 - d.u0) * (a + 0.5) / kSamples,
                                                       d.v0 + (d.v1 - d.v0) * (c + 0.5) / kSamples);
      Lu += e.Su.norm();
      Lv += e.Sv.norm();
    }
  }
  return {std::max(Lu / (kSamples * kSamples), 1e-12), std::max(Lv / (kSamples * kSamples), 1e-12)};
}

// The thin-plate energy's matrix G: Σ_spans φ_s ∫∫_span (R_ss R_ssᵀ + 2 R_st R_stᵀ + R_tt R_ttᵀ) ds dt, s = L_u·u,
// t = L_v·v, by 5 × 5 Gauss points per span. Chunks of spans of the unknowns' outer direction in a fixed number,
// summed in order.
// With `D` (n × 3, the displacement of the control net) it writes each span's isotropic energy of that displacement,
// Dᵀ G_span D (θ = 1, unweighted), to `span_energy` instead and builds no matrix.
ThinPlateTerms thin_plate_energy(const Surface& s, const Ordering& order, int b, std::span<const double> span_weights,
                                 const std::vector<double>* D, std::vector<double>* span_energy,
                                 const HierarchicalBasis* thb) {
  const int n = thb ? thb->unknowns : s.num_u() * s.num_v();
  const int p = s.p(), q = s.q();
  const std::vector<double> bu = s.U().breakpoints();
  const std::vector<double> bv = s.V().breakpoints();
  const int nsu = static_cast<int>(bu.size()) - 1, nsv = static_cast<int>(bv.size()) - 1;
  const MeanSpeeds speeds = mean_speeds(s);
  const double Lu = speeds.u, Lv = speeds.v;
  // ds dt = Lu Lv du dv; d_ss = d_uu / Lu², d_st = d_uv / (Lu Lv), d_tt = d_vv / Lv².
  const double cuu = Lu * Lv / std::pow(Lu, 4), cuv = 2.0 * Lu * Lv / (Lu * Lu * Lv * Lv), cvv = Lu * Lv / std::pow(Lv, 4);
  // Each span's knot span index in U (a) and in V (e).
  std::vector<int> span_u(static_cast<std::size_t>(nsu)), span_v(static_cast<std::size_t>(nsv));
  for (int a = 0; a < nsu; ++a) {
    span_u[static_cast<std::size_t>(a)] =
        s.U().find_span(0.5 * (bu[static_cast<std::size_t>(a)] + bu[static_cast<std::size_t>(a) + 1]));
  }
  for (int e = 0; e < nsv; ++e) {
    span_v[static_cast<std::size_t>(e)] =
        s.V().find_span(0.5 * (bv[static_cast<std::size_t>(e)] + bv[static_cast<std::size_t>(e) + 1]));
  }
  // The chunks split the spans of the unknowns' outer direction (u when v is inner, else v), each chunk taking every
  // span of the other direction: its functions' unknowns are then one narrow run of rows (a THB basis's unknowns
  // are in the same order: hierarchical.cpp). Split along the inner direction, every chunk would reach nearly every
  // row (the million-point benchmark's 171 × 177 net, u inner, at half-bandwidth 516: 24 nearly whole bands, 3 GB).
  // A span is (outer o, inner x) in the loops, (a, e) in u and v.
  const bool outer_u = order.v_inner;
  const int n_outer = outer_u ? nsu : nsv, n_inner = outer_u ? nsv : nsu;
  const int chunks = std::min(n_outer, 8);
  std::vector<ThinPlateTerms> parts(static_cast<std::size_t>(chunks));
  if (span_energy) span_energy->assign(static_cast<std::size_t>(nsu) * nsv, 0.0);
  // Each chunk's terms cover only the band's rows its spans' functions reach, rows [row0, row0 + rows) held from 0:
  // the same sums, without eight whole bands of three terms each (a THB face of 5 400 unknowns at half-bandwidth
  // 386: 400 MB, zeroed).
  std::vector<int> row0(static_cast<std::size_t>(chunks), n), row1(static_cast<std::size_t>(chunks), -1);
  // The first chunk's terms hold every row, and the others are summed into them: no three whole bands more beside
  // the chunks' (the million-point benchmark's at half-bandwidth 516: 125 MB a band).
  row0[0] = 0;
  row1[0] = n - 1;
  tbb::parallel_for(1, chunks, [&](int c) {
    int& lo = row0[static_cast<std::size_t>(c)];
    int& hi = row1[static_cast<std::size_t>(c)];
    for (int o = n_outer * c / chunks; o < n_outer * (c + 1) / chunks; ++o) {
      for (int x = 0; x < n_inner; ++x) {
        const int a = outer_u ? o : x, e = outer_u ? x : o;
        const int i0 = span_u[static_cast<std::size_t>(a)] - p, j0 = span_v[static_cast<std::size_t>(e)] - q;
        if (thb) {
          const auto cell = static_cast<std::size_t>(i0 * s.num_v() + j0);
          lo = std::min(lo, thb->cell_unknowns[static_cast<std::size_t>(thb->cell_first[cell])]);
          hi = std::max(hi, thb->cell_unknowns[static_cast<std::size_t>(thb->cell_first[cell + 1]) - 1]);
        } else {
          for (int k = 0; k < (p + 1) * (q + 1); ++k) {
            const int I = order.index(i0 + k / (q + 1), j0 + k % (q + 1));
            lo = std::min(lo, I);
            hi = std::max(hi, I);
          }
        }
      }
    }
  });
  tbb::parallel_for(0, chunks, [&](int c) {
    ThinPlateTerms& G = parts[static_cast<std::size_t>(c)];
    const int shift = row0[static_cast<std::size_t>(c)];
    const int rows = std::max(0, row1[static_cast<std::size_t>(c)] - shift + 1);
    if (!D) G = ThinPlateTerms{Band(rows, b), Band(rows, b), Band(rows, b)};
    RationalBasisD2 d2;
    const int m_max = thb ? std::max(thb->max_row, (p + 1) * (q + 1)) : (p + 1) * (q + 1);
    std::vector<int> idx_store(static_cast<std::size_t>(m_max));
    std::vector<double> uu(static_cast<std::size_t>(m_max)), uv(uu), vv(uu);
    // A span's functions are the same at all its Gauss points: their products are summed over the span in a dense
    // block first (lower triangle by position, [x·m + y], y ≤ x), added into the bands once per span.
    const auto block_size = static_cast<std::size_t>(m_max) * static_cast<std::size_t>(m_max);
    std::vector<double> block_uu(block_size), block_uv(block_size), block_vv(block_size);
    int* idx = idx_store.data();
    int m = (p + 1) * (q + 1);
    for (int o = n_outer * c / chunks; o < n_outer * (c + 1) / chunks; ++o) {
      for (int x = 0; x < n_inner; ++x) {
        const int a = outer_u ? o : x, e = outer_u ? x : o;
        const double ua = bu[static_cast<std::size_t>(a)], ub = bu[static_cast<std::size_t>(a) + 1];
        const int su = span_u[static_cast<std::size_t>(a)];
        const double phi = D ? 1.0 : span_weights.empty() ? 1.0 : span_weights[static_cast<std::size_t>(a) * nsv + e];
        if (phi == 0.0) continue;
        double energy = 0.0;
        const double va = bv[static_cast<std::size_t>(e)], vb = bv[static_cast<std::size_t>(e) + 1];
        const int sv = span_v[static_cast<std::size_t>(e)];
        const double jac = 0.25 * (ub - ua) * (vb - va) * phi;
        if (!D) {
          std::fill(block_uu.begin(), block_uu.end(), 0.0);
          std::fill(block_uv.begin(), block_uv.end(), 0.0);
          std::fill(block_vv.begin(), block_vv.end(), 0.0);
        }
        for (std::size_t gu = 0; gu < kGaussNodes.size(); ++gu) {
          const double u = 0.5 * (ua + ub) + 0.5 * (ub - ua) * kGaussNodes[gu];
          for (std::size_t gv = 0; gv < kGaussNodes.size(); ++gv) {
            const double v = 0.5 * (va + vb) + 0.5 * (vb - va) * kGaussNodes[gv];
            detail::rational_basis_d2(s, su, sv, u, v, d2);
            const double* Ruu = d2.Ruu;
            const double* Ruv = d2.Ruv;
            const double* Rvv = d2.Rvv;
            if (thb && !D) {
              // The hierarchical functions' second derivatives: the same combinations of the tensor ones.
              m = reduce_row(*thb, d2.i0, d2.j0, d2.Ruu, uu.data(), idx);
              (void)reduce_row(*thb, d2.i0, d2.j0, d2.Ruv, uv.data(), idx);
              (void)reduce_row(*thb, d2.i0, d2.j0, d2.Rvv, vv.data(), idx);
              Ruu = uu.data();
              Ruv = uv.data();
              Rvv = vv.data();
            } else {
              for (int k = 0; k < m; ++k) idx[k] = order.index(d2.i0 + k / (q + 1), d2.j0 + k % (q + 1));
            }
            const double w = jac * kGaussWeights[gu] * kGaussWeights[gv];
            if (D) {
              Vector3 duu = Vector3::Zero(), duv = Vector3::Zero(), dvv = Vector3::Zero();
              for (int k = 0; k < m; ++k) {
                const Vector3 d((*D)[3 * idx[k]], (*D)[3 * idx[k] + 1], (*D)[3 * idx[k] + 2]);
                duu += d2.Ruu[k] * d;
                duv += d2.Ruv[k] * d;
                dvv += d2.Rvv[k] * d;
              }
              energy += w * (cuu * duu.squaredNorm() + cuv * duv.squaredNorm() + cvv * dvv.squaredNorm());
              continue;
            }
            const double wuu = w * cuu, wuv = w * cuv, wvv = w * cvv;
            for (int k = 0; k < m; ++k) {
              const double fuu = wuu * Ruu[k], fuv = wuv * Ruv[k], fvv = wvv * Rvv[k];
              double* row_uu = &block_uu[static_cast<std::size_t>(k * m)];
              double* row_uv = &block_uv[static_cast<std::size_t>(k * m)];
              double* row_vv = &block_vv[static_cast<std::size_t>(k * m)];
              for (int l = 0; l <= k; ++l) {
                row_uu[l] += fuu * Ruu[l];
                row_uv[l] += fuv * Ruv[l];
                row_vv[l] += fvv * Rvv[l];
              }
            }
          }
        }
        if (D) {
          (*span_energy)[static_cast<std::size_t>(a) * nsv + e] = energy;
          continue;
        }
        for (int k = 0; k < m; ++k) {
          for (int l = 0; l <= k; ++l) {
            const int I = std::max(idx[k], idx[l]) - shift, J = std::min(idx[k], idx[l]) - shift;
            const auto at = static_cast<std::size_t>(k * m + l);
            G.uu.at(I, J) += block_uu[at];
            G.uv.at(I, J) += block_uv[at];
            G.vv.at(I, J) += block_vv[at];
          }
        }
      }
    }
  });
  if (D) return {};
  // The chunks' rows summed in chunk order, as whole bands would be, into the first chunk's whole bands; each
  // chunk freed once added.
  ThinPlateTerms G = std::move(parts[0]);
  const std::size_t stride = static_cast<std::size_t>(b) + 1;
  for (int c = 1; c < chunks; ++c) {
    ThinPlateTerms& part = parts[static_cast<std::size_t>(c)];
    const std::size_t at = static_cast<std::size_t>(row0[static_cast<std::size_t>(c)]) * stride;
    for (std::size_t k = 0; k < part.uu.a.size(); ++k) {
      G.uu.a[at + k] += part.uu.a[k];
      G.uv.a[at + k] += part.uv.a[k];
      G.vv.a[at + k] += part.vv.a[k];
    }
    part = ThinPlateTerms{};
  }
  return G;
}

}  // namespace probecomp::fitting::detail
