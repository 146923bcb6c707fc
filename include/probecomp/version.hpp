#pragma once
// The library's version, "MAJOR.MINOR.PATCH" (the CMake project version it was built as).

#include <string>

namespace probecomp {

[[nodiscard]] std::string version();

}  // namespace probecomp
