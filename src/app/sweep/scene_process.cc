#include "app/sweep/scene_process.h"

#include <fcntl.h>
#include <signal.h>
#include <cstring>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <stdexcept>

namespace hgrasp::app::sweep {
namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace

SceneProcess::SceneProcess(const std::vector<std::string>& argv, const std::string& log_path,
                           double time_limit_s)
    : time_limit_s_(time_limit_s), start_(Clock::now()) {
  if (argv.empty()) throw std::invalid_argument("SceneProcess: no program");
  const int log = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log < 0) {
    throw std::runtime_error("cannot write " + log_path + ": " + std::strerror(errno));
  }
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  // Everything the child needs is made before fork: between fork and exec only
  // async-signal-safe calls.
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(log);
    throw std::runtime_error(std::string("cannot start a scene process: ") + std::strerror(errno));
  }
  if (pid == 0) {
    ::setpgid(0, 0);
    // The sweep's handlers are not the scene's: default SIGINT/SIGTERM, nothing blocked.
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    const int devnull = ::open("/dev/null", O_RDONLY);
    if (devnull >= 0) ::dup2(devnull, 0);
    ::dup2(log, 1);
    ::dup2(log, 2);
    ::execv(args[0], args.data());
    const char msg[] = "sweep: cannot run the scene's program\n";
    [[maybe_unused]] const ssize_t n = ::write(2, msg, sizeof msg - 1);
    ::_exit(127);
  }
  ::setpgid(pid, pid);  // also here, so that no signal to the group can come before the child's
  ::close(log);
  pid_ = pid;
  running_ = true;
}

SceneProcess::~SceneProcess() {
  if (!running_) return;
  Signal(SIGKILL);
  int status = 0;
  ::waitpid(pid_, &status, 0);
}

void SceneProcess::Signal(int sig) {
  // The whole group: whatever the scene started goes too.
  if (::kill(-pid_, sig) != 0) ::kill(pid_, sig);
}

void SceneProcess::Stop() {
  if (!running_ || term_sent_) return;
  outcome_.stopped = true;
  Signal(SIGTERM);
  term_sent_ = Clock::now();
}

bool SceneProcess::Poll() {
  if (!running_) return true;
  int status = 0;
  const pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r == pid_) {
    running_ = false;
    outcome_.wall_s = Since(start_);
    if (WIFEXITED(status)) outcome_.exit_code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) outcome_.signal = WTERMSIG(status);
    if (outcome_.timed_out || outcome_.stopped) outcome_.signal.reset();
    // Leftovers of the group (a scene's own children) go with it.
    ::kill(-pid_, SIGKILL);
    return true;
  }
  if (!term_sent_ && time_limit_s_ > 0 && Since(start_) > time_limit_s_) {
    outcome_.timed_out = true;
    Signal(SIGTERM);
    term_sent_ = Clock::now();
  } else if (term_sent_ && Since(*term_sent_) > kGraceS) {
    Signal(SIGKILL);
  }
  return false;
}

std::string SignalName(int sig) {
  switch (sig) {
    case SIGSEGV: return "SIGSEGV";
    case SIGABRT: return "SIGABRT";
    case SIGKILL: return "SIGKILL";
    case SIGTERM: return "SIGTERM";
    case SIGINT: return "SIGINT";
    case SIGBUS: return "SIGBUS";
    case SIGFPE: return "SIGFPE";
    case SIGILL: return "SIGILL";
    case SIGPIPE: return "SIGPIPE";
    default: return "signal " + std::to_string(sig);
  }
}

}  // namespace hgrasp::app::sweep
