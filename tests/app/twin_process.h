#pragma once
// `hgrasp twin` in the background, for the tests that run the robot through its real drivers
// against it: started in a folder of its own, waited for until it serves (DIR/ready), stopped
// with SIGINT (it writes DIR/twin.json) when the test is done, whatever happened.

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/fast_homing.h"

namespace hgrasp::testing {

/// A JSON file (a report, twin.json); null when it is missing or does not parse.
inline nlohmann::json ReadJson(const std::filesystem::path& p) {
  std::ifstream f(p);
  if (!f) return nullptr;
  return nlohmann::json::parse(f, nullptr, /*allow_exceptions=*/false);
}

/// A report or twin record without the keys that measure the machine rather than the run
/// (wall-clock timings, render times): what two runs of one scenario in simulated time share.
inline nlohmann::json WithoutWallTimes(nlohmann::json j) {
  if (j.is_object()) {
    for (const char* k : {"timing_s", "wall_time_s", "wall_s", "mean_render_ms", "max_render_ms"}) {
      j.erase(k);
    }
    for (auto& [k, v] : j.items()) v = WithoutWallTimes(v);
  } else if (j.is_array()) {
    for (auto& v : j) v = WithoutWallTimes(v);
  }
  return j;
}

class TwinProcess {
 public:
  /// Starts `hgrasp twin SCENARIO --dir DIR --camera-ports 0 0 --head-options FAST EXTRA...`
  /// with its output in DIR.log; false when it does not serve within `ready_s`.
  bool Start(const std::string& scenario, const std::filesystem::path& dir,
             const std::vector<std::string>& extra = {}, double ready_s = 60.0) {
    dir_ = dir;
    std::filesystem::remove_all(dir);
    std::vector<std::string> args = {HGRASP_BINARY,    "twin",           scenario, "--dir",
                                     dir.string(),     "--camera-ports", "0",      "0",
                                     "--head-options", kFastHoming};
    args.insert(args.end(), extra.begin(), extra.end());
    const std::string log = dir.string() + ".log";
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) {
        dup2(fd, 1);
        dup2(fd, 2);
      }
      std::vector<char*> argv;
      for (std::string& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(ready_s);
    while (std::chrono::steady_clock::now() < until) {
      if (std::filesystem::exists(dir / "ready")) return true;
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }

  /// Writes a control command into the twin's FIFO (e.g. "cut arm_right").
  void Control(const std::string& command) const {
    std::ofstream(dir_ / "control") << command << "\n";
  }

  /// SIGINT, then waits (SIGKILL after `limit_s`); returns twin.json (null when none).
  nlohmann::json Stop(double limit_s = 30.0) {
    if (pid_ > 0) {
      kill(pid_, SIGINT);
      const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_s);
      int status = 0;
      while (waitpid(pid_, &status, WNOHANG) != pid_) {
        if (std::chrono::steady_clock::now() > until) {
          kill(pid_, SIGKILL);
          waitpid(pid_, &status, 0);
          break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      pid_ = -1;
    }
    std::ifstream f(dir_ / "twin.json");
    if (!f) return nullptr;
    return nlohmann::json::parse(f, nullptr, /*allow_exceptions=*/false);
  }

  /// The twin's own output (its log).
  std::string Log() const {
    std::ifstream f(dir_.string() + ".log");
    return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  }

  ~TwinProcess() { Stop(5.0); }

  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  pid_t pid_ = -1;
};

}  // namespace hgrasp::testing
