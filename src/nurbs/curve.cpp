#include "probecomp/nurbs/curve.hpp"

#include <string>

#include "probecomp/nurbs/basis.hpp"
#include "probecomp/nurbs/knot_insertion.hpp"

namespace probecomp::nurbs {

namespace {
void check_weights(const std::vector<HomogeneousPoint>& Pw) {
  for (std::size_t i = 0; i < Pw.size(); ++i) {
    if (!(Pw[i].w() > 0.0) || !Pw[i].allFinite()) {
      throw InvalidGeometry("control point " + std::to_string(i) + " has a non-positive or non-finite weight");
    }
  }
}
}  // namespace

Curve::Curve(KnotVector U, const std::vector<Point3>& P, const std::vector<double>& w) : U_(std::move(U)) {
  if (static_cast<int>(P.size()) != U_.num_basis()) {
    throw InvalidGeometry("curve has " + std::to_string(P.size()) + " control points but its knot vector needs " +
                          std::to_string(U_.num_basis()));
  }
  if (!w.empty() && w.size() != P.size()) throw InvalidGeometry("curve weights and control points differ in number");
  Pw_.resize(P.size());
  for (std::size_t i = 0; i < P.size(); ++i) {
    const double wi = w.empty() ? 1.0 : w[i];
    Pw_[i] << wi * P[i], wi;
  }
  check_weights(Pw_);
}

Curve::Curve(KnotVector U, std::vector<HomogeneousPoint> Pw) : U_(std::move(U)), Pw_(std::move(Pw)) {
  if (static_cast<int>(Pw_.size()) != U_.num_basis()) {
    throw InvalidGeometry("curve has " + std::to_string(Pw_.size()) +
                          " control points but its knot vector needs " + std::to_string(U_.num_basis()));
  }
  check_weights(Pw_);
}

Point3 Curve::control_point(int i) const {
  const auto& q = Pw_[i];
  return q.head<3>() / q.w();
}

Point3 evaluate(const Curve& c, double u) {
  const int p = c.degree();
  const int span = c.knots().find_span(u);
  double N[kMaxDegree + 1];
  basis_functions(c.knots(), span, u, N);
  HomogeneousPoint Cw = HomogeneousPoint::Zero();
  for (int j = 0; j <= p; ++j) Cw += N[j] * c.homogeneous()[span - p + j];
  return Cw.head<3>() / Cw.w();
}

CurveD2 derivatives_d2(const Curve& c, double u) {
  const int p = c.degree();
  const int span = c.knots().find_span(u);
  double ders[3 * (kMaxDegree + 1)];
  basis_function_derivatives(c.knots(), span, u, 2, ders);
  HomogeneousPoint A[3] = {HomogeneousPoint::Zero(), HomogeneousPoint::Zero(), HomogeneousPoint::Zero()};
  for (int k = 0; k <= 2; ++k) {
    for (int j = 0; j <= p; ++j) A[k] += ders[k * (p + 1) + j] * c.homogeneous()[span - p + j];
  }
  // A4.2 written out for k <= 2: C^(k) = (A^(k) - Σ_{i=1..k} C(k,i) w^(i) C^(k-i)) / w.
  const double w = A[0].w();
  CurveD2 r;
  r.C = A[0].head<3>() / w;
  r.Cu = (A[1].head<3>() - A[1].w() * r.C) / w;
  r.Cuu = (A[2].head<3>() - 2.0 * A[1].w() * r.Cu - A[2].w() * r.C) / w;
  return r;
}

Curve insert_knot(const Curve& c, double u, int r) {
  auto [U, Pw] = insert_knot_homogeneous(c.knots(), c.homogeneous(), u, r);
  return Curve(std::move(U), std::move(Pw));
}

}  // namespace probecomp::nurbs
