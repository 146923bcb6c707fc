// Tensor-product cubic P-spline with GCV-chosen anisotropic (and optionally block-adaptive) penalties.
//
// Linear algebra. Coefficients are ordered so that the direction with fewer coefficients (m of them) varies
// fastest; the normal matrix A = BᵀWB + P is then block banded with m × m blocks and three blocks either side
// of the diagonal (bandwidth about 3m, the narrowest a tensor-product cubic basis allows in a banded order).
// A is factorised by a blocked left-looking band Cholesky, A = LLᵀ, the blocks dense so that Eigen's matrix
// products do the work. tr H = tr(A⁻¹BᵀWB) needs A⁻¹ only where BᵀWB is non-zero, which lies inside the band;
// those entries come from the Takahashi recurrence (Takahashi, Fagan & Chen 1973; Erisman & Tinney 1975,
// "On computing certain elements of the inverse of a sparse matrix"), here in block form:
//     Z_{R,J} = −Z_{R,R} U_J,   Z_{J,J} = (L_JJ L_JJᵀ)⁻¹ − U_Jᵀ Z_{R,J},   U_J = L_{R,J} L_JJ⁻¹,
// R the (up to three) block rows below J, swept from the last block column to the first. Every Z_{R,R} it needs
// is inside the band, so the cost is O(n b²) like the factorisation, and no dense n × n matrix is ever formed.

#include "support/reference_smoother.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace probecomp::reference {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Uniform cubic B-splines on [x0, x0 + spans·h], knots x0 + (j − 3)h continued past both ends (not clamped): all
// basis functions are translates of one, so f'' is exactly the linear spline with coefficients Δ²c/h² (the
// penalty is a discrete ∫f''² everywhere, edges included) and linear functions have coefficients linear in i.
struct Basis1D {
  double x0 = 0.0, h = 1.0;
  int spans = 1;

  // The first of the four basis functions non-zero at x, their values and derivatives d/dx.
  int eval(double x, double* v, double* d) const {
    const double u_all = (x - x0) / h;
    const int q = std::clamp(static_cast<int>(std::floor(u_all)), 0, spans - 1);
    const double u = u_all - q, w = 1.0 - u;
    v[0] = w * w * w / 6.0;
    v[1] = (3.0 * u * u * u - 6.0 * u * u + 4.0) / 6.0;
    v[2] = (-3.0 * u * u * u + 3.0 * u * u + 3.0 * u + 1.0) / 6.0;
    v[3] = u * u * u / 6.0;
    if (d != nullptr) {
      d[0] = -w * w / (2.0 * h);
      d[1] = (3.0 * u * u - 4.0 * u) / (2.0 * h);
      d[2] = (-3.0 * u * u + 2.0 * u + 1.0) / (2.0 * h);
      d[3] = u * u / (2.0 * h);
    }
    return q;
  }
  [[nodiscard]] int count() const { return spans + 3; }
};

// One used data point in the block order: first outer and inner basis index, the 4 + 4 basis values.
struct Row {
  int o = 0, i = 0;
  std::array<double, 4> bo{}, bi{};
  double w = 1.0, z = 0.0;
  std::size_t k = 0;  // index in the input
};

struct Score {
  bool factorised = false;
  double gcv = kInf, edf = 0.0, rss = 0.0;  // gcv stays +∞ when tr H ≥ n: the fit interpolates, GCV is undefined
};

