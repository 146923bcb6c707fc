#include "probecomp/occt/convert.hpp"

#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>

namespace probecomp::occt {

namespace {

// OpenCASCADE stores distinct knots and multiplicities; the kernel stores the flat knot vector.
void split_knots(const nurbs::KnotVector& U, TColStd_Array1OfReal& knots, TColStd_Array1OfInteger& mults) {
  std::vector<double> distinct;
  std::vector<int> mult;
  for (double k : U.knots()) {
    if (distinct.empty() || k != distinct.back()) {
      distinct.push_back(k);
      mult.push_back(1);
    } else {
      ++mult.back();
    }
  }
  knots.Resize(1, static_cast<int>(distinct.size()), false);
  mults.Resize(1, static_cast<int>(distinct.size()), false);
  for (std::size_t i = 0; i < distinct.size(); ++i) {
    knots.SetValue(static_cast<int>(i) + 1, distinct[i]);
    mults.SetValue(static_cast<int>(i) + 1, mult[i]);
  }
}

nurbs::KnotVector flat_knots(const TColStd_Array1OfReal& knots, const TColStd_Array1OfInteger& mults, int degree) {
  std::vector<double> U;
  for (int i = knots.Lower(); i <= knots.Upper(); ++i) U.insert(U.end(), mults(i), knots(i));
  return nurbs::KnotVector(std::move(U), degree);
}

}  // namespace

Handle(Geom_BSplineSurface) to_occt(const nurbs::Surface& s) {
  const int nu = s.num_u();
  const int nv = s.num_v();
  TColgp_Array2OfPnt poles(1, nu, 1, nv);
  TColStd_Array2OfReal weights(1, nu, 1, nv);
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const Point3 P = s.control_point(i, j);
      poles.SetValue(i + 1, j + 1, gp_Pnt(P.x(), P.y(), P.z()));
      weights.SetValue(i + 1, j + 1, s.weight(i, j));
    }
  }
  TColStd_Array1OfReal uk(1, 1), vk(1, 1);
  TColStd_Array1OfInteger um(1, 1), vm(1, 1);
  split_knots(s.U(), uk, um);
  split_knots(s.V(), vk, vm);
  return new Geom_BSplineSurface(poles, weights, uk, vk, um, vm, s.p(), s.q());
}

nurbs::Surface from_occt(const Handle(Geom_BSplineSurface)& in) {
  Handle(Geom_BSplineSurface) s = in;
  // The kernel's knot vectors are clamped (end knots of multiplicity p + 1). A periodic surface is made
  // non-periodic, and one whose end knots are fewer (unclamped: a file's uniform knots, or OpenCASCADE's
  // conversion of a surface of revolution, NIST STC-06's turned faces) is cut to its parameter range, which
  // inserts the end knots p + 1 times (knot insertion: the same surface, not an approximation).
  auto unclamped = [](const Handle(Geom_BSplineSurface)& b) {
    return b->UMultiplicity(1) < b->UDegree() + 1 || b->UMultiplicity(b->NbUKnots()) < b->UDegree() + 1 ||
           b->VMultiplicity(1) < b->VDegree() + 1 || b->VMultiplicity(b->NbVKnots()) < b->VDegree() + 1;
  };
  if (s->IsUPeriodic() || s->IsVPeriodic() || unclamped(s)) {
    s = Handle(Geom_BSplineSurface)::DownCast(in->Copy());
    if (s->IsUPeriodic()) s->SetUNotPeriodic();
    if (s->IsVPeriodic()) s->SetVNotPeriodic();
    if (unclamped(s)) {
      double u0 = 0.0, u1 = 0.0, v0 = 0.0, v1 = 0.0;
      s->Bounds(u0, u1, v0, v1);
      s->Segment(u0, u1, v0, v1);
    }
  }
  const int nu = s->NbUPoles();
  const int nv = s->NbVPoles();
  std::vector<HomogeneousPoint> Pw(static_cast<std::size_t>(nu) * nv);
  for (int i = 1; i <= nu; ++i) {
    for (int j = 1; j <= nv; ++j) {
      const gp_Pnt P = s->Pole(i, j);
      const double w = s->Weight(i, j);
      Pw[(i - 1) * nv + (j - 1)] << w * P.X(), w * P.Y(), w * P.Z(), w;
    }
  }
  TColStd_Array1OfReal uk(1, s->NbUKnots()), vk(1, s->NbVKnots());
  TColStd_Array1OfInteger um(1, s->NbUKnots()), vm(1, s->NbVKnots());
  s->UKnots(uk);
  s->VKnots(vk);
  s->UMultiplicities(um);
  s->VMultiplicities(vm);
  return nurbs::Surface(flat_knots(uk, um, s->UDegree()), flat_knots(vk, vm, s->VDegree()), std::move(Pw));
}

}  // namespace probecomp::occt
