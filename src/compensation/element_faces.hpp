#pragma once
// Faces too sparse for their NURBS net (10–40 touches on a plane or a hole, the usual way a CMM measures a prismatic
// face), fitted as the plane, cylinder, sphere, cone or torus the CAD file says they are. Private to compensation/.

#include <optional>
#include <span>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/geometry/rigid.hpp"

namespace probecomp::compensation::detail {

// The face's element fitted to its tip centres (machine frame, as the faces' NURBS fits; `to_machine` the
// registration), with points beyond kElementOutlierScales robust scales of the fit's residuals left out (`outlier`,
// per centre, set to 1) and the element fitted again. A cone or torus starts from the nominal's offset and holds
// there what its centres fix too poorly, given their `noise` along the normal (mm; kMaxFittedStd). Nothing
// where the face is not an elementary surface, the centres do not fix the element (too few, all on a line, a band
// too narrow for a cone's angle), or the element is not the nominal's offset by the tip radius `r` to within
// kMaxElementTilt and kMaxRadiusChange (a hole narrower than the tip, a fit that found another shape in a few
// points): those points stay offset along the nominal normal.
[[nodiscard]] std::optional<ElementFaceFit> fit_element_face(const cad::Face& face, std::span<const Point3> centres,
                                                             const geometry::RigidTransform& to_machine, double r,
                                                             double noise, std::vector<char>& outlier);

// The signed distance of x from the element, mm (plane: along its normal as fitted; the others: positive away from
// the axis, centre or tube's centre circle).
[[nodiscard]] double element_distance(const ElementFaceFit& e, const Point3& x);

// The element's unit normal at (or nearest) x, pointing as `towards` does (the side the tip was on).
[[nodiscard]] Vector3 element_normal(const ElementFaceFit& e, const Point3& x, const Vector3& towards);

// The noise along the normal that the rows of faces fitted as their elements take as u (mm; infinity where nothing
// tells it). The same probe on the same machine measured them all: their residuals are pooled (Σ rss / Σ (n − k)),
// and so fixed by all their degrees of freedom, where one face's 5–37 leave its own estimate a fifth off or more. A
// face whose own residuals that noise does not explain (χ² test) holds form error its element does not follow: it
// is left out of the pool and keeps its own, larger, estimate (its rms with the element's parameters' share of the
// degrees of freedom given back, √(n / (n − k))). With fewer than kMinPooledDegrees in the pool,
// `fitted_noise` (the NURBS-fitted faces' median estimate, from more points) stands in where there is one.
struct ElementNoise {
  std::vector<double> face;  // per face, in the order given
  double pooled = 0.0;       // the pool's (infinity without a degree of freedom)
  double shared = 0.0;       // the part's noise, which the faces in the pool take: the pool, or `fitted_noise`
};
[[nodiscard]] ElementNoise element_face_noise(std::span<const ElementFaceFit* const> faces,
                                              std::optional<double> fitted_noise);

}  // namespace probecomp::compensation::detail
