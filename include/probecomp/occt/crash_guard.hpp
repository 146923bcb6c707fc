#pragma once
// While a CrashGuard lives, a crash inside OpenCASCADE on this thread (a null or wild pointer in a reader
// fed a malformed file: SIGSEGV, SIGBUS, SIGILL, integer SIGFPE) becomes a Standard_Failure (OSD_SIGSEGV, ...)
// thrown from the nearest OCC_CATCH_SIGNALS, instead of killing the process. OpenCASCADE's own readers
// carry OCC_CATCH_SIGNALS around each entity they transfer, so most such crashes only lose that entity.
//
// Only those four signals are taken over, and only for the guard's life: the process's handlers (Ctrl-C,
// SIGTERM, a sanitizer's SIGSEGV report) and floating-point trap settings are put back when it ends.
// Signal handlers are process-wide: a crash on another thread inside this window also meets OpenCASCADE's
// handler, so readers run under one lock (cad::read_model's exchange mutex).
//
// A stack overflow (deep recursion on a malformed file) is caught too: the handlers run on an alternate signal stack,
// the thread's own if it has one, else one the guard sets up for its life (without one the kernel cannot deliver
// the signal and ends the process without a word).
//
// Needs OCC_CONVERT_SIGNALS (set for every OpenCASCADE-facing layer in CMakeLists.txt, as OpenCASCADE
// itself is built on Linux), so that OCC_CATCH_SIGNALS places a jump target.

#include <csignal>
#include <cfenv>
#include <iterator>
#include <memory>

namespace probecomp::occt {

class CrashGuard {
 public:
  CrashGuard();
  ~CrashGuard();
  CrashGuard(const CrashGuard&) = delete;
  CrashGuard& operator=(const CrashGuard&) = delete;

 private:
  static constexpr int kTaken[] = {SIGSEGV, SIGBUS, SIGILL, SIGFPE};
  static constexpr int kLeft[] = {SIGHUP, SIGINT, SIGQUIT, SIGSYS};  // OSD::SetSignal sets these too
  struct sigaction taken_before_[std::size(kTaken)] {};
  struct sigaction left_before_[std::size(kLeft)] {};
  std::fenv_t fenv_before_{};
  std::unique_ptr<char[]> alternate_stack_;  // set up by the guard when the thread had none
};

}  // namespace probecomp::occt
