#include "probecomp/occt/crash_guard.hpp"

#include <OSD.hxx>

namespace probecomp::occt {

namespace {
// OpenCASCADE's handler builds its exception (a message, a handle) on this stack before it jumps; 256 KiB leaves it
// room many times over.
constexpr std::size_t kAlternateStackBytes = 256 * 1024;
}  // namespace

CrashGuard::CrashGuard() {
  std::fegetenv(&fenv_before_);
  for (std::size_t k = 0; k < std::size(kTaken); ++k) sigaction(kTaken[k], nullptr, &taken_before_[k]);
  for (std::size_t k = 0; k < std::size(kLeft); ++k) sigaction(kLeft[k], nullptr, &left_before_[k]);
  // false: no floating-point traps; our numerics expect IEEE infinities and NaNs, not SIGFPE.
  OSD::SetSignal(OSD_SignalMode_Set, false);
  for (std::size_t k = 0; k < std::size(kLeft); ++k) sigaction(kLeft[k], &left_before_[k], nullptr);
  for (const int signal : kTaken) {
    struct sigaction occt {};
    sigaction(signal, nullptr, &occt);
    occt.sa_flags |= SA_ONSTACK;
    sigaction(signal, &occt, nullptr);
  }
  stack_t current{};
  if (sigaltstack(nullptr, &current) == 0 && (current.ss_flags & SS_DISABLE)) {
    alternate_stack_ = std::make_unique<char[]>(kAlternateStackBytes);
    stack_t ours{};
    ours.ss_sp = alternate_stack_.get();
    ours.ss_size = kAlternateStackBytes;
    if (sigaltstack(&ours, nullptr) != 0) alternate_stack_.reset();
  }
  std::fesetenv(&fenv_before_);
}

CrashGuard::~CrashGuard() {
  for (std::size_t k = 0; k < std::size(kTaken); ++k) sigaction(kTaken[k], &taken_before_[k], nullptr);
  if (alternate_stack_) {
    stack_t none{};
    none.ss_flags = SS_DISABLE;
    sigaltstack(&none, nullptr);
  }
  std::fesetenv(&fenv_before_);
}

}  // namespace probecomp::occt
