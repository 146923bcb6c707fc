#pragma once
// Rigorous bounds on the normal directions of a rational Bézier patch, for culling in the closest-point search.
//
// With A = Σ B_i B_j w_ij P_ij and W = Σ B_i B_j w_ij (the homogeneous patch), S = A / W and
//   S_u × S_v = N / W³,   N = W (A_u × A_v) + W_v (A × A_u) + W_u (A_v × A),
// so N, a vector polynomial of degree (3p − 1, 3q − 1), points along the normal everywhere (W > 0). Its Bézier
// coefficients span a convex cone holding every value of N (convex hull property), hence every normal of the
// patch: a rigorous normal cone, which tightens linearly as the patch shrinks.

#include <span>
#include <vector>

#include "probecomp/geometry/types.hpp"

namespace probecomp::nurbs {

// A bivariate vector polynomial in Bernstein form on [0,1]²: (du + 1)·(dv + 1) coefficients, row (u) major.
struct BernsteinVectorPatch {
  int du = 0, dv = 0;
  std::vector<Vector3> c;
};

// N (up to a positive factor) of the rational Bézier patch with homogeneous net `net` ((p+1)·(q+1) points, row
// u major, Pw = (w P, w)); p, q ≥ 1. With equal weights the degree is only (2p − 1, 2q − 1).
[[nodiscard]] BernsteinVectorPatch normal_polynomial(int p, int q, std::span<const HomogeneousPoint> net);

// The same polynomial over the part [u0,u1] × [v0,v1] of [0,1]², reparametrised to [0,1]² (de Casteljau).
[[nodiscard]] BernsteinVectorPatch restrict_patch(const BernsteinVectorPatch& f, double u0, double u1, double v0,
                                                  double v1);

// The same polynomial cut into `pieces` equal parts along u (direction 0) or v (1), each reparametrised to
// [0,1]²: one de Casteljau split per cut, half the work of restricting to each part on its own.
[[nodiscard]] std::vector<BernsteinVectorPatch> split_patch(const BernsteinVectorPatch& f, int direction, int pieces);

// The cosine of the half-angle of the cone about the unit vector `axis` that holds every coefficient of `N`, or
// a value ≤ 0 when the coefficients do not all lie strictly on the axis's side (no cone below 90°: a normal may
// vanish or turn over, and nothing can be culled).
[[nodiscard]] double normal_cone_cosine(const BernsteinVectorPatch& N, const Vector3& axis);

}  // namespace probecomp::nurbs
