#pragma once
// QUAL.json, what `probecomp qualify` writes and `compensate --qualification` reads (DESIGN.md §8): per stylus the
// fitted sphere, the effective radius and the model of it by direction, lengths in mm whatever the points' unit.
//   {"format": "probecomp qualification 1", "units": "mm", "sphere_diameter": D,
//    "styli": [{"stylus": "T1", "status": "ok", "touches": n, "effective_radius": r, "effective_radius_u": u,
//               "sphere_centre": [x, y, z], "form_error": f, "sphere_rms": s, "residual": e, "loo_residual": e1,
//               "model": {"basis": ..., "degree": L, "variation": v, "log10_smoothing": s, "terms": [{"l": 0, "m": 0, "coefficient": c}, ...],
//                         "covariance": [[...], ...]},
//               "support_angle_deg": a, "directions": [[dx, dy, dz], ...]}]}
// A stylus whose qualification failed is written with its status and reason and nothing else.

#include <string>

#include "probecomp/io/json.hpp"
#include "probecomp/probe/qualification.hpp"

namespace probecomp::probe {

[[nodiscard]] io::Json to_json(const Qualification& q);
// Throws InputError naming `path` and what is wrong (not JSON, not a qualification, a stylus without a model).
[[nodiscard]] Qualification qualification_from_json(const std::string& text, const std::string& path);
[[nodiscard]] Qualification read_qualification(const std::string& path);

}  // namespace probecomp::probe
