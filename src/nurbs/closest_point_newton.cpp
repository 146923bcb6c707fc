#include "closest_point_newton.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace probecomp::nurbs {

const char* to_string(ClosestPointStatus s) {
  switch (s) {
    case ClosestPointStatus::Converged: return "converged";
    case ClosestPointStatus::OnBoundary: return "on-boundary";
    case ClosestPointStatus::NotConverged: return "not-converged";
    case ClosestPointStatus::NumericalError: return "numerical-error";
  }
  return "unknown";
}

// ---------------------------------------------------------------------------------------------------------
// Local Newton iteration

namespace detail {

namespace {

// Cosine below which a stalled iteration (no further decrease of f possible in double precision) still
// counts as a minimum: rounding in S − P limits the attainable cosine to about 1e-16·|P| / |S − P|.
constexpr double kStallCosine = 1e-7;
// Backtracking halvings before a step is declared unable to decrease f.
constexpr int kMaxHalvings = 30;
// Newton's last step is also taken without a new evaluation when the steps so far show that the one after it would
// be below the tolerance: with quadratic convergence e' ≈ K e², and two full steps σ₀, σ₁ give K ≈ σ₁/σ₀², so the
// step after σ₁ is about σ₁³/σ₀². Asked to be a hundredth of the tolerance (1e-10 mm), with σ₁ at most 1e-6 mm.
// Should the convergence be only linear (Gauss–Newton), the step after is σ₁²/σ₀, which the two conditions still
// hold to (σ₁²/σ₀)² ≤ 1e-10 σ₁ ≤ (1e-8)²: the tolerance. The landing point is the second-order Taylor polynomial
// (error of order σ₁³ times the third derivatives) and the tangents there its first-order one (error of order σ₁²
// times the curvature). It spares one evaluation where Newton starts some way off: a contact point's foot on the
// nominal face, some 30 µm from the registration's (u, v), takes two evaluations instead of three.
constexpr double kPredictedErrorFraction = 1e-2;
constexpr double kMaxPredictedLastStep = 1e-6;  // mm

// Near the minimum f is flat: a tangential move of 1e-8 mm changes f by about 1e-16 mm², below its rounding.
// A Newton step is accepted unless it increases f by more than rounding, so the quadratic convergence can
// finish instead of stalling a few digits short. f = |S − P|² is computed from coordinates of size |P|, so
// its rounding is about 2·|S − P|·(ε·|P|) per coordinate: absolute, not relative to f.
double rounding_of_f(const Point3& P, const Iterate& it) {
  constexpr double eps = std::numeric_limits<double>::epsilon();
  return 16.0 * eps * (P.norm() + it.d.S.norm()) * std::sqrt(it.f) + 4.0 * eps * it.f;
}

}  // namespace

Iterate make_iterate(const Surface& s, const Point3& P, double u, double v, KnotSpans spans) {
  Iterate it{u, v, derivatives_d2(s, u, v, spans), Vector3::Zero(), 0.0};
  it.r = it.d.S - P;
  it.f = it.r.squaredNorm();
  return it;
}

namespace {

// Which parameters sit on a domain edge with the gradient pushing them outwards (the active set).
struct ActiveSet {
  bool u = false;
  bool v = false;
};

ActiveSet active_set(const Domain& dom, const Iterate& it, double gu, double gv) {
  return {(it.u <= dom.u0 && gu > 0.0) || (it.u >= dom.u1 && gu < 0.0),
          (it.v <= dom.v0 && gv > 0.0) || (it.v >= dom.v1 && gv < 0.0)};
}

}  // namespace

// How flat f is: the smallest λ with det(H − λ J) = 0. 1 for a plane; it falls towards 0 as the query nears a
// centre of curvature (a focal point), where f is flat along some direction and a second minimum may lie close by.
double flatness(const Hessian& h) {
  const double a = h.Juu * h.Jvv - h.Juv * h.Juv;
  if (!(a > 0.0)) return 0.0;
  const double b = h.Huu * h.Jvv + h.Hvv * h.Juu - 2.0 * h.Huv * h.Juv;
  const double c = h.Huu * h.Hvv - h.Huv * h.Huv;
  return (b - std::sqrt(std::max(0.0, b * b - 4.0 * a * c))) / (2.0 * a);
}

namespace {

// Newton step on the free parameters; Gauss–Newton (Hessian without the curvature terms, always positive
// semi-definite) where the full Hessian is not positive definite, e.g. far from a concave region's centre.
[[gnu::always_inline]] inline std::array<double, 2> newton_step(const Hessian& h, double gu, double gv, ActiveSet active) {
  const auto [Juu, Juv, Jvv, Huu, Huv, Hvv] = h;
  auto solve1 = [](double h, double j, double g) {
    if (h > 0.0) return -g / h;
    if (j > 0.0) return -g / j;
    return 0.0;
  };
  if (active.u) return {0.0, solve1(Hvv, Jvv, gv)};
  if (active.v) return {solve1(Huu, Juu, gu), 0.0};
  const double det = Huu * Hvv - Huv * Huv;
  if (Huu > 0.0 && det > 1e-14 * Huu * Hvv) {
    return {(-gu * Hvv + gv * Huv) / det, (gu * Huv - gv * Huu) / det};
  }
  const double detJ = Juu * Jvv - Juv * Juv;
  if (Juu > 0.0 && detJ > 1e-14 * Juu * Jvv) {
    return {(-gu * Jvv + gv * Juv) / detJ, (gu * Juv - gv * Juu) / detJ};
  }
  // Tangents parallel (a pole): move along each tangent separately.
  return {solve1(Huu, Juu, gu), solve1(Hvv, Jvv, gv)};
}

// Newton steps on the surface's second-order Taylor polynomial about `c` (at (u0, v0)), kept inside `dom`: no
// evaluation. Its foot is within the polynomial's third-order error of the surface's (a cell is small against the
// curvature radii), where a single Newton step from (u0, v0) is off by the square of the start's distance.
// Two steps: the polynomial's own foot is then nearer than that error, and Newton on the surface takes as many
// steps after them as after four (BM_ClosestPoint: 2.513 against 2.509 a query; one step leaves 3.13). Each step
// is a chain of dependent operations with a division in it: two fewer made the benchmark 7–9 % faster.
constexpr int kTaylorSteps = 2;
Iterate taylor_foot(const SurfaceD2& c, const Point3& P, double u0, double v0, const Domain& dom) {
  Iterate m{u0, v0, c, c.S - P, (c.S - P).squaredNorm(), true};
  double a = 0.0, b = 0.0;
  for (int k = 0; k < kTaylorSteps; ++k) {
    const double gu = m.r.dot(m.d.Su), gv = m.r.dot(m.d.Sv);
    const auto [du, dv] = newton_step(hessian(m), gu, gv, active_set(dom, m, gu, gv));
    a = std::clamp(u0 + a + du, dom.u0, dom.u1) - u0;
    b = std::clamp(v0 + b + dv, dom.v0, dom.v1) - v0;
    m.u = u0 + a;
    m.v = v0 + b;
    m.d.S = c.S + a * c.Su + b * c.Sv + (0.5 * a * a) * c.Suu + (a * b) * c.Suv + (0.5 * b * b) * c.Svv;
    m.d.Su = c.Su + a * c.Suu + b * c.Suv;
    m.d.Sv = c.Sv + a * c.Suv + b * c.Svv;
    m.r = m.d.S - P;
    m.f = m.r.squaredNorm();
  }
  return m;
}

}  // namespace

// Projected Newton inside `dom`; `spans` are the knot spans of `dom` when it lies in one (a cell), else -1.
// `flat`, if given, receives flatness() at the last iterate. `start`, if given, is the surface at (u0, v0), inside
// `dom`, with its derivatives rounded to floats (a seed cell's centre): Newton starts from the foot of its Taylor
// polynomial (taylor_foot), or where the surface is farther there than at (u0, v0), takes its first step from the
// stored derivatives without an evaluation. Rounded derivatives make either slightly other than exact, which the
// steps after them correct.
ClosestPointResult refine_in(const Surface& s, const Point3& P, double u0, double v0, const Domain& dom,
                             int max_iterations, KnotSpans spans, double* flat, const SurfaceD2* start) {
  ClosestPointResult result;
  Iterate it;
  if (start != nullptr) {
    it = {u0, v0, *start, start->S - P, 0.0, true};
    it.f = it.r.squaredNorm();
    // Newton on the surface starts from the Taylor polynomial's foot where the surface is no farther there than at
    // the centre (else from the centre, its first step from the stored derivatives). BM_ClosestPoint: Newton steps
    // 4.32 → 2.51 a query, for one evaluation at the polynomial's foot a search.
    const Iterate foot = taylor_foot(*start, P, u0, v0, dom);
    Iterate at_foot = make_iterate(s, P, foot.u, foot.v, spans);
    if (at_foot.f <= it.f + rounding_of_f(P, it)) it = std::move(at_foot);
  } else {
    it = make_iterate(s, P, std::clamp(u0, dom.u0, dom.u1), std::clamp(v0, dom.v0, dom.v1), spans);
  }

  // The Hessian of the last Newton step, for flatness() at the end: one step before the final iterate at most,
  // which is close enough for a test of whether the distance is flat there.
  Hessian h{};
  bool have_h = false;
  auto report_flatness = [&] {
    result.flatness = flatness(have_h ? h : hessian(it));
    if (flat != nullptr) *flat = result.flatness;
  };
  auto finish = [&](ClosestPointStatus status) {
    if (it.approximate) {
      it = make_iterate(s, P, it.u, it.v, spans);
      have_h = false;
    }
    report_flatness();
    result.status = status;
    result.u = it.u;
    result.v = it.v;
    result.point = it.d.S;
    result.distance = std::sqrt(it.f);
    result.Su = it.d.Su;
    result.Sv = it.d.Sv;
    result.Suu = it.d.Suu;
    result.Suv = it.d.Suv;
    result.Svv = it.d.Svv;
    return result;
  };

  double previous_step = 0.0;  // the last full Newton step's length (mm), 0 until one was taken without halving
  for (int k = 0; k < max_iterations; ++k) {
    if (!std::isfinite(it.f) || !it.d.Su.allFinite() || !it.d.Sv.allFinite()) {
      return finish(ClosestPointStatus::NumericalError);
    }
    const double dist = std::sqrt(it.f);
    if (dist == 0.0) return finish(ClosestPointStatus::Converged);
    const double gu = it.r.dot(it.d.Su);
    const double gv = it.r.dot(it.d.Sv);
    const ActiveSet active = active_set(dom, it, gu, gv);
    const double cos_u = std::abs(gu) / (it.d.Su.norm() * dist);
    const double cos_v = std::abs(gv) / (it.d.Sv.norm() * dist);
    const bool u_done = active.u || !(cos_u > kClosestPointZeroCosine);
    const bool v_done = active.v || !(cos_v > kClosestPointZeroCosine);
    const auto converged_status = (active.u || active.v) ? ClosestPointStatus::OnBoundary : ClosestPointStatus::Converged;
    if (u_done && v_done) return finish(converged_status);

    ++result.iterations;
    h = hessian(it);
    have_h = true;
    auto [du, dv] = newton_step(h, gu, gv, active);
    // The predicted step's length decides only when it is at most kMaxPredictedLastStep (the larger tolerance):
    // its square root is taken only then (its square a little above that bound's, so that no rounding of the root
    // could have decided otherwise).
    const double predicted_sq = (du * it.d.Su + dv * it.d.Sv).squaredNorm();
    bool next_below_tolerance = false;
    if (predicted_sq <= 1.001 * kMaxPredictedLastStep * kMaxPredictedLastStep) {
      const double predicted = std::sqrt(predicted_sq);
      next_below_tolerance =
          predicted < kClosestPointStepTolerance ||
          (previous_step > 0.0 && predicted <= kMaxPredictedLastStep &&
           predicted * predicted * predicted <= kPredictedErrorFraction * kClosestPointStepTolerance * previous_step * previous_step);
    }
    if (next_below_tolerance && !it.approximate && it.d.Suu.allFinite() && it.d.Suv.allFinite() &&
        it.d.Svv.allFinite()) {
      // The last, tiny step is taken without the derivatives it would need only to start another: Newton's
      // error after it is of the order of its square. The point where the step lands is the Taylor polynomial of
      // second order from the derivatives at hand: its error is of the third order in a step under 1e-8 mm (times
      // the third derivatives' size: far below rounding), and it spares an evaluation.
      const double u1 = std::clamp(it.u + du, dom.u0, dom.u1), v1 = std::clamp(it.v + dv, dom.v0, dom.v1);
      const double a = u1 - it.u, b = v1 - it.v;
      const Point3 S1 = it.d.S + a * it.d.Su + b * it.d.Sv + (0.5 * a * a) * it.d.Suu + (a * b) * it.d.Suv +
                        (0.5 * b * b) * it.d.Svv;
      const double dist1 = (S1 - P).norm();
      if (!(dist1 <= dist + kClosestPointStepTolerance)) return finish(converged_status);
      report_flatness();
      result.status = converged_status;
      result.u = u1;
      result.v = v1;
      result.point = S1;
      result.distance = dist1;
      result.Su = it.d.Su + a * it.d.Suu + b * it.d.Suv;
      result.Sv = it.d.Sv + a * it.d.Suv + b * it.d.Svv;
      result.Suu = it.d.Suu;
      result.Suv = it.d.Suv;
      result.Svv = it.d.Svv;
      return result;
    }
    Iterate next = it;
    bool decreased = false;
    int halving = 0;
    for (; halving <= kMaxHalvings; ++halving) {
      next = make_iterate(s, P, std::clamp(it.u + du, dom.u0, dom.u1), std::clamp(it.v + dv, dom.v0, dom.v1), spans);
      if (next.f <= it.f + rounding_of_f(P, it)) {
        decreased = true;
        break;
      }
      du *= 0.5;
      dv *= 0.5;
    }
    if (!decreased) {
      // No representable step decreases f: we are at the minimum to rounding, or stuck at a saddle.
      const bool stalled_ok = (active.u || cos_u <= kStallCosine) && (active.v || cos_v <= kStallCosine);
      return finish(stalled_ok ? converged_status : ClosestPointStatus::NotConverged);
    }
    const double step = ((next.u - it.u) * it.d.Su + (next.v - it.v) * it.d.Sv).norm();
    // Only a full, unclamped step tells the rate of convergence.
    const bool full = halving == 0 && next.u == it.u + du && next.v == it.v + dv && !it.approximate;
    previous_step = full ? step : 0.0;
    it = next;
    if (step < kClosestPointStepTolerance) {
      const double g2u = it.r.dot(it.d.Su);
      const double g2v = it.r.dot(it.d.Sv);
      const ActiveSet a2 = active_set(dom, it, g2u, g2v);
      return finish((a2.u || a2.v) ? ClosestPointStatus::OnBoundary : ClosestPointStatus::Converged);
    }
  }
  return finish(ClosestPointStatus::NotConverged);
}

}  // namespace detail

ClosestPointResult refine_closest_point(const Surface& s, const Point3& P, double u0, double v0, int max_iterations) {
  return detail::refine_in(s, P, u0, v0, s.domain(), max_iterations, {});
}

ClosestPointResult refine_closest_point_in(const Surface& s, const Point3& P, double u0, double v0, const Domain& dom,
                                           int max_iterations) {
  return detail::refine_in(s, P, u0, v0, dom, max_iterations, {});
}

}  // namespace probecomp::nurbs