// The penalised least-squares problem in block order ("outer" = the direction of the blocks).
class Problem {
 public:
  Problem(const Basis1D& outer, const Basis1D& inner, std::vector<Row> rows, int K, bool outer_is_s)
      : outer_(outer), inner_(inner), rows_(std::move(rows)), M_(outer.count()), m_(inner.count()) {
    const int N = M_ * m_;
    G_ = Eigen::MatrixXd::Zero(4 * m_, static_cast<Eigen::Index>(N));
    r_ = Eigen::VectorXd::Zero(N);
    for (const Row& p : rows_) {
      for (int a1 = 0; a1 < 4; ++a1) {
        for (int b1 = 0; b1 < 4; ++b1) {
          const double x1 = p.w * p.bo[a1] * p.bi[b1];
          r_((p.o + a1) * m_ + p.i + b1) += x1 * p.z;
          for (int a2 = 0; a2 <= a1; ++a2) {  // block (o+a1, o+a2) lies in panel o+a2, block row a1−a2
            for (int b2 = 0; b2 < 4; ++b2) {
              G_((a1 - a2) * m_ + p.i + b1, (p.o + a2) * m_ + p.i + b2) += x1 * p.bo[a2] * p.bi[b2];
            }
          }
        }
      }
    }
    // Which adaptivity block holds the centre of each difference; centres are Greville points x0 + (j − 1)h.
    const auto block_of = [&](const Basis1D& b, int j) {
      return std::clamp(static_cast<int>(std::floor(static_cast<double>(j - 1) / b.spans * K)), 0, K - 1);
    };
    const auto st_block = [&](int jo, int ji) {
      const int bo = block_of(outer_, jo), bi = block_of(inner_, ji);
      return outer_is_s ? bo * K + bi : bi * K + bo;
    };
    for (int jo = 1; jo + 1 < M_; ++jo) {
      for (int ji = 0; ji < m_; ++ji) outer_block_.push_back(st_block(jo, ji));
    }
    for (int jo = 0; jo < M_; ++jo) {
      for (int ji = 1; ji + 1 < m_; ++ji) inner_block_.push_back(st_block(jo, ji));
    }
    n_ = static_cast<double>(rows_.size());
  }

  [[nodiscard]] const std::vector<Row>& rows() const { return rows_; }
  [[nodiscard]] const Eigen::VectorXd& coefficients() const { return c_; }

  // trace(BᵀWB) / trace(P_outer + P_inner) with unit λ and weights.
  [[nodiscard]] double lambda_reference() const {
    double tg = 0.0;
    for (int J = 0; J < M_; ++J) tg += G_.block(0, J * m_, m_, m_).trace();
    const double po = 6.0 * std::max(0, M_ - 2) * m_ / std::pow(outer_.h, 4);
    const double pi = 6.0 * std::max(0, m_ - 2) * M_ / std::pow(inner_.h, 4);
    return tg / std::max(po + pi, std::numeric_limits<double>::min());
  }

  // Fits at (λ_outer, λ_inner, log-weights a) and scores it; the band of A⁻¹ stays for hat().
  Score fit(double lo, double li, const std::vector<double>& a) {
    assemble(lo, li, a);
    if (!factorise()) return {};
    solve();
    double rss = 0.0;
    for (const Row& p : rows_) {
      const double e = p.z - value(p);
      rss += p.w * e * e;
    }
    const double edf = trace_hat();
    Score sc;
    sc.factorised = true;
    sc.edf = edf;
    sc.rss = rss;
    if (!std::isfinite(edf) || !std::isfinite(rss) || edf >= n_) return sc;
    sc.gcv = n_ * rss / ((n_ - edf) * (n_ - edf));
    return sc;
  }

  // h_k = w_k b_kᵀ A⁻¹ b_k from the inverse band left by the last fit().
  [[nodiscard]] double hat(const Row& p) const {
    double h = 0.0;
    for (int a1 = 0; a1 < 4; ++a1) {
      for (int a2 = 0; a2 < 4; ++a2) {
        const int hi = std::max(a1, a2), lo = std::min(a1, a2);
        for (int b1 = 0; b1 < 4; ++b1) {
          for (int b2 = 0; b2 < 4; ++b2) {
            // Z_{(o+a1, i+b1), (o+a2, i+b2)}; the lower block of the pair is stored.
            const int row_in = a1 >= a2 ? p.i + b1 : p.i + b2, col_in = a1 >= a2 ? p.i + b2 : p.i + b1;
            const double z = Z_((hi - lo) * m_ + row_in, (p.o + lo) * m_ + col_in);
            h += p.bo[a1] * p.bi[b1] * p.bo[a2] * p.bi[b2] * z;
          }
        }
      }
    }
    return p.w * h;
  }

  [[nodiscard]] double value(const Row& p) const {
    double f = 0.0;
    for (int a = 0; a < 4; ++a) {
      const double* c = c_.data() + (p.o + a) * m_ + p.i;
      f += p.bo[a] * (p.bi[0] * c[0] + p.bi[1] * c[1] + p.bi[2] * c[2] + p.bi[3] * c[3]);
    }
    return f;
  }

 private:
  // Rows of panel J that exist: the diagonal block and up to three below it.
  [[nodiscard]] int panel_rows(int J) const { return std::min(4, M_ - J) * m_; }

