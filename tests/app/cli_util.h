#pragma once
// Runs the `hgrasp` binary as a user would, for the CLI tests.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace hgrasp::testing {

struct CliResult {
  int status = -1;
  std::string output;  // stdout and stderr
};

/// Runs `hgrasp ARGS` (the built binary) and returns its exit status and output.
inline CliResult RunHgrasp(const std::string& args) {
  CliResult r;
  const std::string cmd = std::string(HGRASP_BINARY) + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buf;
  while (fgets(buf.data(), buf.size(), pipe) != nullptr) r.output += buf.data();
  const int raw = pclose(pipe);
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return r;
}

}  // namespace hgrasp::testing
