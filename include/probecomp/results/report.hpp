#pragma once
// What an inspector reads of a run (issue 22): one self-contained HTML page (no file, script, style or font from
// outside it: it opens offline) with a 3-D colour map of the deviations, histograms, a table per face against an
// optional tolerance band, the registration, the inputs and the timings. Its tables carry the JSON's figures
// (results/statistics.hpp: summarise_deviations, statistics_json).

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/cad/outline.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/geometry/rigid.hpp"
#include "probecomp/results/statistics.hpp"

namespace probecomp::results {

// The report's inputs beyond the result.
struct ReportContext {
  RunInputs inputs;
  std::optional<Tolerance> tolerance;
  FileTimings timings;
  // The nominal faces drawn faintly under the points (machine frame): registered_outline of the model.
  std::vector<cad::Polyline> nominal{};
  // Each row's conventional contact point (the centre moved by its radius against its approach normal), when the
  // file has approach normals: the report shows how far the CAD-based contact point lies from it.
  std::optional<std::vector<Point3>> conventional{};
  int labelled_worst = 10;  // the trusted points of largest |deviation| labelled in the view
  // The 3-D view shows at most this many points (every k-th row, the labelled ones always): 100 000 points make a
  // report of about 5 MB. The tables and histograms always use every point.
  std::size_t max_view_points = 120000;
  // The drawing's characteristics and datums, when the run judged them: a table of each after the counts.
  const inspection::Inspection* inspection = nullptr;
};

// The model's faces as outlines (cad::face_outline) moved by `cad_to_machine`, at most about `max_points` points in
// all: without interior isolines when they would pass it, and each line thinned beyond that.
[[nodiscard]] std::vector<cad::Polyline> registered_outline(const cad::Model& model,
                                                            const geometry::RigidTransform& cad_to_machine,
                                                            std::size_t max_points = 40000);

// The page: the inputs (files, unit, tip radii, tolerance, version); counts by status; the trusted deviations (mean,
// std, min, max, out of tolerance) with their histogram and tolerance band; with approach normals, a histogram of
// the CAD-based minus the conventional contact point along the normal; the characteristics and datums, when judged;
// the 3-D view (colour by deviation, status or
// u; the worst points labelled); a table per face (points, ok, mean, std, min, max, out of tolerance, mean u,
// fitted or why not); the registration (status, RMS, transform, free motions); the warnings; the timings.
[[nodiscard]] std::string html_report(const compensation::CompensationResult& result, const ReportContext& context);

}  // namespace probecomp::results
