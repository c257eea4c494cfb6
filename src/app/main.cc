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

  hgrasp::app::CalibrateLaserOptions calibrate;
  CLI::App* cmd_calibrate = app.add_subcommand("calibrate", "Self-calibration");
  cmd_calibrate->require_subcommand(1);
  CLI::App* cmd_calibrate_laser = cmd_calibrate->add_subcommand(
      "laser",
      "The laser's light plane against encoder count, from a sweep over any non-planar "
      "target (Taylor & Kleeman eq. 6)");
  cmd_calibrate_laser->add_option("scenario", calibrate.scenario, "scenario YAML file")->required();
  cmd_calibrate_laser->add_option("--out", calibrate.out_file, "laser calibration YAML to write")
      ->required();
  cmd_calibrate_laser->add_option("--cameras", calibrate.files.cameras, "camera intrinsics YAML");

  hgrasp::app::ScanOptions scan;
  CLI::App* cmd_scan = app.add_subcommand(
      "scan", "One stereo laser-stripe sweep: range.ply, range.png, report.json");
  cmd_scan->add_option("scenario", scan.scenario, "scenario YAML file")->required();
  cmd_scan->add_option("--out", scan.out_dir, "output directory")->required();
  cmd_scan->add_option("--cameras", scan.files.cameras, "camera intrinsics YAML");
  cmd_scan->add_option("--laser", scan.files.laser, "laser calibration YAML");
  cmd_scan->add_flag("--single-camera", scan.single_camera,
                     "light-plane triangulation from the left camera alone, no stereo validation "
                     "(for comparison)");

  hgrasp::app::ModelOptions model;
  CLI::App* cmd_model = app.add_subcommand(
      "model",
      "Scan, segment into planes and fit boxes with textures and colour: range.ply, range.png, "
      "segments.png, models.png, models.obj, report.json");
  cmd_model->add_option("scenario", model.scenario, "scenario YAML file")->required();
  cmd_model->add_option("--out", model.out_dir, "output directory")->required();
  cmd_model->add_option("--cameras", model.files.cameras, "camera intrinsics YAML");
  cmd_model->add_option("--laser", model.files.laser, "laser calibration YAML");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    if (*cmd_render) return hgrasp::app::Render(render);
    if (*cmd_calibrate_laser) return hgrasp::app::CalibrateLaser(calibrate);
    if (*cmd_scan) return hgrasp::app::Scan(scan);
    if (*cmd_model) return hgrasp::app::Model(model);
  } catch (const hgrasp::InputError& e) {
    std::fprintf(stderr, "hgrasp: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hgrasp: error: %s\n", e.what());
    return 1;
  }
  return 2;
}
