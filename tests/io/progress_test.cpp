// io/progress: the line's share, rate and time left worked by hand; a short run silent, a log's lines whole, a
// terminal's bar drawn in place and cleared for a warning and on an error.

#include "probecomp/io/progress.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>

namespace probecomp::io {
namespace {

TEST(ProgressLine, ShareRateAndTimeLeftFromThePaceSoFar) {
  // A quarter of 10 219 456 points in 10 s: 255 486 points a second over the run, 30 s to go at that pace.
  EXPECT_EQ(progress_line("registration", 0.25, 10.0, 10'219'456),
            "[#####---------------]  25%  registration  10 219 456 points, 255 k/s, about 30 s left");
  // 4 s later, with no news from the stage, the time left counts down.
  EXPECT_EQ(progress_line("registration", 0.25, 10.0, 10'219'456, 4.0),
            "[#####---------------]  25%  registration  10 219 456 points, 255 k/s, about 26 s left");
  // Past the estimate nothing is promised.
  EXPECT_EQ(progress_line("fitting", 0.5, 60.0, 2'000'000, 61.0),
            "[##########----------]  50%  fitting  2 000 000 points, 17 k/s");
  // Long runs in minutes; the rate in millions.
  EXPECT_EQ(progress_line("fitting", 0.1, 1.0, 20'000'000),
            "[##------------------]  10%  fitting  20 000 000 points, 2.0 M/s, about 9 s left");
  EXPECT_EQ(progress_line("fitting", 0.1, 20.0, 1'000), "[##------------------]  10%  fitting  1 000 points, 5 /s, about 3 min 00 s left");
}

TEST(ProgressLine, NoCountBeforeThePointsAreReadAndNoGuessAtTheStart) {
  EXPECT_EQ(progress_line("reading", 0.05, 2.0, 0), "[#-------------------]   5%  reading  about 38 s left");
  // Below 2 % the pace says too little.
  EXPECT_EQ(progress_line("reading", 0.01, 2.0, 0), "[--------------------]   1%  reading");
  EXPECT_EQ(progress_line("done", 1.0, 12.0, 5), "[####################] 100%  done  5 points, 0 /s");
}

TEST(ProgressBar, ShortRunsAndQuietRunsPrintNothing) {
  std::ostringstream log, quiet;
  {
    ProgressBar bar(log, false, false);
    bar.update("registration", 0.5);
    bar.update("done", 1.0);
  }
  EXPECT_EQ(log.str(), "");  // under a second
  {
    ProgressBar bar(quiet, true, true);
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    bar.update("registration", 0.5);
  }
  EXPECT_EQ(quiet.str(), "");
}

TEST(ProgressBar, ALogGetsWholeLinesAtEachStage) {
  std::ostringstream log;
  {
    ProgressBar bar(log, false, false);
    bar.set_points(1000);
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    bar.update("fitting", 0.5);
    bar.update("fitting", 0.4);  // never backwards
    bar.print("probecomp: warning: something");
    bar.update("writing", 0.9);
  }
  const std::string s = log.str();
  EXPECT_EQ(s.find('\r'), std::string::npos);
  EXPECT_NE(s.find("probecomp: [##########----------]  50%  fitting  1 000 points"), std::string::npos) << s;
  EXPECT_NE(s.find("\nprobecomp: warning: something\n"), std::string::npos) << s;
  EXPECT_NE(s.find("probecomp: [##################--]  90%  writing"), std::string::npos) << s;
  EXPECT_EQ(s.find(" 40%"), std::string::npos) << s;
  EXPECT_EQ(s.back(), '\n');
}

TEST(ProgressBar, ATerminalsBarIsRedrawnInPlaceAndClearedOnAnError) {
  std::ostringstream tty;
  {
    ProgressBar bar(tty, true, false);
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    bar.update("registration", 0.3);
    bar.print("probecomp: warning: w");
  }
  std::string s = tty.str();
  EXPECT_NE(s.find("\r\033[Kprobecomp: [######--------------]  30%  registration"), std::string::npos) << s;
  EXPECT_NE(s.find("\r\033[Kprobecomp: warning: w\n"), std::string::npos) << s;
  EXPECT_EQ(s.back(), '\n');  // the finished bar stays, on a line of its own

  std::ostringstream failed;
  try {
    ProgressBar bar(failed, true, false);
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    bar.update("fitting", 0.6);
    throw std::runtime_error("failed");
  } catch (const std::runtime_error&) {
  }
  s = failed.str();
  EXPECT_NE(s.find("60%  fitting"), std::string::npos) << s;
  EXPECT_TRUE(s.ends_with("\r\033[K")) << s;  // the error message goes where the bar was
}

}  // namespace
}  // namespace probecomp::io
