#pragma once
/// @file The `hgrasp` subcommands. Each returns the process exit status: 0 success, 1 the task
/// failed, 2 bad input or usage (DESIGN.md, "The command").

#include <cstdint>
#include <string>
#include <vector>

namespace hgrasp::app {

struct RenderOptions {
  std::string scenario;                            ///< scenario YAML path
  std::string out_dir;                             ///< created if missing
  std::vector<std::int32_t> encoder_counts = {0};  ///< laser positions to render the stripe at
};

/// `hgrasp render`: stereo images without and with the stripe, depth and label images, and
/// truth.json, from the simulated robot in its home pose.
int Render(const RenderOptions& options);

}  // namespace hgrasp::app
