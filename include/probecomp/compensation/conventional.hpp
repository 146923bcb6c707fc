#pragma once
// Conventional compensation (DESIGN.md §1), what most CMM software does: the contact point is the probe
// centre moved by the tip radius against the programmed approach normal, c − r·(i,j,k). Exact only when the
// part's actual normal at the contact equals the programmed one.

#include <span>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/geometry/tip_radii.hpp"
#include "probecomp/geometry/types.hpp"
#include "probecomp/registration/icp.hpp"

namespace probecomp::compensation {

// (i,j,k) is the outward normal of the programmed point (DMIS PTMEAS); it is normalised here. A zero or
// non-finite normal gives a non-finite point (the caller flags it). Each centre is moved by its own tip's radius.
[[nodiscard]] std::vector<Point3> conventional_contact_points(std::span<const Point3> centres,
                                                              std::span<const Vector3> approach_normals,
                                                              const geometry::TipRadii& radii);

// The conventional registration route (paper §5.1): these contact points registered to the nominal model.
[[nodiscard]] registration::RegistrationResult register_conventional(const cad::Model& nominal, std::span<const Point3> raw_centres,
                                                       std::span<const Vector3> approach_normals, const geometry::TipRadii& radii,
                                                       const registration::RegistrationOptions& options = {});

}  // namespace probecomp::compensation
