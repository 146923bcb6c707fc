#pragma once
// A drawing's characteristics judged on the compensated points (DESIGN.md §7): surface profiles, flatness being one
// without datums, with their value and the decision under ISO 14253-1 (U = k·u, k at least 2: see `coverage`).
// Each is judged in its datum reference frame (datum_frame.hpp); motions its datums leave free, all six without
// datums, are best-fitted to its own points (least squares) first.

#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/cad/pmi.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/inspection/datum_frame.hpp"

namespace probecomp::inspection {

struct CharacteristicSpec {
  std::string name;
  std::string type = "surface-profile";
  std::vector<int> faces;             // model face indices, as `probecomp info` lists them
  double tolerance = 0.0;             // t: the zone's total width, mm
  std::optional<double> outside;      // how much of it lies outside the material, mm (default t/2)
  std::vector<std::string> datums;    // reference frame, primary first; empty: form only
};

struct Specification {
  std::vector<DatumSpec> datums;  // as the file defines them, in its order
  // Datums named but not usable, with why (a STEP file's datum set by point or line targets): a characteristic that
  // refers to one is not evaluated, with that reason.
  std::map<std::string, std::string> unusable_datums;
  std::vector<CharacteristicSpec> characteristics;
  std::vector<std::string> alignment;  // the datum frame the whole output is put in, primary first; empty: none
};

// The specification file (JSON, DESIGN.md §7). Throws InputError naming the file and what is wrong (not JSON, a
// characteristic or datum without faces, a tolerance that is not positive, an unknown type or fit, a face the model
// does not have, a datum the file does not define, in a characteristic or in "alignment").
[[nodiscard]] Specification read_specification(const std::filesystem::path& path, const cad::Model& model);

// The characteristics a STEP AP242 file's PMI states (cad/pmi.hpp): each profile of surface and flatness as a
// surface profile on its faces, in the datum reference frame the file gives it; each datum a least-squares fit of its
// datum feature's faces (or target areas). A datum set by point or line targets is unusable, with that reason. One
// whose magnitude could not be read has a tolerance of 0, which evaluate() reports as not evaluated, with that reason. The others (positions,
// perpendicularities, ...) are not characteristics of this step and are counted in `skipped`.
[[nodiscard]] Specification from_pmi(const cad::Pmi& pmi, int& skipped);

// The characteristics `source` names (compensate --characteristics, Python's characteristics=): a specification file
// (read_specification), or "pmi" for those the model's own STEP AP242 file states (from_pmi). `warnings` are the PMI
// reader's, and how many of the file's tolerances this step does not evaluate. Throws InputError for a bad file, and
// std::invalid_argument where "pmi" finds no surface profile or flatness to judge.
struct LoadedSpecification {
  Specification spec;
  std::vector<std::string> warnings;
};
[[nodiscard]] LoadedSpecification load_specification(const std::string& source, const cad::Model& model);

// The faces of every datum feature the specification defines (sorted, once each): what locates the part when the
// best fit of all its points is doubtful (compensation::CompensateOptions::datum_faces).
[[nodiscard]] std::vector<int> datum_faces(const Specification& spec);

enum class Decision { Conforms, DoesNotConform, Indeterminate, NotEvaluated };

// A trusted point as its characteristic judged it (the report's view colours by these).
struct JudgedPoint {
  std::size_t row = 0;     // in the compensation result
  double deviation = 0.0;  // signed, in the characteristic's frame after its best fit, mm
  double U = 0.0;          // k·u, its own and its datums' share, mm
};
[[nodiscard]] const char* to_string(Decision d);  // "conforms", "does-not-conform", ...

struct CharacteristicResult {
  CharacteristicSpec spec;
  double outside = 0.0;  // as used (t/2 unless given)
  int points = 0;        // trusted points used
  double min = 0.0, max = 0.0;  // signed deviations in the characteristic's frame, mm
  double value = 0.0;    // 2·max|d − (outside − t/2)|: the width of the smallest such zone holding every point, mm
  double u = 0.0;        // of value: 2u of the point that sets it (its own and its datums' share), mm
  // The decision's coverage factor: every point's d ± k·u (u its own and its datums' share) is judged against the zone,
  // k keeping all the points' intervals right together with 95 % probability (2 for a few points; 3.0 for 20).
  double coverage = 2.0;
  Decision decision = Decision::NotEvaluated;
  std::string reason;    // why not evaluated; or, when indeterminate, which points hold it back
  bool too_few_points = false;  // not evaluated for want of trusted points on its faces (more would decide it)
  std::vector<std::size_t> undecided;  // rows of the result whose d ± U crosses a limit of the zone: to measure again
  std::vector<JudgedPoint> judged;     // every point it used, by ascending row (24 bytes each)
};

// One datum as a frame fitted it.
struct FrameDatum {
  std::string frame;  // the frame's datums, primary first, joined by '|': "A|B|C"
  DatumResult datum;
};

struct Inspection {
  std::vector<FrameDatum> datums;  // of every frame set up, in the order of first use
  std::vector<CharacteristicResult> characteristics;
  // Every frame set up (or tried: NotDone), by its datums joined with '|' ("" is the frame of no datums).
  std::map<std::string, DatumFrame> frames;
  std::string alignment;                    // the specification's alignment frame ("A|B|C"); empty: none
  std::optional<DatumFrame> alignment_frame;  // set up when there is one (NotDone: why, in its reason)
};

// Each characteristic on `result`'s trusted (ok) points of its faces, in its datum reference frame; motions the
// frame leaves free are best-fitted to the characteristic's points on its nominal faces (least squares, the motions
// they fix; the rest held) before their deviations are taken.
[[nodiscard]] Inspection evaluate(const Specification& spec, const cad::Model& nominal,
                                  const compensation::CompensationResult& result);

}  // namespace probecomp::inspection
