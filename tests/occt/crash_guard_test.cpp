// occt::CrashGuard: a real SIGSEGV inside the guarded block becomes a Standard_Failure at OCC_CATCH_SIGNALS,
// and the process's own handlers are what they were, during the guard for the signals it leaves alone and
// after it for all.

#include "probecomp/occt/crash_guard.hpp"

#include <gtest/gtest.h>

#include <OSD_SIGSEGV.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>

#include <cmath>
#include <csignal>
#include <string>

namespace probecomp::occt {
namespace {

void (*handler_of(int signal))(int) {
  struct sigaction a {};
  sigaction(signal, nullptr, &a);
  return a.sa_handler;
}

void ours(int) {}

// A read through a null pointer the compiler cannot see coming, as in a reader that follows a broken reference.
// Not instrumented, like OpenCASCADE's own code: in the sanitizer build UndefinedBehaviorSanitizer would report the
// null load itself before any signal.
__attribute__((no_sanitize("address", "undefined"))) int read_through(volatile int* p) { return *p; }

TEST(CrashGuard, TurnsASegmentationFaultIntoAFailureAndRestoresHandlers) {
  struct sigaction mine {};
  mine.sa_handler = ours;
  struct sigaction before_int {}, before_segv {};
  sigaction(SIGINT, &mine, &before_int);
  sigaction(SIGSEGV, nullptr, &before_segv);
  std::string caught;
  {
    const CrashGuard guard;
    EXPECT_EQ(handler_of(SIGINT), &ours);  // Ctrl-C stays the process's
    EXPECT_NE(handler_of(SIGSEGV), before_segv.sa_handler);
    volatile int* volatile null = nullptr;
    try {
      OCC_CATCH_SIGNALS
      (void)read_through(null);
    } catch (const OSD_SIGSEGV& e) {
      caught = e.DynamicType()->Name();
    } catch (const Standard_Failure& e) {
      caught = std::string("other: ") + e.DynamicType()->Name();
    }
  }
  EXPECT_EQ(caught, "OSD_SIGSEGV");
  EXPECT_EQ(handler_of(SIGSEGV), before_segv.sa_handler);
  EXPECT_EQ(handler_of(SIGINT), &ours);
  sigaction(SIGINT, &before_int, nullptr);
}

// Recursion without end, as a reader might follow a cycle of references: each frame keeps a block of its stack.
// (`never` hides from the compiler that it never ends.)
volatile int never = -1;
__attribute__((no_sanitize("address", "undefined"))) int recurse(int depth) {
  if (depth == never) return 0;
  volatile char block[4096];
  block[0] = static_cast<char>(depth);
  return recurse(depth + 1) + block[0];
}

TEST(CrashGuard, TurnsAStackOverflowIntoAFailure) {
  std::string caught;
  {
    const CrashGuard guard;
    try {
      OCC_CATCH_SIGNALS
      (void)recurse(0);
    } catch (const Standard_Failure& e) {
      caught = e.DynamicType()->Name();
    }
  }
  EXPECT_EQ(caught, "OSD_SIGSEGV");
}

TEST(CrashGuard, LeavesFloatingPointTrapsOff) {
  const CrashGuard guard;
  volatile double zero = 0.0;
  EXPECT_TRUE(std::isinf(1.0 / zero));  // IEEE, no SIGFPE
}

}  // namespace
}  // namespace probecomp::occt
