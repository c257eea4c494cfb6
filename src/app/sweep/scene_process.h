#pragma once
/// @file One scene of a sweep in its own process: `hgrasp STAGE FILE --out DIR --lean`, in a
/// process group of its own (a terminal's Ctrl-C reaches only the sweep, which stops its scenes
/// itself), its output in a log file, killed when it runs past its time limit. Whatever the
/// scene does (crashes, hangs, exits 2 on a bad file) is an outcome, never the sweep's end.

#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace hgrasp::app::sweep {

/// How a scene's process ended.
struct ProcessOutcome {
  std::optional<int> exit_code;  ///< when it exited
  std::optional<int> signal;     ///< when a signal ended it (and it was not our time limit)
  bool timed_out = false;        ///< killed at the time limit
  bool stopped = false;          ///< killed because the sweep was asked to stop
  double wall_s = 0;
};

/// A started scene process. The destructor kills a process still running (and its group).
class SceneProcess {
 public:
  /// Starts `argv` (argv[0] the program's path) with stdout and stderr to `log_path`.
  /// @throws std::runtime_error when it cannot be started (the program is missing, no process).
  SceneProcess(const std::vector<std::string>& argv, const std::string& log_path,
               double time_limit_s);
  ~SceneProcess();
  SceneProcess(const SceneProcess&) = delete;
  SceneProcess& operator=(const SceneProcess&) = delete;

  /// Checks the process without blocking: true once it has ended (outcome() is then set).
  /// Past the time limit it is sent SIGTERM (it leaves the robot safe and reports), then, after
  /// kGraceS, SIGKILL; it then counts as timed out.
  bool Poll();
  /// Asks it to stop now (SIGTERM, SIGKILL after kGraceS): the sweep is being stopped.
  void Stop();
  const ProcessOutcome& outcome() const { return outcome_; }
  pid_t pid() const { return pid_; }

  /// Seconds between SIGTERM and SIGKILL.
  static constexpr double kGraceS = 5.0;

 private:
  void Signal(int sig);

  pid_t pid_ = -1;
  bool running_ = false;
  double time_limit_s_;
  std::chrono::steady_clock::time_point start_;
  std::optional<std::chrono::steady_clock::time_point> term_sent_;
  ProcessOutcome outcome_;
};

/// "SIGSEGV", "SIGKILL", ... or "signal N".
std::string SignalName(int sig);

}  // namespace hgrasp::app::sweep
