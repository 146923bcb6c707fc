#include "probecomp/compensation/conventional.hpp"

#include <limits>
#include <stdexcept>

#include "probecomp/cad/locator.hpp"
#include "probecomp/error.hpp"

namespace probecomp::compensation {

std::vector<Point3> conventional_contact_points(std::span<const Point3> centres, std::span<const Vector3> approach_normals,
                                                const geometry::TipRadii& radii) {
  if (centres.size() != approach_normals.size()) {
    throw InputError("conventional compensation needs one approach normal per point");
  }
  std::vector<Point3> out(centres.size());
  for (std::size_t i = 0; i < centres.size(); ++i) {
    const double len = approach_normals[i].norm();
    out[i] = len > 0.0 && std::isfinite(len)
                 ? Point3(centres[i] - radii[i] * approach_normals[i] / len)
                 : Point3::Constant(std::numeric_limits<double>::quiet_NaN());
  }
  return out;
}

registration::RegistrationResult register_conventional(const cad::Model& nominal, std::span<const Point3> raw_centres,
                                         std::span<const Vector3> approach_normals, const geometry::TipRadii& radii,
                                         const registration::RegistrationOptions& options) {
  const std::vector<Point3> contacts = conventional_contact_points(raw_centres, approach_normals, radii);
  const cad::ModelLocator locator(nominal);
  return registration::register_points(locator, contacts, options);
}

}  // namespace probecomp::compensation
