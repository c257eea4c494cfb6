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

  // The commands that scan a scenario share its arguments: scenario, --out, calibration files.
  auto scene_command = [&](const char* name, const char* what, std::string* scenario,
                           std::string* out_dir, hgrasp::app::CalibrationFiles* files) {
    CLI::App* cmd = app.add_subcommand(name, what);
    cmd->add_option("scenario", *scenario, "scenario YAML file")->required();
    cmd->add_option("--out", *out_dir, "output directory")->required();
    cmd->add_option("--cameras", files->cameras, "camera intrinsics YAML");
    cmd->add_option("--laser", files->laser, "laser calibration YAML");
    cmd->add_option("--leds", files->leds, "LED positions on the grippers YAML");
    return cmd;
  };

  hgrasp::app::ScanOptions scan;
  CLI::App* cmd_scan =
      scene_command("scan", "One stereo laser-stripe sweep: range.ply, range.png, report.json",
                    &scan.scenario, &scan.out_dir, &scan.files);
  cmd_scan->add_flag("--single-camera", scan.single_camera,
                     "light-plane triangulation from the left camera alone, no stereo validation "
                     "(for comparison)");

  hgrasp::app::ModelOptions model;
  CLI::App* cmd_model = scene_command(
      "model",
      "Scan, segment into planes and fit boxes with textures and colour: range.ply, range.png, "
      "segments.png, models.png, models.obj, report.json",
      &model.scenario, &model.out_dir, &model.files);

  hgrasp::app::ModelOptions plan;
  CLI::App* cmd_plan = scene_command(
      "plan", "As `model`, then the grasp of the target: grasp.png, the grasp in report.json",
      &plan.scenario, &plan.out_dir, &plan.files);

  hgrasp::app::RunOptions run;
  CLI::App* cmd_run = scene_command(
      "run",
      "The whole task: look, plan, approach, visual servo, grasp, lift and hold; the outputs of "
      "`plan`, servo_*.png, left.avi, the result and the servo's figures in report.json",
      &run.scenario, &run.out_dir, &run.files);
  cmd_run->add_flag(
      "--no-video", [&run](std::int64_t) { run.video = false; }, "do not write left.avi");

  hgrasp::app::EmulateOptions emulate;
  CLI::App* cmd_emulate = app.add_subcommand(
      "emulate",
      "Serve one device's emulator on a pseudo-terminal and print its port, for the real "
      "drivers (devices block of a scenario) without the hardware; stops at Ctrl-C");
  cmd_emulate->add_option("device", emulate.device, "val2, biclops, sensorhand or laser_board")
      ->required();
  cmd_emulate->add_option("--side", emulate.side, "val2: the left or right arm (default right)");
  cmd_emulate->add_option("--link", emulate.link,
                          "also make this path a symlink to the port (stable across restarts)");
  cmd_emulate->add_option("--seconds", emulate.seconds, "stop after this many seconds");

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
    if (*cmd_plan) return hgrasp::app::Plan(plan);
    if (*cmd_run) return hgrasp::app::Run(run);
    if (*cmd_emulate) return hgrasp::app::Emulate(emulate);
  } catch (const hgrasp::InputError& e) {
    std::fprintf(stderr, "hgrasp: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hgrasp: error: %s\n", e.what());
    return 1;
  }
  return 2;
}
