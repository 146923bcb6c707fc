#include "probecomp/compensation/contact.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace probecomp::compensation {

std::vector<ContactPoint> contact_points(const nurbs::Surface& centre_surface, int outward, double probe_radius,
                                         std::span<const Point3> raw_centres,
                                         std::span<const fitting::SurfaceParameter> params) {
  std::vector<ContactPoint> out(raw_centres.size());
  // The global solver is built only if some Newton projection fails (its seed tree costs more than a batch of
  // Newton projections from good parameters).
  std::vector<std::size_t> retry;
  auto finish = [&](std::size_t k, const nurbs::ClosestPointResult& r) {
    ContactPoint& c = out[k];
    c.status = r.status;
    c.centre = raw_centres[k];
    if (!r.ok()) return;
    // Newton's own tangents where it gives them: one evaluation fewer a point.
    const bool tangents = !(r.Su.isZero() && r.Sv.isZero());
    const nurbs::UnitNormal n = tangents ? nurbs::unit_normal(centre_surface, r.u, r.v, r.Su, r.Sv)
                                         : nurbs::unit_normal(centre_surface, r.u, r.v);
    if (n.status == nurbs::UnitNormal::Status::Degenerate) {
      c.status = nurbs::ClosestPointStatus::NumericalError;
      return;
    }
    c.u = r.u;
    c.v = r.v;
    c.centre = r.point;
    c.normal = static_cast<double>(outward) * n.n;
    c.contact = r.point - probe_radius * c.normal;
  };
  std::vector<char> failed(raw_centres.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, raw_centres.size(), 512), [&](const auto& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const nurbs::ClosestPointResult r = nurbs::refine_closest_point(centre_surface, raw_centres[k], params[k].u, params[k].v);
      if (r.ok()) {
        finish(k, r);
      } else {
        failed[k] = 1;
      }
    }
  });
  for (std::size_t k = 0; k < failed.size(); ++k) {
    if (failed[k]) retry.push_back(k);
  }
  if (!retry.empty()) {
    const nurbs::ClosestPointSolver solver(centre_surface);
    tbb::parallel_for(std::size_t{0}, retry.size(), [&](std::size_t i) {
      finish(retry[i], solver.closest_point(raw_centres[retry[i]]));
    });
  }
  return out;
}

}  // namespace probecomp::compensation
