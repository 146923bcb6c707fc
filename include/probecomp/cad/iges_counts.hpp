#pragma once
// A check of an IGES file's parameter data before OpenCASCADE reads it (issue 25's fuzzing): OpenCASCADE sizes an
// entity's arrays by the counts the entity declares and then reads them one parameter at a time, recording a
// failure for each one missing. A damaged count (a B-spline surface of 10 000 × 10 000 poles in a 60 kB file) makes
// it allocate gigabytes and record millions of messages. A count can never exceed the number of parameters the
// entity holds, since each counted item takes at least one: that necessary condition is checked here for the
// entities whose counts size arrays (IGES 5.3: 102, 106, 112, 114, 126, 128 and the property entity 406), so no
// valid file is refused.

#include <istream>
#include <optional>
#include <string>

namespace probecomp::cad {

// The first entity whose declared counts its parameter data cannot hold, as a one-line reason ("IGES entity 128
// (directory line 3) declares 100000000 poles but its parameter data hold 437 values"); nothing when every count
// fits.
[[nodiscard]] std::optional<std::string> iges_count_beyond_data(std::istream& in);

}  // namespace probecomp::cad
