#pragma once
// A face near a foot point to second order: its osculating paraboloid. ICP moves the points between closest-point
// searches against it (registration/icp_state.hpp). The signed distance of a point then comes out right to third
// order in its tangential offset from the foot, and so do its parameters, so a slide also sees a foot cross a face's
// edge. With a tangent plane only the first order is right. A tangent plane also misses the turn of the normal, which
// is what fixes the motions that a gently curved face fixes only weakly.
//
// At a foot p with unit normal n, let x = p + d, h = n·d and t = d − h n. With J = [S_u S_v], the first form
// I = JᵀJ, the second form II = [n·S_uu n·S_uv; n·S_uv n·S_vv] and A = I⁻¹Jᵀ, the parameter step to x's foot is
// a = A t, and x's signed distance is r = h − ½ aᵀ II a. Its gradient is n − Aᵀ II a (do Carmo §3.2; Pottmann and
// Hofer 2003 for the squared distance's second-order model). Both are accurate to terms in |t|³ and in h|t|²κ².
// The terms in h come from the offset of x itself, which is about the noise (micrometres) in ICP.

#include "probecomp/nurbs/surface.hpp"

namespace probecomp::nurbs {

// 36 bytes, in floats: kept for every point while registering (a million points: 36 MB). Their 7 significant
// digits carry a correction that is itself of the order of κ|t|², so they add no error that can be seen.
struct OsculatingPatch {
  float A[6] = {0, 0, 0, 0, 0, 0};  // I⁻¹Jᵀ, row by row: a 3D tangential offset → (du, dv)
  float II[3] = {0, 0, 0};          // the second form: n·S_uu, n·S_uv, n·S_vv

  // The patch of the surface with derivatives `d` at the foot, `normal` the unit normal there (either side: II takes
  // its sign from it). `offset` (mm) gives the patch of the surface moved that far along `normal` instead (a tip
  // larger than the model's). Invalid where a tangent vanishes (a pole) or the two are (nearly) parallel, or a value
  // is not finite or would not fit a float.
  [[nodiscard]] static OsculatingPatch at(const nurbs::SurfaceD2& d, const Vector3& normal, double offset = 0.0);
  [[nodiscard]] static OsculatingPatch invalid();
  [[nodiscard]] bool valid() const { return A[0] == A[0]; }  // NaN marks an invalid patch

  struct Prediction {
    double distance = 0.0;               // signed, + on the side `normal` points to, mm
    Vector3 gradient = Vector3::Zero();  // of the distance at x: the normal at x's foot, to first order
    double du = 0.0, dv = 0.0;           // from the foot's parameters to x's foot's
  };
  [[nodiscard]] Prediction predict(const Point3& foot, const Vector3& normal, const Point3& x) const;
};
static_assert(sizeof(OsculatingPatch) == 36);

}  // namespace probecomp::nurbs
