// libFuzzer target: the rigid-transform file reader (io/transform_file).
#include "fuzz_input.hpp"
#include "probecomp/io/transform_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return probecomp::fuzz::read_input(data, size, ".txt",
                                     [](const std::filesystem::path& p) { (void)probecomp::io::read_transform(p); });
}
