#include "probecomp/temporary_files.hpp"

#include <array>
#include <atomic>
#include <csignal>
#include <cstring>

#include <pthread.h>
#include <unistd.h>

namespace probecomp {

namespace {

// A run stages at most a handful of files (points, report, JSON, a surface file's own temporary); 64 leaves room
// for a library user's threads. 4096 bytes is Linux's PATH_MAX.
constexpr int kSlots = 64;
constexpr std::size_t kPathBytes = 4096;

enum SlotState : int { kFree = 0, kClaimed = 1, kReady = 2 };

struct Slot {
  std::atomic<int> state{kFree};
  char path[kPathBytes];
};

std::array<Slot, kSlots> g_slots;
std::atomic<int> g_deferring{0};
std::atomic<int> g_pending_signal{0};

constexpr int kTermination[] = {SIGINT, SIGTERM, SIGHUP};

// Async-signal-safe: unlink, signal, pthread_sigmask and raise only.
[[noreturn]] void remove_and_end(int signal) {
  for (Slot& s : g_slots) {
    if (s.state.load(std::memory_order_acquire) == kReady) ::unlink(s.path);
  }
  std::signal(signal, SIG_DFL);
  // Inside the handler the signal is blocked; unblocked, the raise takes effect at once with the default action.
  sigset_t just_this;
  sigemptyset(&just_this);
  sigaddset(&just_this, signal);
  pthread_sigmask(SIG_UNBLOCK, &just_this, nullptr);
  std::raise(signal);
  ::_exit(128 + signal);  // not reached: the default action of these signals ends the process
}

extern "C" void on_termination(int signal) {
  if (g_deferring.load(std::memory_order_acquire) > 0) {
    g_pending_signal.store(signal, std::memory_order_release);
    // The last DeferTermination may have ended between the test and the store, and so not seen it.
    if (g_deferring.load(std::memory_order_acquire) > 0 || g_pending_signal.exchange(0) == 0) return;
  }
  remove_and_end(signal);
}

}  // namespace

TemporaryFile::TemporaryFile(const std::filesystem::path& path) {
  const std::string& text = path.native();
  if (text.size() >= kPathBytes) return;
  for (int k = 0; k < kSlots; ++k) {
    int expected = kFree;
    if (g_slots[k].state.compare_exchange_strong(expected, kClaimed, std::memory_order_acq_rel)) {
      std::memcpy(g_slots[k].path, text.c_str(), text.size() + 1);
      g_slots[k].state.store(kReady, std::memory_order_release);
      slot_ = k;
      return;
    }
  }
}

TemporaryFile::~TemporaryFile() {
  if (slot_ >= 0) g_slots[slot_].state.store(kFree, std::memory_order_release);
}

TemporaryFile& TemporaryFile::operator=(TemporaryFile&& other) noexcept {
  if (this != &other) {
    if (slot_ >= 0) g_slots[slot_].state.store(kFree, std::memory_order_release);
    slot_ = other.slot_;
    other.slot_ = -1;
  }
  return *this;
}

DeferTermination::DeferTermination() { g_deferring.fetch_add(1, std::memory_order_acq_rel); }

DeferTermination::~DeferTermination() {
  if (g_deferring.fetch_sub(1, std::memory_order_acq_rel) == 1) {
    if (const int signal = g_pending_signal.exchange(0, std::memory_order_acq_rel); signal != 0) remove_and_end(signal);
  }
}

void remove_temporaries_on_termination() {
  for (const int signal : kTermination) {
    struct sigaction current {};
    sigaction(signal, nullptr, &current);
    if (current.sa_handler == SIG_IGN) continue;
    struct sigaction ours {};
    ours.sa_handler = on_termination;
    sigemptyset(&ours.sa_mask);
    for (const int other : kTermination) sigaddset(&ours.sa_mask, other);  // one handler at a time
    sigaction(signal, &ours, nullptr);
  }
}

}  // namespace probecomp
