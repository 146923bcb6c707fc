#include "probecomp/cad/offset_model.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <optional>

namespace probecomp::cad {

namespace {
// An elementary offset face's normals against its offset NURBS's: loose, as the NURBS is only within the offset's
// tolerance (1e-4 mm over spans of a few mm: normals off by up to about 1e-4 rad); it catches a wrong side or a
// wrong parameter map, which are off by far more.
constexpr double kOffsetNormalMatch = 1e-3;
}  // namespace

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
    if (face.shape_spans_u == 0) face.shape_spans_u = face.surface.U().num_spans();
    if (face.shape_spans_v == 0) face.shape_spans_v = face.surface.V().num_spans();
    face.surface = results[k]->surface;
    // Offset faces are approximations to the tolerance, like OpenCASCADE's conversions of procedural surfaces.
    face.exact = false;
    face.source_type = "offset " + face.source_type;
    // An elementary face's offset is elementary again, exactly; the offset NURBS approximates it to its deviation,
    // so the check that both describe one surface at the same parameters is that loose (kOffsetNormalMatch
    // catches a wrong side or map, not the fit's own error).
    if (face.analytic) {
      const std::optional<AnalyticFace> exact = face.analytic->offset(d * face.outward);
      face.analytic = nullptr;
      if (exact && results[k]->status != fitting::OffsetResult::Status::Degenerate) {
        const AnalyticFace::Check check = exact->compare(face.surface);
        const double allowed = 2.0 * std::max(options.tolerance, results[k]->deviation) + kAnalyticMatch;
        if (check.distance <= allowed && check.normal_angle <= kOffsetNormalMatch) face.analytic = std::make_shared<const AnalyticFace>(*exact);
      }
    }
    out.faces.push_back(std::move(*results[k]));
  }
  return out;
}

}  // namespace probecomp::cad