  // L ← BᵀWB + P in panel form (panel J: blocks (J..J+3, J) stacked, m columns).
  void assemble(double lo, double li, const std::vector<double>& a) {
    L_ = G_;
    const double so = lo / std::pow(outer_.h, 4), si = li / std::pow(inner_.h, 4);
    const auto weight = [&](int blk) { return a.empty() ? 1.0 : std::exp(a[blk]); };
    static constexpr double d[3] = {1.0, -2.0, 1.0};
    std::size_t r = 0;
    for (int jo = 1; jo + 1 < M_; ++jo) {
      for (int ji = 0; ji < m_; ++ji, ++r) {
        const double w = so * weight(outer_block_[r]);
        for (int p = 0; p < 3; ++p) {
          for (int q = 0; q <= p; ++q) L_((p - q) * m_ + ji, (jo - 1 + q) * m_ + ji) += w * d[p] * d[q];
        }
      }
    }
    r = 0;
    for (int jo = 0; jo < M_; ++jo) {
      for (int ji = 1; ji + 1 < m_; ++ji, ++r) {
        const double w = si * weight(inner_block_[r]);
        for (int p = 0; p < 3; ++p) {
          for (int q = 0; q < 3; ++q) L_(ji - 1 + p, jo * m_ + ji - 1 + q) += w * d[p] * d[q];
        }
      }
    }
  }

  // Blocked left-looking band Cholesky in place on L_ (each diagonal block holds its lower-triangular factor).
  bool factorise() {
    for (int J = 0; J < M_; ++J) {
      const int h = panel_rows(J);
      auto PJ = L_.block(0, static_cast<Eigen::Index>(J) * m_, h, m_);
      for (int K = std::max(0, J - 3); K < J; ++K) {
        const int d = J - K, hk = std::min(h, panel_rows(K) - d * m_);
        const auto LJK = L_.block(d * m_, static_cast<Eigen::Index>(K) * m_, m_, m_);
        // The diagonal block only in its lower triangle, which is all the block Cholesky reads.
        PJ.topRows(m_).triangularView<Eigen::Lower>() -= LJK * LJK.transpose();
        if (hk > m_) {
          PJ.middleRows(m_, hk - m_).noalias() -=
              L_.block((d + 1) * m_, static_cast<Eigen::Index>(K) * m_, hk - m_, m_) * LJK.transpose();
        }
      }
      Eigen::LLT<Eigen::MatrixXd> llt(PJ.topRows(m_));
      if (llt.info() != Eigen::Success) return false;
      Ljj_ = llt.matrixL();
      if (!(Ljj_.diagonal().minCoeff() > 0.0) || !Ljj_.allFinite()) return false;
      PJ.topRows(m_) = Ljj_;
      if (h > m_) {
        auto S = PJ.bottomRows(h - m_);
        Ljj_.transpose().triangularView<Eigen::Upper>().solveInPlace<Eigen::OnTheRight>(S);
      }
    }
    return true;
  }

  void solve() {
    c_ = r_;
    for (int J = 0; J < M_; ++J) {
      const int h = panel_rows(J);
      auto cJ = c_.segment(static_cast<Eigen::Index>(J) * m_, m_);
      L_.block(0, static_cast<Eigen::Index>(J) * m_, m_, m_).triangularView<Eigen::Lower>().solveInPlace(cJ);
      if (h > m_) {
        c_.segment(static_cast<Eigen::Index>(J + 1) * m_, h - m_).noalias() -=
            L_.block(m_, static_cast<Eigen::Index>(J) * m_, h - m_, m_) * cJ;
      }
    }
    for (int J = M_ - 1; J >= 0; --J) {
      const int h = panel_rows(J);
      auto cJ = c_.segment(static_cast<Eigen::Index>(J) * m_, m_);
      if (h > m_) {
        cJ.noalias() -= L_.block(m_, static_cast<Eigen::Index>(J) * m_, h - m_, m_).transpose() *
                        c_.segment(static_cast<Eigen::Index>(J + 1) * m_, h - m_);
      }
      const auto Ljj = L_.block(0, static_cast<Eigen::Index>(J) * m_, m_, m_);
      Ljj.transpose().triangularView<Eigen::Upper>().solveInPlace(cJ);
    }
  }

