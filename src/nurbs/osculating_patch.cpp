#include "probecomp/nurbs/osculating_patch.hpp"

#include <Eigen/Dense>

#include <limits>

namespace probecomp::nurbs {

OsculatingPatch OsculatingPatch::invalid() {
  OsculatingPatch patch;
  patch.A[0] = std::numeric_limits<float>::quiet_NaN();
  return patch;
}

OsculatingPatch OsculatingPatch::at(const nurbs::SurfaceD2& d, const Vector3& normal, double offset) {
  OsculatingPatch patch;
  Eigen::Matrix<double, 3, 2> J;
  J << d.Su, d.Sv;
  Eigen::Matrix2d II;
  II << normal.dot(d.Suu), normal.dot(d.Suv), normal.dot(d.Suv), normal.dot(d.Svv);
  Eigen::Matrix2d I = J.transpose() * J;
  // The parallel surface at distance e along n has tangents J (1 − e W), W = I⁻¹ II the shape operator (n_u, n_v =
  // −J W: Weingarten), and second form (1 − e W)ᵀ II (on a sphere of radius R: W = −1/R, and both come out as the
  // sphere of radius R + e's).
  if (offset != 0.0) {
    const Eigen::Matrix2d stretch = Eigen::Matrix2d::Identity() - offset * I.inverse() * II;
    J = J * stretch;
    II = stretch.transpose() * II;
    I = J.transpose() * J;
  }
  // Invalid where a tangent vanishes (a sphere's pole) or the two are (nearly) parallel: relative to the trace, not
  // to I₁₁ I₂₂, which vanishes with the tangent.
  const double det = I.determinant();
  const Eigen::Matrix<double, 2, 3> A = I.inverse() * J.transpose();
  // Floats hold the patch: a value beyond their range (a parametrisation scaled absurdly) makes it invalid too.
  constexpr double kFloatRange = std::numeric_limits<float>::max();
  if (!(det > 1e-12 * I.trace() * I.trace()) || !(A.cwiseAbs().maxCoeff() < kFloatRange) ||
      !(II.cwiseAbs().maxCoeff() < kFloatRange)) {
    return invalid();
  }
  for (int k = 0; k < 6; ++k) patch.A[k] = static_cast<float>(A(k / 3, k % 3));
  patch.II[0] = static_cast<float>(II(0, 0));
  patch.II[1] = static_cast<float>(0.5 * (II(0, 1) + II(1, 0)));
  patch.II[2] = static_cast<float>(II(1, 1));
  return patch;
}

OsculatingPatch::Prediction OsculatingPatch::predict(const Point3& foot, const Vector3& normal, const Point3& x) const {
  const Vector3 d = x - foot;
  const double h = normal.dot(d);
  const Vector3 t = d - h * normal;
  Prediction p;
  p.du = A[0] * t.x() + A[1] * t.y() + A[2] * t.z();
  p.dv = A[3] * t.x() + A[4] * t.y() + A[5] * t.z();
  const double IIa0 = II[0] * p.du + II[1] * p.dv, IIa1 = II[1] * p.du + II[2] * p.dv;
  p.distance = h - 0.5 * (p.du * IIa0 + p.dv * IIa1);
  p.gradient = normal - Vector3(A[0] * IIa0 + A[3] * IIa1, A[1] * IIa0 + A[4] * IIa1, A[2] * IIa0 + A[5] * IIa1);
  return p;
}

}  // namespace probecomp::nurbs
