#pragma once
/// @file A driver's record of the state-changing commands it had its device execute, in the
/// order it sent them, each once. Every entry is either confirmed (the driver knows the device
/// executed it: an echo, a reply, or its own resolution of a lost answer) or unconfirmed (sent,
/// and the driver cannot know whether it ran: a blind re-send of an idempotent command, a stop
/// typed to a silent line, a command whose outcome it never learnt). A command the driver
/// learns did not run is not in the log.
///
/// So the log and the device's own record of what it executed (the emulators' logs) compare
/// exactly: every confirmed entry is one executed command, every unconfirmed one is one or none,
/// in order, and nothing else ran. Each driver's header says what it records and in which
/// encoding (the emulator's of the same device).
///
/// Thread-safe: a driver's I/O thread writes while the composition root takes a snapshot.

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace hgrasp::drivers {

/// A byte command as the logs' JSON spells it (hgrasp run --command-log, the twin's
/// twin.json): lowercase hex, two digits a byte.
inline std::string HexBytes(std::span<const std::uint8_t> bytes) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string s;
  s.reserve(2 * bytes.size());
  for (std::uint8_t b : bytes) {
    s.push_back(kDigits[b >> 4]);
    s.push_back(kDigits[b & 15]);
  }
  return s;
}

template <class Command>
class CommandLog {
 public:
  struct Entry {
    Command command;
    bool confirmed = true;
  };
  /// A place in the log for a command sent whose outcome comes later (Resolve).
  using Id = std::size_t;

  /// The device executed `command`.
  void Executed(Command command) { Add(std::move(command), State::kConfirmed); }
  /// `command` was sent; whether the device executed it, the driver cannot know.
  void Unconfirmed(Command command) { Add(std::move(command), State::kUnconfirmed); }
  /// `command` is being sent; Resolve tells its outcome later, in this place of the order.
  /// Unresolved, it counts as unconfirmed.
  Id Sent(Command command) { return Add(std::move(command), State::kUnconfirmed); }
  /// The outcome of a command from Sent: executed (confirmed), or not (it leaves the log).
  void Resolve(Id id, bool executed) {
    std::lock_guard<std::mutex> lock(mu_);
    if (id < entries_.size()) entries_[id].second = executed ? State::kConfirmed : State::kGone;
  }
  /// The entries so far, in the order sent.
  std::vector<Entry> Snapshot() const {
    std::lock_guard<std::mutex> lock(mu_);
    std::vector<Entry> out;
    out.reserve(entries_.size());
    for (const auto& [command, state] : entries_) {
      if (state != State::kGone) out.push_back({command, state == State::kConfirmed});
    }
    return out;
  }

 private:
  enum class State { kConfirmed, kUnconfirmed, kGone };

  Id Add(Command command, State state) {
    std::lock_guard<std::mutex> lock(mu_);
    entries_.emplace_back(std::move(command), state);
    return entries_.size() - 1;
  }

  mutable std::mutex mu_;
  std::vector<std::pair<Command, State>> entries_;
};

/// Whether `device`, what a device executed in order, is what `log` says it executed: each
/// confirmed entry once, each unconfirmed entry once or not at all, in order, and nothing else.
/// `same(command, record)` compares a log entry's command with one of the device's records.
template <class Command, class Record, class Same>
bool LogExplains(const std::vector<typename CommandLog<Command>::Entry>& log,
                 const std::vector<Record>& device, Same same) {
  const std::size_t n = log.size(), m = device.size();
  // ok[i][j]: log[i..] explains device[j..] (filled from the ends).
  std::vector<std::vector<char>> ok(n + 1, std::vector<char>(m + 1, 0));
  ok[n][m] = 1;
  for (std::size_t i = n; i-- > 0;) {
    for (std::size_t j = m + 1; j-- > 0;) {
      const bool ran = j < m && same(log[i].command, device[j]) && ok[i + 1][j + 1];
      ok[i][j] = ran || (!log[i].confirmed && ok[i + 1][j]);
    }
  }
  return ok[0][0] != 0;
}

}  // namespace hgrasp::drivers
