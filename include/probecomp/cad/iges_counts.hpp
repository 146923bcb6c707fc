#pragma once
// A check of an IGES file's declared counts before OpenCASCADE's entity readers see them (issue 25's fuzzing).
// OpenCASCADE 7.6 sizes some of an entity's arrays by the counts the entity declares, before it reads the items
// (IGESGeom_ToolBSplineSurface::ReadOwnParams: `new TColStd_HArray2OfReal(0, K1, 0, K2)`), then reads them one
// parameter at a time and records a failure for each one missing. A damaged count (a B-spline surface of
// 100 000 × 100 000 poles in a 60 kB file) makes it allocate tens of gigabytes.
//
// A counted item takes at least one parameter, so a count beyond the number of parameters the entity holds is
// refused: a necessary condition, so no valid file is refused. The file is read by OpenCASCADE's own lexer (`igesread`,
// the first stage of IGESControl_Reader::ReadFile, declared in its installed igesread.h), so the counts checked are
// exactly those its readers will use: the same records, delimiters, assignment of parameter lines to directory
// entries, entity types (from the directory entry) and integers (atoi; an empty parameter reads as 0).
//
// The lexer keeps its state in static variables: call this only under the lock that serialises OpenCASCADE's reads.

#include <filesystem>
#include <optional>
#include <string>

namespace probecomp::cad {

// The first entity whose declared counts its parameter data cannot hold, as a one-line reason ("IGES entity 128
// (directory line 3) declares 100000000 poles but its parameter data hold 437 values"); nothing when every count
// fits, or when OpenCASCADE's lexer cannot read the file at all (its reader then says so).
[[nodiscard]] std::optional<std::string> iges_count_beyond_data(const std::filesystem::path& path);

}  // namespace probecomp::cad
