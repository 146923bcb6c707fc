#include "probecomp/cad/offset_model.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <optional>

namespace probecomp::cad {

int OffsetModel::failed() const {
  return static_cast<int>(std::count_if(faces.begin(), faces.end(), [](const auto& r) { return !r.ok(); }));
}

OffsetModel offset_model(const Model& model, double d, const fitting::OffsetOptions& options) {
  std::vector<std::optional<fitting::OffsetResult>> results(model.faces.size());
  tbb::parallel_for(std::size_t{0}, model.faces.size(), [&](std::size_t k) {
    const Face& face = model.faces[k];
    results[k] = fitting::offset_surface(face.surface, d * face.outward, options);
  });
  OffsetModel out{model, {}};
  out.faces.reserve(results.size());
  for (std::size_t k = 0; k < results.size(); ++k) {
    Face& face = out.model.faces[k];
    face.surface = results[k]->surface;
    // Offset faces are approximations to the tolerance, like OpenCASCADE's conversions of procedural surfaces.
    face.exact = false;
    face.source_type = "offset " + face.source_type;
    out.faces.push_back(std::move(*results[k]));
  }
  return out;
}

}  // namespace probecomp::cad
