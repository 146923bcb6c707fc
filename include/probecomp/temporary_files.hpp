#pragma once
// Files a run is writing that are not yet in place (io::OutputFiles' temporaries, cad::write_surfaces' own),
// kept where a signal handler can find them. Once a command has called remove_temporaries_on_termination(),
// SIGINT, SIGTERM and SIGHUP delete them and then end the process as the signal would have (status 128 + N),
// so an interrupted run leaves no partial output. A signal handler may not lock or allocate: the paths live in
// fixed slots, claimed and released with atomics.

#include <filesystem>

namespace probecomp {

// Registers `path` for removal on a termination signal, for the object's life (the file itself is not touched).
class TemporaryFile {
 public:
  explicit TemporaryFile(const std::filesystem::path& path);
  ~TemporaryFile();
  TemporaryFile(TemporaryFile&& other) noexcept : slot_(other.slot_) { other.slot_ = -1; }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  TemporaryFile& operator=(TemporaryFile&& other) noexcept;

 private:
  int slot_ = -1;  // -1: not registered (path too long, or every slot taken: the file is then only removed by
                   // its owner's destructor, as before)
};

// While one lives, a termination signal waits: the run's outputs are being renamed into place, all or none.
// The last one to end acts on a signal that came meanwhile.
class DeferTermination {
 public:
  DeferTermination();
  ~DeferTermination();
  DeferTermination(const DeferTermination&) = delete;
  DeferTermination& operator=(const DeferTermination&) = delete;
};

// Installs the handlers (SIGINT, SIGTERM, SIGHUP; a signal the process ignores, as under nohup, stays ignored).
void remove_temporaries_on_termination();

}  // namespace probecomp