  // Block Takahashi recurrence into Z_ (same panel layout as L_); returns tr(A⁻¹ BᵀWB).
  double trace_hat() {
    Z_.resize(L_.rows(), L_.cols());
    double tr = 0.0;
    const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(m_, m_);
    for (int J = M_ - 1; J >= 0; --J) {
      const Eigen::Index col = static_cast<Eigen::Index>(J) * m_;
      const int R = panel_rows(J) - m_;  // rows below the diagonal block
      Linv_ = L_.block(0, col, m_, m_).triangularView<Eigen::Lower>().solve(I);
      Zjj_.noalias() = Linv_.transpose() * Linv_;
      if (R > 0) {
        U_.noalias() = L_.block(m_, col, R, m_) * Linv_.triangularView<Eigen::Lower>();
        // W = Z over the block rows and columns J+1 .. J+R/m, gathered from their panels.
        W_.resize(R, R);
        const int nb = R / m_;
        for (int q = 0; q < nb; ++q) {
          for (int p = q; p < nb; ++p) {
            const auto blk = Z_.block((p - q) * m_, static_cast<Eigen::Index>(J + 1 + q) * m_, m_, m_);
            W_.block(p * m_, q * m_, m_, m_) = blk;
            if (p != q) W_.block(q * m_, p * m_, m_, m_) = blk.transpose();
          }
        }
        auto ZR = Z_.block(m_, col, R, m_);
        ZR.noalias() = -W_ * U_;
        Zjj_.noalias() -= U_.transpose() * ZR;
        tr += 2.0 * ZR.cwiseProduct(G_.block(m_, col, R, m_)).sum();
      }
      Z_.block(0, col, m_, m_) = 0.5 * (Zjj_ + Zjj_.transpose());
      tr += Z_.block(0, col, m_, m_).cwiseProduct(G_.block(0, col, m_, m_)).sum();
    }
    return tr;
  }

  Basis1D outer_, inner_;
  std::vector<Row> rows_;
  int M_, m_;  // blocks, and coefficients in a block
  double n_ = 0.0;
  Eigen::MatrixXd G_, L_, Z_;  // panels of BᵀWB, of the Cholesky factor, of A⁻¹ (lower block band)
  Eigen::VectorXd r_, c_;      // BᵀWz and the coefficients
  std::vector<int> outer_block_, inner_block_;
  Eigen::MatrixXd Ljj_, Linv_, Zjj_, U_, W_;  // scratch
};

// Minimises f on [lo, hi] by golden section (f assumed unimodal there); returns the best point seen, including
// `x_now` whose value is `f_now`.
template <class F>
double golden(F&& f, double lo, double hi, int iterations, double x_now, double& f_now) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double best_x = x_now, best_f = f_now;
  const auto consider = [&](double x, double fx) {
    if (fx < best_f) best_f = fx, best_x = x;
  };
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  consider(x1, f1);
  consider(x2, f2);
  for (int it = 0; it < iterations; ++it) {
    if (f1 <= f2) {
      hi = x2, x2 = x1, f2 = f1;
      x1 = hi - g * (hi - lo);
      f1 = f(x1);
      consider(x1, f1);
    } else {
      lo = x1, x1 = x2, f1 = f2;
      x2 = lo + g * (hi - lo);
      f2 = f(x2);
      consider(x2, f2);
    }
  }
  f_now = best_f;
  return best_x;
}

// The weighted least-squares bilinear α + βu + γv + δuv (u, v the coordinates scaled to [−1, 1]), or nothing when
// the used points do not fix it (all equal, all on a line): then the penalty's null space is free.
// The smoother is linear and leaves this null space alone, so fitting z minus the bilinear and adding it back is
// the same fit; it spares the solve a large null-space part whose rounding, multiplied by a large λ, would show.
std::optional<Eigen::Vector4d> bilinear_trend(const std::vector<Row>& rows,
                                              const std::vector<std::array<double, 2>>& uv) {
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(4, 4);
  Eigen::VectorXd r = Eigen::VectorXd::Zero(4);
  double wsum = 0.0;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    const Eigen::Vector4d b(1.0, uv[j][0], uv[j][1], uv[j][0] * uv[j][1]);
    N += rows[j].w * b * b.transpose();
    r += rows[j].w * rows[j].z * b;
    wsum += rows[j].w;
  }
  N /= wsum, r /= wsum;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(N);
  const Eigen::VectorXd ev = eig.eigenvalues();
  if (eig.info() != Eigen::Success || !(ev(0) > 1e-10 * ev(3))) return std::nullopt;
  return Eigen::Vector4d(eig.eigenvectors() * (ev.cwiseInverse().asDiagonal() * (eig.eigenvectors().transpose() * r)));
}

}  // namespace

