#pragma once
// Where the tests' data are: the CAD samples in tests/data/cad (their sources in its PROVENANCE.md).
#include <filesystem>

namespace probecomp::test {

inline const std::filesystem::path kCadDir = PROBECOMP_TEST_CAD_DIR;

}  // namespace probecomp::test
