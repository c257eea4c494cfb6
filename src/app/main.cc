// hgrasp: the command. Parses the command line, runs one subcommand, maps errors to exit status
// (DESIGN.md: 0 success, 1 the task failed, 2 bad input or usage).

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>
#include <system_error>
#include <vector>

#include "app/commands.h"
#include "common/error.h"

namespace {

// The twin's faults and control commands (`twin`, `run --lockstep`): app/twin_faults.h.
void AddWireOptions(CLI::App* cmd, hgrasp::app::TwinWireOptions* w) {
  cmd->add_option("--corrupt", w->corrupt,
                  "fault: probability that a byte is corrupted, per byte and direction, on every "
                  "serial line");
  cmd->add_option("--dropouts", w->dropouts_per_s,
                  "fault: mean dropouts per second on every serial line (both ways silent)");
  cmd->add_option("--dropout-s", w->dropout_s, "fault: length of a dropout (s, default 0.2)");
  cmd->add_option("--dropout-gap-s", w->dropout_gap_s,
                  "fault: least time a line works between two dropouts (s, default: one "
                  "dropout's length; 0 lets two make one longer outage)");
  cmd->add_option("--fault-seed", w->fault_seed,
                  "fault: the faults' seed (default: drawn from the scenario's seed)");
  cmd->add_option("--at", w->at,
                  "SECONDS:COMMAND: run a control command at that twin time (repeatable): "
                  "cut|cut_tx|mend|vanish|reappear DEVICE, stop|resume cameras");
}

// The message for the first word of the command line that should name a command (or a
// subcommand of one) and names none; empty when every such word is known. Options and their
// values are left to CLI11.
std::string UnknownCommand(const CLI::App& app, int argc, char** argv) {
  const CLI::App* level = &app;
  std::string path = "hgrasp";
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word[0] == '-') return "";  // an option (--help, ...): CLI11's
    const std::vector<const CLI::App*> subs = level->get_subcommands({});
    if (subs.empty()) return "";
    // A command with both subcommands and positional arguments (sweep: merge, or scenario
    // files): the word may be an argument, CLI11's to judge.
    const std::vector<const CLI::Option*> positionals =
        level->get_options([](const CLI::Option* o) { return o->get_positional(); });
    if (!positionals.empty() && level != &app) return "";
    const CLI::App* next = nullptr;
    std::string names;
    for (const CLI::App* sub : subs) {
      if (sub->check_name(word)) next = sub;
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (next == nullptr) {
      return path + ": '" + word + "' is no command; expected one of: " + names +
             " (hgrasp --help lists them)";
    }
    level = next;
    path += " " + word;
  }
  return "";
}

// --encoder's values: integer encoder counts.
std::vector<std::int32_t> EncoderCounts(const std::vector<std::string>& text) {
  std::vector<std::int32_t> counts;
  for (const std::string& s : text) {
    std::int32_t v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || end != s.data() + s.size()) {
      throw hgrasp::InputError("", "--encoder", s,
                               "an integer laser encoder count (0.01 deg per count, e.g. -500 0 "
                               "500; the laser reaches about +-4500)");
    }
    counts.push_back(v);
  }
  return counts;
}

// --at's values: "X,Y,Z", a point in W in m over the table.
std::vector<std::array<double, 3>> LookAtPoints(const std::vector<std::string>& text) {
  std::vector<std::array<double, 3>> points;
  for (const std::string& s : text) {
    std::array<double, 3> p{};
    std::size_t at = 0;
    bool ok = true;
    for (int i = 0; i < 3 && ok; ++i) {
      const std::size_t comma = i < 2 ? s.find(',', at) : s.size();
      ok = comma != std::string::npos && comma > at;
      if (!ok) break;
      const auto [end, ec] = std::from_chars(s.data() + at, s.data() + comma, p[i]);
      ok = ec == std::errc() && end == s.data() + comma && std::isfinite(p[i]);
      at = comma + 1;
    }
    if (!ok || std::abs(p[0]) > 2.0 || std::abs(p[1]) > 2.0 || p[2] < -0.5 || p[2] > 2.0) {
      throw hgrasp::InputError("", "--at", s,
                               "a point in W in m as X,Y,Z, within 2 m of the robot (e.g. "
                               "0.36,0,0.37)");
    }
    points.push_back(p);
  }
  return points;
}

