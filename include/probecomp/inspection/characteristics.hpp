#pragma once
// A drawing's characteristics judged on the compensated points (DESIGN.md §7): surface profiles, flatness being one
// without datums, with their value and the decision under ISO 14253-1 (U = 2u). This step evaluates the
// characteristics without datums (form only: the points best-fitted to their nominal faces first); one with datums
// is `not-evaluated`, with that reason, until datum reference frames are built.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/cad/pmi.hpp"
#include "probecomp/compensation/pipeline.hpp"

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
  std::vector<CharacteristicSpec> characteristics;
};

// The specification file (JSON, DESIGN.md §7). Throws InputError naming the file and what is wrong (not JSON, a
// characteristic without faces or with a tolerance that is not positive, an unknown type, a face the model does not
// have, a datum the file does not define).
[[nodiscard]] Specification read_specification(const std::filesystem::path& path, const cad::Model& model);

// The characteristics a STEP AP242 file's PMI states (cad/pmi.hpp): each profile of surface and flatness as a
// surface profile on its faces (datums as the file gives them). One whose magnitude could not be read has a
// tolerance of 0, which evaluate() reports as not evaluated, with that reason. The others (positions,
// perpendicularities, ...) are not characteristics of this step and are counted in `skipped`.
[[nodiscard]] Specification from_pmi(const cad::Pmi& pmi, int& skipped);

enum class Decision { Conforms, DoesNotConform, Indeterminate, NotEvaluated };
[[nodiscard]] const char* to_string(Decision d);  // "conforms", "does-not-conform", ...

struct CharacteristicResult {
  CharacteristicSpec spec;
  double outside = 0.0;  // as used (t/2 unless given)
  int points = 0;        // trusted points used
  double min = 0.0, max = 0.0;  // signed deviations in the characteristic's frame, mm
  double value = 0.0;    // 2·max|d − (outside − t/2)|: the width of the smallest such zone holding every point, mm
  double u = 0.0;        // of value: 2u of the point that sets it, mm
  Decision decision = Decision::NotEvaluated;
  std::string reason;    // why not evaluated
};

// Each characteristic on `result`'s trusted (ok) points of its faces. Without datums the points are best-fitted to
// the nominal faces (least squares, the motions they fix; the rest held) before their deviations are taken.
[[nodiscard]] std::vector<CharacteristicResult> evaluate(const Specification& spec, const cad::Model& nominal,
                                                         const compensation::CompensationResult& result);

}  // namespace probecomp::inspection
