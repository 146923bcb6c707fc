#include "probecomp/compensation/qualified_radii.hpp"

#include <cmath>
#include <map>

#include "probecomp/error.hpp"
#include "warnings.hpp"

namespace probecomp::compensation {

QualifiedRadii qualified_radii(const probe::Qualification& qualification, std::span<const std::string> styli,
                               std::span<const Vector3> travel, std::span<const double> own_radius,
                               double default_radius) {
  const std::size_t n = travel.size();
  if (!styli.empty() && styli.size() != n) throw InputError("the points' styli do not match the points in number");
  if (styli.empty() && qualification.styli.size() != 1) {
    std::string names;
    for (const probe::StylusQualification& s : qualification.styli) names += (names.empty() ? "" : ", ") + s.stylus;
    throw InputError("the points name no stylus (a column stylus or tip, or DMIS SNSLCT) and the qualification holds " +
                     std::to_string(qualification.styli.size()) + ": " + names);
  }
  QualifiedRadii out;
  out.radius.assign(n, 0.0);
  out.uncertainty.assign(n, 0.0);
  std::map<std::string, int> unsupported, unqualified;
  std::map<std::string, std::size_t> use;  // index into out.styli
  for (std::size_t k = 0; k < n; ++k) {
    const std::string& name = styli.empty() ? qualification.styli.front().stylus : styli[k];
    const probe::StylusQualification* q = qualification.find(name);
    const auto [at, added] = use.emplace(name, out.styli.size());
    if (added) {
      StylusRadii s{.stylus = name, .qualified = q != nullptr};
      if (q != nullptr) {
        s.effective_radius = q->effective_radius;
        s.variation = q->model.variation();
        s.degree = q->model.degree();
      }
      out.styli.push_back(std::move(s));
    }
    StylusRadii& stylus_use = out.styli[at->second];
    ++stylus_use.points;
    if (q == nullptr) {
      const double own = own_radius.empty() ? std::nan("") : own_radius[k];
      if (std::isfinite(own) && own > 0.0) {
        out.radius[k] = own;
      } else if (default_radius > 0.0) {
        out.radius[k] = default_radius;
      } else {
        throw InputError("stylus " + (name.empty() ? std::string("(unnamed)") : name) + " (point " + std::to_string(k + 1) +
                         ") is not in the qualification and has no tip radius of its own or by default");
      }
      ++unqualified[name];
      continue;
    }
    if (q->status != probe::QualificationStatus::OK) {
      throw InputError("stylus " + name + " (point " + std::to_string(k + 1) + ") has no usable qualification: " + q->reason);
    }
    if (travel[k].squaredNorm() == 0.0) {  // the direction is not known: the sphere's radius, and its variation in u
      out.radius[k] = q->effective_radius;
      out.uncertainty[k] = std::hypot(q->effective_radius_u, q->model.variation());
      continue;
    }
    const probe::EffectiveRadius r = probe::effective_radius(*q, travel[k]);
    out.radius[k] = r.radius;
    out.uncertainty[k] = r.uncertainty;
    if (r.unsupported) {
      ++unsupported[name];
      ++stylus_use.unsupported;
    }
  }
  for (const auto& [name, count] : unsupported) {
    const probe::StylusQualification& q = *qualification.find(name);
    out.warnings.push_back(std::to_string(count) + " point" + (count == 1 ? " was" : "s were") + " touched with stylus " +
                           name + " from directions its qualification never touched from (more than " +
                           std::to_string(static_cast<int>(std::lround(q.support_angle_deg))) +
                           " degrees from every touch): they take its sphere-fit radius, and their u includes how much "
                           "its radius varies with direction (" + detail::um(q.model.variation()) + ")");
  }
  for (const auto& [name, count] : unqualified) {
    out.warnings.push_back(std::to_string(count) + " point" + (count == 1 ? "" : "s") + " of stylus " +
                           (name.empty() ? std::string("(unnamed)") : name) +
                           ", which the qualification does not hold, take their nominal tip radius");
  }
  return out;
}

}  // namespace probecomp::compensation
