#include "probecomp/version.hpp"

namespace probecomp {

// PROBECOMP_VERSION is the CMake project version, defined for this file alone (CMakeLists.txt).
std::string version() { return PROBECOMP_VERSION; }

}  // namespace probecomp