// --board: "COLSxROWS", inner corners.
void BoardCorners(const std::string& text, int* cols, int* rows) {
  const std::size_t x = text.find('x');
  const auto number = [](std::string_view s, int* v) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), *v);
    return !s.empty() && ec == std::errc() && end == s.data() + s.size();
  };
  if (x == std::string::npos || !number(std::string_view(text).substr(0, x), cols) ||
      !number(std::string_view(text).substr(x + 1), rows)) {
    throw hgrasp::InputError("", "--board", text, "inner corners as COLSxROWS, e.g. 8x6");
  }
}

// --seeds: "N" or "FIRST..LAST", non-negative integers.
void SeedRange(const std::string& text, std::uint64_t* first, std::uint64_t* last) {
  const auto number = [&](std::string_view s, std::uint64_t* v) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), *v);
    return !s.empty() && ec == std::errc() && end == s.data() + s.size();
  };
  const std::size_t dots = text.find("..");
  const bool ok = dots == std::string::npos
                      ? number(text, first) && number(text, last)
                      : number(std::string_view(text).substr(0, dots), first) &&
                            number(std::string_view(text).substr(dots + 2), last);
  if (!ok) {
    throw hgrasp::InputError(
        "", "--seeds", text,
        "a seed N or a range FIRST..LAST of non-negative integers, e.g. 1..20");
  }
}

}  // namespace

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
  std::vector<std::string> encoder_text;  // parsed below, so a bad one is named with its range
  cmd_render
      ->add_option("--encoder", encoder_text,
                   "laser encoder counts to render the stripe at (0.01 deg/count)")
      ->type_name("COUNT");

  hgrasp::app::CalibrateLaserOptions calibrate;
  // --lockstep for the commands that take no wire faults (run's has its own, with them).
  const auto add_lockstep = [](CLI::App* cmd, bool* lockstep) {
    cmd->add_flag("--lockstep", *lockstep,
                  "every device on its real driver against the twin, in simulated time, in "
                  "this process (no pty)");
  };

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
  add_lockstep(cmd_calibrate_laser, &calibrate.lockstep);

  hgrasp::app::CalibrateCamerasOptions calibrate_cameras;
  CLI::App* cmd_calibrate_cameras = cmd_calibrate->add_subcommand(
      "cameras",
      "Both cameras' intrinsics from chessboards the head looks at (OpenCV stereo calibration); "
      "writes the cameras file the scanner reads");
  cmd_calibrate_cameras->add_option("scenario", calibrate_cameras.scenario, "scenario YAML file")
      ->required();
  cmd_calibrate_cameras
      ->add_option("--out", calibrate_cameras.out_file, "camera intrinsics YAML to write")
      ->required();
  cmd_calibrate_cameras->add_option("--report", calibrate_cameras.report_file,
                                    "JSON report: views, fit, and the twin's truth");
  cmd_calibrate_cameras->add_option("--views", calibrate_cameras.views_dir,
                                    "folder for each view's images with the corners found");
  std::vector<std::string> look_at_text;
  cmd_calibrate_cameras
      ->add_option("--at", look_at_text,
                   "a point in W (m) the head looks at, one per board (repeat; default: the "
                   "boards of scenarios/calibration_boards.yaml)")
      ->type_name("X,Y,Z");
  std::string board_text;
  cmd_calibrate_cameras->add_option("--board", board_text, "inner corners, COLSxROWS (default 8x6)")
      ->type_name("COLSxROWS");
  cmd_calibrate_cameras->add_option("--square-mm", calibrate_cameras.square_mm,
                                    "the board's square edge (mm, default 25)");
  cmd_calibrate_cameras->add_option("--cameras", calibrate_cameras.cameras,
                                    "the nominal camera intrinsics, for the report");
  add_lockstep(cmd_calibrate_cameras, &calibrate_cameras.lockstep);

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
  cmd_scan->add_flag("--lean", scan.lean, "only report.json (as a sweep's scenes)");
  add_lockstep(cmd_scan, &scan.lockstep);

  hgrasp::app::ModelOptions model;
  CLI::App* cmd_model = scene_command(
      "model",
      "Scan, segment into planes and fit boxes with textures and colour: range.ply, range.png, "
      "segments.png, models.png, models.obj, report.json",
      &model.scenario, &model.out_dir, &model.files);

  cmd_model->add_flag("--lean", model.lean,
                      "only report.json, segments.png and models.png (as a sweep's scenes)");
  add_lockstep(cmd_model, &model.lockstep);

  hgrasp::app::ModelOptions plan;
  CLI::App* cmd_plan = scene_command(
      "plan", "As `model`, then the grasp of the target: grasp.png, the grasp in report.json",
      &plan.scenario, &plan.out_dir, &plan.files);

  cmd_plan->add_flag("--lean", plan.lean,
                     "only report.json, segments.png and grasp.png (as a sweep's scenes)");
  add_lockstep(cmd_plan, &plan.lockstep);

  hgrasp::app::RunOptions run;
  CLI::App* cmd_run = scene_command(
      "run",
      "The whole task: look, plan, approach, visual servo, grasp, lift and hold; the outputs of "
      "`plan`, servo_*.png, left.avi, the result and the servo's figures in report.json",
      &run.scenario, &run.out_dir, &run.files);
  cmd_run->add_flag(
      "--no-video", [&run](std::int64_t) { run.video = false; }, "do not write left.avi");
  cmd_run->add_flag("--lean", run.lean,
                    "only report.json, segments.png, grasp.png and servo_*.png (as a sweep's "
                    "scenes; no video)");
  cmd_run->add_option("--command-log", run.command_log,
                      "write the state-changing commands each real driver had its device "
                      "execute into FILE (JSON, keyed as the twin's twin.json \"commands\"), "
                      "once the robot is left safe");
  cmd_run->add_flag("--lockstep", run.lockstep,
                    "every device on its real driver against the twin, in simulated time, in "
                    "this process (no pty; twin.json beside the report); with the faults and "
                    "commands below on the twin's wires");
  AddWireOptions(cmd_run, &run.wires);

  hgrasp::app::GenerateOptions generate;
  std::string generate_seeds = "1";
  CLI::App* cmd_generate = app.add_subcommand(
      "generate",
      "Write the scenario files of a scene family over a seed range (DIR/<name>.yaml), to read, "
      "keep and run");
  cmd_generate->add_option("--family", generate.family,
                           "the scene family (random_boxes, wide_boxes)");
  cmd_generate->add_option("--seeds", generate_seeds, "the seeds: N or FIRST..LAST (default 1)");
  cmd_generate->add_option("--out", generate.out_dir, "output directory")->required();

  hgrasp::app::SweepOptions sweep;
  std::string sweep_seeds, sweep_shard;
  CLI::App* cmd_sweep = app.add_subcommand(
      "sweep",
      "Many scenes, each in its own process, scored against the simulator's truth: "
      "summary.json, summary.csv, junit.xml, report.html; baselines; resumes; Slurm");
  cmd_sweep->add_option("scenarios", sweep.inputs, "scenario files, or folders of them");
  CLI::Option* sweep_family = cmd_sweep->add_option(
      "--family", sweep.family,
      "generated scenes of this family (random_boxes, wide_boxes) with --seeds");
  cmd_sweep->add_option("--seeds", sweep_seeds, "the generated scenes' seeds: N or FIRST..LAST");
  cmd_sweep->add_option("--stage", sweep.stage, "scan, model, plan or run (default run)");
  CLI::Option* sweep_out = cmd_sweep->add_option("--out", sweep.out_dir, "the sweep's folder");
  cmd_sweep->add_option("--jobs", sweep.jobs, "scene processes at once (default 1)");
  cmd_sweep->add_option("--time-limit", sweep.time_limit_s,
                        "seconds a scene may take before it is killed (default 300)");
  cmd_sweep->add_option("--cameras", sweep.files.cameras, "camera intrinsics YAML");
  cmd_sweep->add_option("--laser", sweep.files.laser, "laser calibration YAML");
  cmd_sweep->add_option("--leds", sweep.files.leds, "LED positions on the grippers YAML");
  cmd_sweep->add_option("--baseline", sweep.baseline,
                        "compare with this baseline; a regression exits 1");
  cmd_sweep->add_option("--write-baseline", sweep.write_baseline,
                        "write this sweep's figures as a baseline");
  cmd_sweep->add_flag("--lockstep", sweep.lockstep,
                      "each scene through the real drivers against the twin in simulated time "
                      "(the stage's --lockstep), scored against the twin's truth");
  cmd_sweep->add_option("--hgrasp", sweep.hgrasp,
                        "the program the scenes run with (default: this hgrasp; e.g. another "
                        "build, or a wrapper)");
  cmd_sweep->add_flag("--prepare", sweep.prepare,
                      "write the sweep's manifest and scenario files only (for --shard runs "
                      "elsewhere, e.g. GNU parallel)");
  cmd_sweep->add_flag("--slurm", sweep.slurm,
                      "submit the scenes as a Slurm job array (results in --out, which must be "
                      "shared), instead of running them here");
  cmd_sweep->add_option("--shards", sweep.shards,
                        "--slurm: array tasks (default: the scenes, at most 64)");
  cmd_sweep->add_flag("--slurm-wait", sweep.slurm_wait,
                      "--slurm: wait for the array to end, then merge");
  cmd_sweep->add_option("--sbatch-arg", sweep.sbatch_args,
                        "--slurm: an sbatch option (repeat for more), e.g. --sbatch-arg=-p "
                        "--sbatch-arg=gpu");
  cmd_sweep->add_option("--shard", sweep_shard,
                        "INDEX/COUNT: run that shard of the sweep in --out (a Slurm array task)");
  hgrasp::app::SweepMergeOptions sweep_merge;
  CLI::App* cmd_sweep_merge = cmd_sweep->add_subcommand(
      "merge", "The summary, pages and baseline of a sweep whose scenes ran elsewhere (Slurm)");
  cmd_sweep_merge->add_option("dir", sweep_merge.dir, "the sweep's folder")->required();
  cmd_sweep_merge->add_option("--baseline", sweep_merge.baseline, "compare with this baseline");
  cmd_sweep_merge->add_option("--write-baseline", sweep_merge.write_baseline,
                              "write the figures as a baseline");

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
  double emulate_seconds = 0.0;
  CLI::Option* emulate_seconds_option = cmd_emulate->add_option(
      "--seconds", emulate_seconds, "stop after this many seconds (> 0; default: at Ctrl-C)");

  hgrasp::app::TwinCommandOptions twin;
  CLI::App* cmd_twin = app.add_subcommand(
      "twin",
      "Run the scenario's world in wall-clock time and serve every device on its real wire: "
      "serial devices on ptys in --dir, cameras as GStreamer streams; then `hgrasp run "
      "DIR/scenario.yaml` runs through the real drivers against it. Stops at Ctrl-C");
  cmd_twin->add_option("scenario", twin.scenario, "scenario YAML")->required();
  cmd_twin->add_option("--dir", twin.dir,
                       "folder for the ports' links, devices.yaml, scenario.yaml, world.xml, "
                       "control and twin.json (default /tmp/hgrasp-twin)");
  cmd_twin->add_option("--rate", twin.rate,
                       "twin seconds per wall second, (0, 1]: below 1 for a slow machine");
  double twin_seconds = 0.0;
  CLI::Option* twin_seconds_option =
      cmd_twin->add_option("--seconds", twin_seconds, "stop after this much twin time (s)");
  cmd_twin->add_option("--camera-ports", twin.camera_ports,
                       "TCP ports of the left and right streams on 127.0.0.1 (0: any free; "
                       "default 5600 5601)");
  AddWireOptions(cmd_twin, &twin.wires);
  cmd_twin->add_option("--head-options", twin.head_options,
                       "the Biclops driver's options written into devices.yaml (YAML flow)");

  // A word where a command belongs that names none: said with the word and the commands (CLI11
  // would say only that a subcommand is required, or show the main help for `WORD --help`).
  if (const std::string unknown = UnknownCommand(app, argc, argv); !unknown.empty()) {
    std::fprintf(stderr, "%s\n", unknown.c_str());
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    if (*cmd_render) {
      if (!encoder_text.empty()) render.encoder_counts = EncoderCounts(encoder_text);
      return hgrasp::app::Render(render);
    }
    if (*cmd_calibrate_laser) return hgrasp::app::CalibrateLaser(calibrate);
    if (*cmd_calibrate_cameras) {
      if (!look_at_text.empty()) calibrate_cameras.look_at = LookAtPoints(look_at_text);
      if (!board_text.empty()) {
        BoardCorners(board_text, &calibrate_cameras.board_cols, &calibrate_cameras.board_rows);
      }
      return hgrasp::app::CalibrateCameras(calibrate_cameras);
    }
    if (*cmd_scan) return hgrasp::app::Scan(scan);
    if (*cmd_model) return hgrasp::app::Model(model);
    if (*cmd_plan) return hgrasp::app::Plan(plan);
    if (*cmd_run) return hgrasp::app::Run(run);
    if (*cmd_generate) {
      SeedRange(generate_seeds, &generate.first_seed, &generate.last_seed);
      return hgrasp::app::Generate(generate);
    }
    if (*cmd_sweep_merge) return hgrasp::app::SweepMerge(sweep_merge);
    if (*cmd_sweep) {
      if (sweep_out->count() == 0) {
        throw hgrasp::InputError("", "--out", "", "the sweep's folder (--out DIR)");
      }
      if (!sweep_seeds.empty()) {
        std::uint64_t first = 0, last = 0;
        SeedRange(sweep_seeds, &first, &last);
        sweep.seeds = {first, last};
      } else if (sweep_family->count() > 0) {
        throw hgrasp::InputError("", "--seeds", "", "the seeds of the --family's scenes");
      }
      if (!sweep_shard.empty()) {
        const size_t slash = sweep_shard.find('/');
        std::uint64_t index = 0, count = 0;
        const auto number = [](std::string_view t, std::uint64_t* v) {
          const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), *v);
          return !t.empty() && ec == std::errc() && end == t.data() + t.size() && *v < 1000000;
        };
        if (slash == std::string::npos ||
            !number(std::string_view(sweep_shard).substr(0, slash), &index) ||
            !number(std::string_view(sweep_shard).substr(slash + 1), &count)) {
          throw hgrasp::InputError("", "--shard", sweep_shard, "INDEX/COUNT, e.g. 3/16");
        }
        sweep.shard = {static_cast<int>(index), static_cast<int>(count)};
      }
      return hgrasp::app::Sweep(sweep);
    }
    if (*cmd_twin) {
      if (twin_seconds_option->count() > 0) twin.seconds = twin_seconds;
      return hgrasp::app::Twin(twin);
    }
    if (*cmd_emulate) {
      if (emulate_seconds_option->count() > 0) emulate.seconds = emulate_seconds;
      return hgrasp::app::Emulate(emulate);
    }
  } catch (const hgrasp::InputError& e) {
    std::fprintf(stderr, "hgrasp: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hgrasp: error: %s\n", e.what());
    return 1;
  }
  return 2;
}
