#pragma once
// Data sets whose least-squares plane, sphere or cylinder is known exactly, made as NIST's Algorithm Testing
// System makes its reference data for ASME B89.4.10 / ISO 10360-6 (Shakarji, "Least-squares fitting algorithms
// of the NIST algorithm testing system", J. Res. NIST 103 (1998) 633): points on a chosen element, each moved
// along the element's normal by a residual e_i taken from the null space of the fit's Jacobian (Jᵀe = 0). Moving
// a point along its normal keeps its row of J, so the chosen element is a stationary point of Σ d_i² with
// residuals e: for residuals small against the element's size, the least-squares element. Hard cases on purpose,
// as NIST's: far from the origin, a small cap of a sphere, an arc of a cylinder.

#include <string>
#include <vector>

#include "probecomp/geometry/types.hpp"

namespace probecomp::selftest {

enum class ElementKind { Plane, Sphere, Cylinder };

struct ReferenceElement {
  std::string name;
  ElementKind kind = ElementKind::Plane;
  std::vector<Point3> points;
  // The known least-squares element: for a plane a point on it and its unit normal; for a sphere the centre and
  // radius; for a cylinder a point on the axis, its unit direction and the radius.
  Point3 point = Point3::Zero();
  Vector3 direction = Vector3::Zero();
  double radius = 0.0;
  double rms = 0.0;  // of the residuals put in, mm: the fit's RMS distance must be this
};

// Two data sets of each kind (about 40–60 points each, residuals up to 10 µm), the same on every machine.
[[nodiscard]] std::vector<ReferenceElement> reference_elements();

}  // namespace probecomp::selftest
