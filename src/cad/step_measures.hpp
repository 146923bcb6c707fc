#pragma once
// What OpenCASCADE's STEP reader leaves unread of a tolerance, read from the file's own text (ISO 10303-21): a
// geometric tolerance's magnitude and an unequally disposed zone's displacement where the file stores them as complex
// entities of measures (NIST CTC-02: (LENGTH_MEASURE_WITH_UNIT() MEASURE_REPRESENTATION_ITEM() MEASURE_WITH_UNIT(...)
// ...), which 7.6 reads as 0). Private to cad/ (pmi.cpp).

#include <filesystem>
#include <map>
#include <optional>
#include <string>

namespace probecomp::cad::detail {

struct ToleranceMeasures {
  std::optional<double> magnitude;     // the zone's width, mm
  std::optional<double> displacement;  // UNEQUALLY_DISPOSED_GEOMETRIC_TOLERANCE: how far the zone lies outside, mm
};

// Every GEOMETRIC_TOLERANCE instance of `path`'s DATA section by its name, with what its own text and the measures it
// refers to give (a length in mm, metres or inches; none where the reference or its unit cannot be resolved). Names
// that occur more than once are left out: a tolerance is matched to OpenCASCADE's by its name. Empty where the file
// cannot be read.
[[nodiscard]] std::map<std::string, ToleranceMeasures> tolerance_measures(const std::filesystem::path& path);

}  // namespace probecomp::cad::detail
