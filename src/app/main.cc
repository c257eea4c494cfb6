// hgrasp: the command. Parses the command line, runs one subcommand, maps errors to exit status
// (DESIGN.md: 0 success, 1 the task failed, 2 bad input or usage).

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>

#include "app/commands.h"
#include "common/error.h"

int main(int argc, char** argv) {
  CLI::App app{"hgrasp: a humanoid that scans, models and grasps boxes it has never seen"};
  app.require_subcommand(1);

  hgrasp::app::RenderOptions render;
  CLI::App* cmd_render =
      app.add_subcommand("render",
                         "Stereo images without and with the laser stripe, depth, "
                         "labels and ground truth from the simulated robot");
  cmd_render->add_option("scenario", render.scenario, "scenario YAML file")->required();
  cmd_render->add_option("--out", render.out_dir, "output directory")->required();
  cmd_render->add_option("--encoder", render.encoder_counts,
                         "laser encoder counts to render the stripe at (0.01 deg/count)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    if (*cmd_render) return hgrasp::app::Render(render);
  } catch (const hgrasp::InputError& e) {
    std::fprintf(stderr, "hgrasp: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hgrasp: error: %s\n", e.what());
    return 1;
  }
  return 2;
}