SmootherResult smooth(std::span<const double> s, std::span<const double> t, std::span<const double> z,
                      const SmootherOptions& o, std::span<const double> w) {
  if (!(o.s1 > o.s0) || !(o.t1 > o.t0) || !std::isfinite(o.s1 - o.s0) || !std::isfinite(o.t1 - o.t0) ||
      o.spans_s < 1 || o.spans_t < 1 || o.adaptive_blocks < 1 || s.size() != t.size() || s.size() != z.size() ||
      (!w.empty() && w.size() != s.size())) {
    throw std::invalid_argument("reference::smooth: malformed rectangle, spans or input sizes");
  }
  SmootherResult res;
  res.s0 = o.s0, res.s1 = o.s1, res.t0 = o.t0, res.t1 = o.t1;
  res.spans_s = o.spans_s, res.spans_t = o.spans_t;
  res.hat.assign(s.size(), 0.0);

  const Basis1D bs{o.s0, (o.s1 - o.s0) / o.spans_s, o.spans_s}, bt{o.t0, (o.t1 - o.t0) / o.spans_t, o.spans_t};
  const bool outer_is_s = bs.count() >= bt.count();
  const Basis1D& outer = outer_is_s ? bs : bt;
  const Basis1D& inner = outer_is_s ? bt : bs;

  std::vector<Row> rows;
  std::vector<std::array<double, 2>> uv;  // coordinates scaled to [−1, 1], for the trend
  const double tol_s = 1e-9 * (o.s1 - o.s0), tol_t = 1e-9 * (o.t1 - o.t0);
  for (std::size_t k = 0; k < s.size(); ++k) {
    const double wk = w.empty() ? 1.0 : w[k];
    if (!(wk > 0.0) || !std::isfinite(wk) || !std::isfinite(z[k]) || !(s[k] >= o.s0 - tol_s) ||
        !(s[k] <= o.s1 + tol_s) || !(t[k] >= o.t0 - tol_t) || !(t[k] <= o.t1 + tol_t)) {
      continue;
    }
    Row p;
    p.w = wk, p.z = z[k], p.k = k;
    const double xo = outer_is_s ? s[k] : t[k], xi = outer_is_s ? t[k] : s[k];
    p.o = outer.eval(xo, p.bo.data(), nullptr);
    p.i = inner.eval(xi, p.bi.data(), nullptr);
    rows.push_back(p);
    uv.push_back({2.0 * (s[k] - o.s0) / (o.s1 - o.s0) - 1.0, 2.0 * (t[k] - o.t0) / (o.t1 - o.t0) - 1.0});
  }
  res.points_used = rows.size();
  if (rows.size() < 5) return res;
  const std::optional<Eigen::Vector4d> trend = bilinear_trend(rows, uv);
  if (!trend) return res;
  const Eigen::Vector4d& th = *trend;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    rows[j].z -= th(0) + th(1) * uv[j][0] + th(2) * uv[j][1] + th(3) * uv[j][0] * uv[j][1];
  }

  const int K = o.adaptive_blocks;
  Problem prob(outer, inner, std::move(rows), K, outer_is_s);
  const double lref = prob.lambda_reference();
  res.lambda_reference = lref;

  // Search in x = log10(λ/λ_ref) per direction (s, t); the problem wants (outer, inner).
  std::vector<double> a;
  const auto score = [&](double xs, double xt) {
    const double ls = lref * std::pow(10.0, xs), lt = lref * std::pow(10.0, xt);
    return prob.fit(outer_is_s ? ls : lt, outer_is_s ? lt : ls, a);
  };

  double xs = 0.0, xt = 0.0, best = kInf;
  if (o.lambda_s > 0.0 && o.lambda_t > 0.0) {
    xs = std::log10(o.lambda_s / lref), xt = std::log10(o.lambda_t / lref);
    const Score fixed = score(xs, xt);
    if (!fixed.factorised) {
      res.status = SmootherStatus::NumericalError;
      return res;
    }
    best = fixed.gcv;
  } else {
    // Coarse grid over 12 decades: from near interpolation (wavelengths below a span survive) to a near-bilinear
    // fit; 1 decade apart, so that GCV's basin, typically several decades wide, is not missed.
    constexpr int kGrid = 13;
    constexpr double kLo = -5.0, kStep = 1.0;
    for (int i = 0; i < kGrid; ++i) {
      for (int j = 0; j < kGrid; ++j) {
        const double g = score(kLo + i * kStep, kLo + j * kStep).gcv;
        if (g < best) best = g, xs = kLo + i * kStep, xt = kLo + j * kStep;
      }
    }
    if (!std::isfinite(best)) {
      res.status = SmootherStatus::NumericalError;
      return res;
    }
    // Coordinate search: golden section along each direction between the grid neighbours, then a narrower pass.
    for (const double half : {1.0, 0.3}) {
      xs = golden([&](double x) { return score(x, xt).gcv; }, xs - half, xs + half, 8, xs, best);
      xt = golden([&](double x) { return score(xs, x).gcv; }, xt - half, xt + half, 8, xt, best);
    }
  }

  if (o.adaptive) {
    // Log-weights by coordinate descent on GCV, λ fixed; a block's new weight is kept only if GCV drops, so the
    // adaptive fit never scores worse than the plain one. Bounded to e^{±7} ≈ 10^{±3}.
    a.assign(static_cast<std::size_t>(K) * K, 0.0);
    constexpr double kBound = 7.0;
    for (int sweep = 0; sweep < o.adaptive_sweeps; ++sweep) {
      for (std::size_t blk = 0; blk < a.size(); ++blk) {
        const double now = a[blk];
        const double lo = sweep == 0 ? -kBound : std::max(-kBound, now - 1.5);
        const double hi = sweep == 0 ? kBound : std::min(kBound, now + 1.5);
        a[blk] = golden(
            [&](double x) {
              a[blk] = x;
              return score(xs, xt).gcv;
            },
            lo, hi, sweep == 0 ? 8 : 6, now, best);
      }
    }
    res.log_weights = a;
  }

  const Score final_score = score(xs, xt);
  if (!final_score.factorised) {
    res.status = SmootherStatus::NumericalError;
    return res;
  }
  res.lambda_s = lref * std::pow(10.0, xs);
  res.lambda_t = lref * std::pow(10.0, xt);
  res.edf = final_score.edf;
  res.gcv = final_score.gcv;
  const double n = static_cast<double>(prob.rows().size());
  res.sigma = final_score.edf < n ? std::sqrt(final_score.rss / (n - final_score.edf)) : 0.0;
  for (const Row& p : prob.rows()) res.hat[p.k] = prob.hat(p);

  const int Ns = bs.count(), Nt = bt.count();
  res.coefficients.assign(static_cast<std::size_t>(Ns) * Nt, 0.0);
  const Eigen::VectorXd& c = prob.coefficients();
  for (int i = 0; i < Ns; ++i) {
    // The trend's own coefficients: its values at the Greville points, exact for a bilinear function.
    const double u = 2.0 * (i - 1) / o.spans_s - 1.0;
    for (int j = 0; j < Nt; ++j) {
      const double v = 2.0 * (j - 1) / o.spans_t - 1.0;
      res.coefficients[static_cast<std::size_t>(i) * Nt + j] =
          (outer_is_s ? c(i * Nt + j) : c(j * Ns + i)) + th(0) + th(1) * u + th(2) * v + th(3) * u * v;
    }
  }
  if (!c.allFinite() || !std::isfinite(res.sigma)) {
    res.coefficients.clear();
    res.status = SmootherStatus::NumericalError;
    return res;
  }
  res.status = SmootherStatus::OK;
  return res;
}

SmootherValue evaluate(const SmootherResult& f, double s, double t) {
  const int Ns = f.spans_s + 3, Nt = f.spans_t + 3;
  if (f.spans_s < 1 || f.spans_t < 1 || f.coefficients.size() != static_cast<std::size_t>(Ns) * Nt) {
    return {kNaN, kNaN, kNaN};
  }
  const Basis1D bs{f.s0, (f.s1 - f.s0) / f.spans_s, f.spans_s}, bt{f.t0, (f.t1 - f.t0) / f.spans_t, f.spans_t};
  double vs[4], ds[4], vt[4], dt[4];
  const int is = bs.eval(s, vs, ds), it = bt.eval(t, vt, dt);
  SmootherValue out;
  for (int a = 0; a < 4; ++a) {
    double row_v = 0.0, row_d = 0.0;
    for (int b = 0; b < 4; ++b) {
      const double c = f.coefficients[static_cast<std::size_t>(is + a) * Nt + it + b];
      row_v += vt[b] * c;
      row_d += dt[b] * c;
    }
    out.value += vs[a] * row_v;
    out.ds += ds[a] * row_v;
    out.dt += vs[a] * row_d;
  }
  return out;
}

}  // namespace probecomp::reference
