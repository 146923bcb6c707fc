#pragma once
// Conversion between the kernel's Surface and OpenCASCADE's Geom_BSplineSurface (same poles, weights,
// knots and degrees, so both evaluate the same mathematical surface).

#include <Geom_BSplineSurface.hxx>
#include <Standard_Handle.hxx>

#include "probecomp/nurbs/surface.hpp"

namespace probecomp::occt {

[[nodiscard]] Handle(Geom_BSplineSurface) to_occt(const nurbs::Surface& s);

// Periodic or unclamped OpenCASCADE surfaces are made clamped first (same shape, same parametrisation).
[[nodiscard]] nurbs::Surface from_occt(const Handle(Geom_BSplineSurface)& s);

}  // namespace probecomp::occt
