// libFuzzer target: the QIF 3.0 measured-points reader (io/qif, pugixml underneath).
#include "fuzz_input.hpp"
#include "probecomp/io/qif.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return probecomp::fuzz::read_input(data, size, ".qif",
                                     [](const std::filesystem::path& p) { (void)probecomp::io::read_point_qif(p); });
}
