// libFuzzer target: the DMIS measurement-results reader (io/dmis).
#include "fuzz_input.hpp"
#include "probecomp/io/dmis.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return probecomp::fuzz::read_input(data, size, ".dmo",
                                     [](const std::filesystem::path& p) { (void)probecomp::io::read_point_dmis(p); });
}
