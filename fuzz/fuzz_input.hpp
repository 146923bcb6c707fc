#pragma once
// What every fuzz target shares: the readers take a path, so the input is written to a file of the right extension
// first; a reader may refuse the input with probecomp's own error (the one-line message users see), never with
// anything else, a crash or a sanitizer report.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "probecomp/error.hpp"

namespace probecomp::fuzz {

// Writes the input to a file named for this process with `extension`, calls `read(path)`, and lets only
// probecomp::Error through (anything else escapes and libFuzzer reports it as a crash).
template <class Read>
int read_input(const std::uint8_t* data, std::size_t size, const char* extension, Read&& read) {
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("probecomp-fuzz-" + std::to_string(::getpid()) + extension);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    read(path);
  } catch (const probecomp::Error&) {
    // A refusal with a one-line reason is the right answer to a malformed file.
  }
  return 0;
}

}  // namespace probecomp::fuzz
