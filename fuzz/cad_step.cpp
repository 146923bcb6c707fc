// libFuzzer target: the STEP readers: the CAD loader (cad/model: OpenCASCADE's reader, our checks and the NURBS
// conversion; OpenCASCADE's exceptions must come back as CadError), and our own reader of the tolerances' measures
// from the file's text (cad/step_measures, which read_pmi calls), which must take any text without failing.
#include "fuzz_input.hpp"
#include "probecomp/cad/model.hpp"
#include "step_measures.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return probecomp::fuzz::read_input(data, size, ".stp", [](const std::filesystem::path& p) {
    (void)probecomp::cad::detail::tolerance_measures(p);
    (void)probecomp::cad::read_model(p);
  });
}
