// libFuzzer target: the CAD loader on STEP (cad/model: OpenCASCADE's reader, our checks and the NURBS conversion;
// OpenCASCADE's exceptions must come back as CadError).
#include "fuzz_input.hpp"
#include "probecomp/cad/model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return probecomp::fuzz::read_input(data, size, ".stp",
                                     [](const std::filesystem::path& p) { (void)probecomp::cad::read_model(p); });
}
