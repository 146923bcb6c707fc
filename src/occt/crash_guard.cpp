#include "probecomp/occt/crash_guard.hpp"

#include <OSD.hxx>

namespace probecomp::occt {

CrashGuard::CrashGuard() {
  std::fegetenv(&fenv_before_);
  for (std::size_t k = 0; k < std::size(kTaken); ++k) sigaction(kTaken[k], nullptr, &taken_before_[k]);
  for (std::size_t k = 0; k < std::size(kLeft); ++k) sigaction(kLeft[k], nullptr, &left_before_[k]);
  // false: no floating-point traps; our numerics expect IEEE infinities and NaNs, not SIGFPE.
  OSD::SetSignal(OSD_SignalMode_Set, false);
  for (std::size_t k = 0; k < std::size(kLeft); ++k) sigaction(kLeft[k], &left_before_[k], nullptr);
  std::fesetenv(&fenv_before_);
}

CrashGuard::~CrashGuard() {
  for (std::size_t k = 0; k < std::size(kTaken); ++k) sigaction(kTaken[k], &taken_before_[k], nullptr);
  std::fesetenv(&fenv_before_);
}

}  // namespace probecomp::occt
