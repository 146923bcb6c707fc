#pragma once
// The files one run writes, written together or not at all: each is first written whole to a temporary file beside
// its destination, and only when every one of them has been written are they renamed into place, so a run that
// fails at any point (a result that cannot be computed, a JSON path that cannot be written) leaves no output of
// its own behind and the destinations as they were. And before anything runs, no destination may name one of the
// run's inputs: a measurement is never overwritten by a result.

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "probecomp/temporary_files.hpp"

namespace probecomp::io {

// A file the run reads or writes, and the option that named it (for the error message).
struct NamedPath {
  std::string option;  // e.g. "--points"
  std::filesystem::path path;
};

// Throws std::invalid_argument when an output names an input (the same path, or the same file through another
// path or a link) or two outputs name the same file. Empty paths (standard output, an option not given) are
// skipped. Call it before reading anything.
void check_outputs_spare_inputs(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs);

class OutputFiles {
 public:
  OutputFiles() = default;
  OutputFiles(const OutputFiles&) = delete;
  OutputFiles& operator=(const OutputFiles&) = delete;
  // Removes the temporary files of a run that did not commit.
  ~OutputFiles();

  // Writes `text` to the destination's temporary file now; throws InputError naming the destination if it cannot.
  void add(const std::filesystem::path& destination, const std::string& text);
  // The same for a writer that streams (a million rows need not be one string first): `write` is given the
  // temporary file's stream; a failure to open, write or flush it (a full disk, a read-only directory) is an
  // InputError naming the destination and the system's reason.
  void add_streamed(const std::filesystem::path& destination, const std::function<void(std::ostream&)>& write);
  // The same for a file written by another writer (e.g. cad::write_surfaces): `write` is given the temporary
  // path, which keeps the destination's extension.
  void add(const std::filesystem::path& destination, const std::function<void(const std::filesystem::path&)>& write);
  // Renames every temporary file to its destination, in the order added, with termination signals held until
  // the last is in place (DeferTermination). (A rename that fails midway, which
  // needs the file system to change under the run, leaves the earlier destinations replaced; it is reported.)
  void commit();

 private:
  struct Staged {
    std::filesystem::path destination, temporary;
    TemporaryFile interrupt_removes;  // the temporary, removed by SIGINT/SIGTERM before it is in place
  };
  std::vector<Staged> staged_;
};

}  // namespace probecomp::io
