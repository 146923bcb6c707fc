#pragma once
// OpenCASCADE's exchange settings are process-wide statics: the readers of this layer (cad/model.cpp, cad/pmi.cpp)
// set them once and read one file at a time. Private to cad/.

#include <filesystem>
#include <mutex>
#include <string>

namespace probecomp::cad::detail {

[[nodiscard]] std::mutex& exchange_mutex();
// Quiet messages, IGES initialised, lengths in millimetres; once per process.
void configure_exchange();
// Throws CadError "PATH: cause": a reader's one-line error naming the file.
[[noreturn]] void fail(const std::filesystem::path& path, const std::string& cause);

}  // namespace probecomp::cad::detail
