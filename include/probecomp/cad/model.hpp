#pragma once
// probecomp's CAD model: the faces of a STEP or IGES part as NURBS surfaces of the kernel, each with its
// trimming, its material side and its index and name, in millimetres. OpenCASCADE reads the file (and converts
// analytic faces exactly to NURBS); nothing of OpenCASCADE shows in this header.

#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "probecomp/cad/analytic.hpp"
#include "probecomp/cad/trim.hpp"
#include "probecomp/error.hpp"
#include "probecomp/nurbs/surface.hpp"

namespace probecomp::cad {

struct Face {
  int index = 0;            // position in the file's face order (OpenCASCADE's), from 0
  std::string name{};       // the face's name in the file; empty when it has none
  std::string source_type{};  // the surface as the file describes it: plane, cylinder, bspline, ...
  nurbs::Surface surface;
  // Empty when the face is its whole surface. Held by pointer so that a solver can keep referring to it.
  std::shared_ptr<const Trim> trim{};
  int outward = 1;              // +1: the outward normal (away from the material) is S_u × S_v; −1: opposite
  bool material_known = false;  // the face bounds a solid, so `outward` is the material side for certain
  // The NURBS is the file's surface exactly (B-spline, Bézier and analytic faces); offset and other procedural
  // surfaces are approximated by OpenCASCADE's conversion, to about its tolerance (1e-6 mm order).
  bool exact = true;
  // The file's plane, cylinder, cone, sphere or torus in closed form, where its map to `surface` checks out;
  // null for other faces. Closest points on the face then come from it, so code that changes `surface` (moves or
  // deforms the face) must change or drop this too.
  std::shared_ptr<const AnalyticFace> analytic = nullptr;
  // The knot spans per direction of the shape `surface` represents, where it has more: an offset face keeps its
  // nominal face's, its added knots only letting the fit follow the offset. The closest-point search sizes its
  // cells by these (nurbs::ClosestPointOptions::shape_spans_u). 0: the surface's own.
  int shape_spans_u = 0;
  int shape_spans_v = 0;

  [[nodiscard]] bool trimmed() const { return trim != nullptr; }
};

struct Model {
  std::filesystem::path path;
  std::string file_units;  // the length unit the file declares ("mm", "inch", ...); geometry here is in mm
  std::vector<Face> faces;
  // What the reader had to leave out (entities OpenCASCADE could not parse), one line each; empty for a
  // clean file. Whoever reports on a model passes these on as warnings.
  std::vector<std::string> read_warnings;

  // Reads .stp/.step or .igs/.iges (chosen by extension, case-insensitive). Throws CadError for a missing,
  // unreadable or truncated file, a file that is not STEP/IGES, or one without surfaces.
  [[nodiscard]] static Model load(const std::filesystem::path& path);
  [[nodiscard]] int face_count() const { return static_cast<int>(faces.size()); }
};

// The same as Model::load.
[[nodiscard]] Model read_model(const std::filesystem::path& path);

// Writes the surfaces as untrimmed NURBS: IGES entity 128 or STEP B-spline faces, by the extension of
// `path`, in millimetres. The file appears complete or not at all (written to a temporary name, renamed).
void write_surfaces(const std::filesystem::path& path, const std::vector<nurbs::Surface>& surfaces);

}  // namespace probecomp::cad
