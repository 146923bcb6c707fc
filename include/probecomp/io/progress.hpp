#pragma once
// A long run's progress on standard error: the stage, the share of the whole command done, the points a second
// and the time left. On a terminal one line redrawn in place four times a second; in a log (not a terminal) a line
// at each new stage and every 10 s. Silent for a run's first second (short runs print nothing) and with --quiet.

#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <ostream>
#include <string>
#include <string_view>
#include <thread>

#include "probecomp/geometry/stopwatch.hpp"

namespace probecomp::io {

// One progress line, e.g. "[######--------------]  31%  registration  10 219 456 points, 152 k/s, about 45 s left":
// `fraction` of the whole run was done after `seconds`, and `since` seconds have passed from then; `points` 0
// while not yet known (the rate and count are left out). The time left is the pace until `fraction` carried to the
// end, less `since` (it counts down while a stage reports nothing); shown once 2 % is done, until it runs out.
[[nodiscard]] std::string progress_line(std::string_view stage, double fraction, double seconds, std::size_t points,
                                        double since = 0.0);

class ProgressBar {
 public:
  // `terminal`: `out` is a terminal (redrawn in place), else a log. With `quiet` nothing is ever written.
  ProgressBar(std::ostream& out, bool terminal, bool quiet);
  // For standard error, a terminal when isatty(2) says so.
  explicit ProgressBar(bool quiet);
  // Stops the redrawing; on a terminal the line is cleared when an exception is unwinding (the error message takes
  // its place), else left standing with a line end.
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // The whole run's share done (0 to 1; a smaller one than before is ignored) and its stage. Any thread.
  void update(std::string_view stage, double fraction);
  // The number of points, once read: the rate is given from then on.
  void set_points(std::size_t points);
  // A line of text (a warning) on the same stream, without tearing the bar.
  void print(const std::string& line);

 private:
  void draw(bool forced);  // with mutex_ held
  void tick(const std::stop_token& stop);

  std::ostream& out_;
  bool terminal_ = false, quiet_ = false;
  geometry::Stopwatch clock_;
  std::mutex mutex_;
  std::condition_variable_any wake_;
  std::string stage_, last_stage_;
  double fraction_ = 0.0;
  double reached_ = 0.0;     // when fraction_ was reached, s
  std::size_t points_ = 0;
  double last_line_ = -1.0;  // when the last line went to a log, s
  bool drawn_ = false;       // a bar stands on the terminal's current line
  std::jthread ticker_;
};

}  // namespace probecomp::io
