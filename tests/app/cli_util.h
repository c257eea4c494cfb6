#pragma once
// Runs the `hgrasp` binary as a user would, for the CLI tests.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace hgrasp::testing {

struct CliResult {
  int status = -1;
  std::string output;  // stdout and stderr
};

/// Runs `hgrasp ARGS` (the built binary) and returns its exit status and output. With
/// `limit_s` > 0 the command is killed after that long (status 124), so a hang fails the test
/// instead of stopping the suite. `env`: "NAME=value ..." set for the command only.
inline CliResult RunHgrasp(const std::string& args, int limit_s = 0, const std::string& env = "") {
  CliResult r;
  const std::string limit = limit_s > 0 ? "timeout " + std::to_string(limit_s) + " " : "";
  const std::string cmd =
      (env.empty() ? "" : "env " + env + " ") + limit + std::string(HGRASP_BINARY) + " " + args +
      " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buf;
  while (fgets(buf.data(), buf.size(), pipe) != nullptr) r.output += buf.data();
  const int raw = pclose(pipe);
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return r;
}

/// A file's whole text ("" when it cannot be read).
inline std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace hgrasp::testing
