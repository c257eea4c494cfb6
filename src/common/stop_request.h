#pragma once
/// @file A request to stop early, made asynchronously (from a SIGINT or SIGTERM handler, or
/// another thread) and polled by the long-running stages: the scan's sweep and the task's waits
/// end at their next frame with device::Status::kInterrupted / task::Failure::kInterrupted, so
/// the composition root can leave the robot safe and write the report (DESIGN.md rule 8).

#include <atomic>
#include <csignal>
#include <string>

namespace hgrasp {

class StopRequest {
 public:
  /// Asks for the stop; `signal` is the signal number that asked (0: not a signal). Safe to
  /// call from a signal handler (one lock-free atomic store). The first request is kept.
  void Request(int signal = 0) noexcept {
    int none = kNone;
    signal_.compare_exchange_strong(none, signal);
  }
  bool requested() const noexcept { return signal_.load() != kNone; }
  /// The signal that asked, or 0.
  int signal() const noexcept {
    const int s = signal_.load();
    return s == kNone ? 0 : s;
  }
  /// "SIGINT", "SIGTERM", "signal N" or "stop requested".
  std::string Reason() const {
    switch (signal()) {
      case SIGINT:
        return "SIGINT";
      case SIGTERM:
        return "SIGTERM";
      case 0:
        return "stop requested";
      default:
        return "signal " + std::to_string(signal());
    }
  }

 private:
  static constexpr int kNone = -1;
  std::atomic<int> signal_{kNone};
  static_assert(std::atomic<int>::is_always_lock_free, "a signal handler needs a lock-free flag");
};

/// Whether `stop` (may be null: never) has been requested.
inline bool StopRequested(const StopRequest* stop) { return stop != nullptr && stop->requested(); }

}  // namespace hgrasp
