#pragma once
// Wall-clock seconds for the stage timings the pipeline and the studies report (steady clock: never jumps).

#include <chrono>

namespace probecomp::geometry {

class Stopwatch {
 public:
  Stopwatch() : start_(Clock::now()) {}
  // Seconds since construction or the last restart().
  [[nodiscard]] double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  // Seconds since the last start, and starts again.
  double restart() {
    const auto now = Clock::now();
    const double s = std::chrono::duration<double>(now - start_).count();
    start_ = now;
    return s;
  }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

}  // namespace probecomp::geometry
