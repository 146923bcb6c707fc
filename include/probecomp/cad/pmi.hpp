#pragma once
// The geometric tolerances and datums a STEP AP242 file carries as semantic PMI (GD&T), as OpenCASCADE's XDE reads
// them, tied to the model's faces. Where OpenCASCADE reads no magnitude (7.6 reads 0 where the file stores it in a
// complex entity: NIST CTC-02) it is read from the file's own text; a tolerance whose magnitude neither gives has
// none, and a warning names it: never a silent 0.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "probecomp/cad/model.hpp"

namespace probecomp::cad {

enum class ToleranceType {
  Angularity, CircularRunout, Circularity, Coaxiality, Concentricity, Cylindricity, Flatness, Parallelism,
  Perpendicularity, Position, ProfileOfLine, ProfileOfSurface, Straightness, Symmetry, TotalRunout, Other,
};
[[nodiscard]] const char* to_string(ToleranceType t);  // "profile of surface", ...

struct GeometricTolerance {
  ToleranceType type = ToleranceType::Other;
  std::optional<double> value;      // the zone's width, mm; none where the file's could not be read
  // An unequally disposed zone (UZ): how far it reaches outside the material, mm (equal: none, value / 2).
  std::optional<double> outside;
  std::vector<int> faces;           // the toleranced faces (positions in the model's faces)
  std::vector<std::string> datums;  // the datum reference frame, primary first (each name once)
};

// A point or line datum target (A1, A2, ...) as the file places it: where the datum simulator touches the part.
// A line's place is a point on it and its direction (the target's placement axis), with its length. Whether that
// point is the line's start or its middle AP242's practice does not settle: NIST FTC-06's J1 lies across its 31.75 mm
// face from a point 0.635 mm below the face's middle, its length the face's height.
struct DatumTarget {
  int number = 0;                         // A1: 1
  Point3 point = Point3::Zero();          // the model's coordinates, mm
  Vector3 direction = Vector3::Zero();    // a line's (unit); zero for a point
  double length = 0.0;                    // a line's, mm
  int face = -1;                          // the face it lies on (position in the model's faces)
  [[nodiscard]] bool line() const { return direction != Vector3::Zero(); }
};

// A datum as the file defines it: the faces of its datum feature, or datum targets.
struct DatumFeature {
  std::string name;
  // The datum feature's faces (positions in the model's faces), sorted; with point targets, the faces they lie on.
  std::vector<int> faces;
  // Datum targets: points, lines or areas on the part rather than a whole feature. Areas tie to faces like a
  // feature; points and lines are placed (`targets`, in number order) where the file places them on a face; those
  // it does not place on one are counted in `point_or_line_targets` and not used.
  std::vector<DatumTarget> targets;
  int point_or_line_targets = 0;
  int area_targets = 0;
};

struct Pmi {
  std::vector<GeometricTolerance> tolerances;
  std::vector<std::string> datums;    // every datum the file names, sorted, each once
  std::vector<DatumFeature> datum_features;  // the same datums with their faces, in the same order
  std::vector<std::string> warnings;  // one line each: what could not be read
};

// Reads `path` (STEP) with OpenCASCADE's XDE and ties each tolerance to `model`'s faces, which must be the same
// file's (Model::load). Empty for IGES and for a STEP file without PMI. Throws CadError where the file cannot be
// read or its faces are not the model's.
[[nodiscard]] Pmi read_pmi(const std::filesystem::path& path, const Model& model);

}  // namespace probecomp::cad
