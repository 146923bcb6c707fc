// libFuzzer target: the CSV point reader (io/point_table), both ways of keeping the numbers' text.
#include "fuzz_input.hpp"
#include "probecomp/io/point_files.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return probecomp::fuzz::read_input(data, size, ".csv", [](const std::filesystem::path& p) {
    (void)probecomp::io::read_points(p);
    (void)probecomp::io::read_points(p, probecomp::io::kMillimetre, {}, probecomp::io::NumberText::Drop);
  });
}
