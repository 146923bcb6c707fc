// An interrupted run leaves no partial output (issue 25): in a child process, a termination signal removes the
// temporaries io::OutputFiles staged and ends the process by that signal; while outputs are being put in place
// the signal waits; a signal the process ignores (nohup) stays ignored.

#include "probecomp/temporary_files.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>

#include <sys/wait.h>
#include <unistd.h>

#include "probecomp/io/output_files.hpp"

namespace probecomp {
namespace {

std::filesystem::path fresh_dir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::path(::testing::TempDir()) / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

// Runs `body` in a child (only this thread is copied: no thread pool there) and returns its wait status.
int in_child(const std::function<void()>& body) {
  const pid_t pid = fork();
  if (pid == 0) {
    body();
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

TEST(TemporaryFiles, ATerminationSignalRemovesStagedOutputsAndEndsTheProcessByIt) {
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
    const std::filesystem::path d = fresh_dir("temporary_files_signal");
    const int status = in_child([&] {
      remove_temporaries_on_termination();
      io::OutputFiles files;
      files.add(d / "out.csv", "x,y,z\n1,2,3\n");
      files.add_streamed(d / "out.json", [](std::ostream& o) { o << "{}"; });
      if (!std::filesystem::exists(d / "out.partial.csv")) _exit(10);  // staged, as the test assumes
      std::raise(signal);
      _exit(11);
    });
    ASSERT_TRUE(WIFSIGNALED(status)) << "signal " << signal << ", status " << status;
    EXPECT_EQ(WTERMSIG(status), signal);
    EXPECT_TRUE(std::filesystem::is_empty(d)) << "signal " << signal << ": something was left in " << d;
  }
}

TEST(TemporaryFiles, ASignalWhileOutputsArePutInPlaceWaitsForThem) {
  const std::filesystem::path d = fresh_dir("temporary_files_defer");
  const int status = in_child([&] {
    remove_temporaries_on_termination();
    io::OutputFiles files;
    files.add(d / "a.csv", "a\n");
    files.add(d / "b.csv", "b\n");
    {
      const DeferTermination all_or_none;
      std::raise(SIGTERM);
      std::ofstream(d / "still-running") << "1";
      files.commit();
    }
    _exit(12);  // not reached: the held signal ends the process once the outputs are in place
  });
  ASSERT_TRUE(WIFSIGNALED(status)) << status;
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_TRUE(std::filesystem::exists(d / "still-running"));
  EXPECT_TRUE(std::filesystem::exists(d / "a.csv"));
  EXPECT_TRUE(std::filesystem::exists(d / "b.csv"));
  EXPECT_FALSE(std::filesystem::exists(d / "a.partial.csv"));
  EXPECT_FALSE(std::filesystem::exists(d / "b.partial.csv"));
}

TEST(TemporaryFiles, AnIgnoredSignalStaysIgnored) {
  const int status = in_child([] {
    std::signal(SIGHUP, SIG_IGN);
    remove_temporaries_on_termination();
    std::raise(SIGHUP);
    _exit(7);
  });
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 7);
}

TEST(TemporaryFiles, AnOwnerThatEndsUnregistersItsFile) {
  // A file no longer staged (renamed into place, or its owner gone) is not removed by a later signal.
  const std::filesystem::path d = fresh_dir("temporary_files_released");
  const int status = in_child([&] {
    remove_temporaries_on_termination();
    {
      const TemporaryFile staged(d / "kept.txt");
      std::ofstream(d / "kept.txt") << "1";
    }
    std::raise(SIGTERM);
    _exit(13);
  });
  ASSERT_TRUE(WIFSIGNALED(status)) << status;
  EXPECT_TRUE(std::filesystem::exists(d / "kept.txt"));
}

}  // namespace
}  // namespace probecomp
