#pragma once
// probecomp's public API in one header: CAD-based contact-probe radius compensation for CMM data.
//
//   const probecomp::CadModel model = probecomp::CadModel::load("part.stp");       // STEP or IGES, in mm
//   const probecomp::io::PointTable raw = probecomp::io::read_points("raw.csv");  // probe centres (CSV, DMIS or QIF)
//   const probecomp::CompensationResult result =
//       probecomp::compensate(model, raw.points, std::nullopt, {.probe_radius = 1.0});
//
// The steps compensate() is made of (prepare_model, register_centres, fit_faces, compensate_points) are in
// probecomp/compensation/pipeline.hpp; every layer's headers are under probecomp/<layer>/. Failures throw a
// probecomp::Error (probecomp/error.hpp).

#include "probecomp/cad/model.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/error.hpp"
#include "probecomp/geometry/types.hpp"
#include "probecomp/io/point_files.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/results/files.hpp"
#include "probecomp/results/statistics.hpp"
#include "probecomp/version.hpp"

namespace probecomp {

// A part's faces as NURBS with their trims and material sides (CadModel::load, face_count()).
using CadModel = cad::Model;

using compensation::compensate;
using compensation::CompensatedPoint;
using compensation::CompensateOptions;
using compensation::CompensationResult;
using compensation::Method;
using compensation::PointStatus;
using compensation::Statistics;
using compensation::to_string;

}  // namespace probecomp
