#include "probecomp/io/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <iostream>

namespace probecomp::io {

namespace {

constexpr double kSilentSeconds = 1.0;   // a run shorter than this prints nothing
constexpr double kRedrawSeconds = 0.25;  // a terminal's bar
constexpr double kLogSeconds = 10.0;     // a log's lines, within one stage
constexpr double kShownFraction = 0.02;  // the time left is a guess before this much is done
constexpr int kBarWidth = 20;

// 10219456 → "10 219 456" (the README's and the reports' way of writing counts).
std::string grouped(std::size_t n) {
  std::string digits = std::to_string(n), out;
  for (std::size_t k = 0; k < digits.size(); ++k) {
    if (k > 0 && (digits.size() - k) % 3 == 0) out += ' ';
    out += digits[k];
  }
  return out;
}

std::string rate_text(double per_second) {
  char s[32];
  if (per_second >= 1e6) {
    std::snprintf(s, sizeof s, "%.1f M/s", per_second / 1e6);
  } else if (per_second >= 1e3) {
    std::snprintf(s, sizeof s, "%.0f k/s", per_second / 1e3);
  } else {
    std::snprintf(s, sizeof s, "%.0f /s", per_second);
  }
  return s;
}

std::string duration_text(double seconds) {
  char s[32];
  const long whole = std::lround(seconds);
  if (whole < 60) {
    std::snprintf(s, sizeof s, "%ld s", whole);
  } else if (whole < 3600) {
    std::snprintf(s, sizeof s, "%ld min %02ld s", whole / 60, whole % 60);
  } else {
    std::snprintf(s, sizeof s, "%ld h %02ld min", whole / 3600, whole / 60 % 60);
  }
  return s;
}

}  // namespace

std::string progress_line(std::string_view stage, double fraction, double seconds, std::size_t points, double since) {
  const double f = std::clamp(fraction, 0.0, 1.0);
  const int filled = static_cast<int>(std::floor(f * kBarWidth));
  std::string line(1, '[');
  line.append(static_cast<std::size_t>(filled), '#').append(static_cast<std::size_t>(kBarWidth - filled), '-');
  line.push_back(']');
  char percent[8];
  std::snprintf(percent, sizeof percent, "%4.0f%%", 100.0 * f);
  line += percent;
  line += "  ";
  line += stage;
  if (points > 0) {
    line += "  " + grouped(points) + " points";
    // The whole run's pace: the points over the time the run takes at it.
    if (f > 0.0 && seconds > 0.0) line += ", " + rate_text(static_cast<double>(points) * f / seconds);
  }
  const double left = seconds * (1.0 - f) / std::max(f, 1e-9) - since;
  if (f >= kShownFraction && f < 1.0 && seconds > 0.0 && left >= 0.5) {
    line += (points > 0 ? ", about " : "  about ") + duration_text(left) + " left";
  }
  return line;
}

ProgressBar::ProgressBar(std::ostream& out, bool terminal, bool quiet) : out_(out), terminal_(terminal), quiet_(quiet) {
  if (!quiet_) ticker_ = std::jthread([this](const std::stop_token& stop) { tick(stop); });
}

ProgressBar::ProgressBar(bool quiet) : ProgressBar(std::cerr, isatty(STDERR_FILENO) == 1, quiet) {}

ProgressBar::~ProgressBar() {
  if (ticker_.joinable()) {
    ticker_.request_stop();
    wake_.notify_all();
    ticker_.join();
  }
  const std::lock_guard lock(mutex_);
  if (!drawn_) return;
  // On an error the message that follows takes the bar's place; after a run the finished bar stays.
  if (std::uncaught_exceptions() > 0) {
    out_ << "\r\033[K" << std::flush;
  } else {
    out_ << '\n' << std::flush;
  }
}

void ProgressBar::update(std::string_view stage, double fraction) {
  if (quiet_) return;
  const std::lock_guard lock(mutex_);
  if (fraction > fraction_) {
    fraction_ = std::min(fraction, 1.0);
    reached_ = clock_.seconds();
  }
  // A terminal's bar is redrawn by the ticker, four times a second, however often the run reports; at once for a
  // new stage.
  const bool new_stage = stage != stage_;
  stage_ = stage;
  if (!terminal_ || new_stage) draw(false);
}

void ProgressBar::set_points(std::size_t points) {
  const std::lock_guard lock(mutex_);
  points_ = points;
}

void ProgressBar::print(const std::string& line) {
  const std::lock_guard lock(mutex_);
  if (terminal_ && drawn_) out_ << "\r\033[K";
  out_ << line << '\n' << std::flush;
  drawn_ = false;
  if (terminal_ && !quiet_) draw(true);
}

void ProgressBar::draw(bool forced) {
  const double t = clock_.seconds();
  if (quiet_ || t < kSilentSeconds || stage_.empty()) return;
  const std::string line = progress_line(stage_, fraction_, reached_, points_, t - reached_);
  if (terminal_) {
    if (!forced && drawn_ && stage_ == last_stage_) return;
    last_stage_ = stage_;
    out_ << "\r\033[K" << "probecomp: " << line << std::flush;
    drawn_ = true;
  } else if (forced || stage_ != last_stage_ || t - last_line_ >= kLogSeconds) {
    out_ << "probecomp: " << line << '\n' << std::flush;
    last_stage_ = stage_;
    last_line_ = t;
  }
}

void ProgressBar::tick(const std::stop_token& stop) {
  std::unique_lock lock(mutex_);
  while (!stop.stop_requested()) {
    // The time left goes on counting down (and the log gets its line) while a stage reports nothing.
    wake_.wait_for(lock, stop, std::chrono::duration<double>(terminal_ ? kRedrawSeconds : 1.0), [] { return false; });
    if (stop.stop_requested()) break;
    draw(terminal_);
  }
}

}  // namespace probecomp::io
