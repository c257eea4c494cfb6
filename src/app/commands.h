#pragma once
/// @file The `hgrasp` subcommands. Each returns the process exit status: 0 success, 1 the task
/// failed, 2 bad input or usage (DESIGN.md, "The command").

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "app/twin_faults.h"

namespace hgrasp::app {

struct RenderOptions {
  std::string scenario;                            ///< scenario YAML path
  std::string out_dir;                             ///< created if missing
  std::vector<std::int32_t> encoder_counts = {0};  ///< laser positions to render the stripe at
};

/// `hgrasp render`: stereo images without and with the stripe, depth and label images, and
/// truth.json, from the simulated robot in its home pose.
int Render(const RenderOptions& options);

/// Calibration files the pipeline reads (the simulated robot's by default).
struct CalibrationFiles {
  std::string cameras = "calibration/sim/cameras.yaml";
  std::string laser = "calibration/sim/laser.yaml";
  std::string leds = "calibration/sim/leds.yaml";  ///< LED positions on each gripper
};

struct CalibrateLaserOptions {
  std::string scenario;  ///< a scene with a non-planar target
  std::string out_file;  ///< the laser calibration YAML to write
  CalibrationFiles files;
  /// Every device on its real driver against the twin in simulated time, in this process
  /// (app/devices.h: OpenRobot's lockstep, with clean wires).
  bool lockstep = false;
};

/// `hgrasp calibrate laser`: the laser's self-calibration (paper eq. 6) over a sweep.
int CalibrateLaser(const CalibrateLaserOptions& options);

struct CalibrateCamerasOptions {
  std::string scenario;  ///< a scene with chessboards on stands (scenarios/calibration_boards.yaml)
  std::string out_file;  ///< the camera intrinsics YAML to write
  std::string report_file;  ///< optional: the views, the fit and (on the twin) its truth, as JSON
  std::string views_dir;    ///< optional: each view's images with the corners found, as PNGs
  /// Points in W (m) the head looks at, one per board; from each, kPosesPerPoint head poses.
  /// The default: the boards of scenarios/calibration_boards.yaml.
  std::vector<std::array<double, 3>> look_at = {
      {0.241, -0.251, 0.371}, {0.358, 0.0, 0.371}, {0.241, 0.251, 0.371}};
  int board_cols = 8, board_rows = 6;  ///< inner corners
  double square_mm = 25.0;
  std::string cameras = "calibration/sim/cameras.yaml";  ///< nominal: only for the report
  /// Every device on its real driver against the twin in simulated time, in this process
  /// (app/devices.h: OpenRobot's lockstep, with clean wires).
  bool lockstep = false;
};

/// `hgrasp calibrate cameras`: stereo calibration from chessboards the head looks at.
int CalibrateCameras(const CalibrateCamerasOptions& options);

struct ScanOptions {
  std::string scenario;
  std::string out_dir;
  CalibrationFiles files;
  bool single_camera = false;  ///< light-plane triangulation from the left camera only
  bool lean = false;           ///< only report.json (a sweep's scene): no range.ply, range.png
  /// Every device on its real driver against the twin in simulated time, in this process
  /// (app/devices.h: OpenRobot's lockstep, with clean wires).
  bool lockstep = false;
};

/// `hgrasp scan`: one laser sweep: range.ply, range.png and report.json.
int Scan(const ScanOptions& options);

struct ModelOptions {
  std::string scenario;
  std::string out_dir;
  CalibrationFiles files;
  /// Only report.json and the pictures a sweep's page shows (segments.png, models.png or
  /// grasp.png); no range.ply, range.png or models.obj.
  bool lean = false;
  /// Every device on its real driver against the twin in simulated time, in this process
  /// (app/devices.h: OpenRobot's lockstep, with clean wires).
  bool lockstep = false;
};

/// `hgrasp model`: a scan, its planar segmentation and the boxes fitted to it: range.ply,
/// range.png, segments.png, models.png, models.obj (+ .mtl, textures) and report.json with the
/// boxes and the target.
int Model(const ModelOptions& options);

/// `hgrasp plan`: `hgrasp model`, then the grasp of the target (paper 5.3): grasp.png and the
/// grasp in report.json; exit 1 when no grasp is reachable.
int Plan(const ModelOptions& options);

struct RunOptions {
  std::string scenario;
  std::string out_dir;
  CalibrationFiles files;
  bool video = true;  ///< write left.avi, the left camera through the whole run
  /// As ModelOptions::lean (and no left.avi): report.json, segments.png, grasp.png, servo_*.png.
  bool lean = false;
  /// Where to write the real drivers' command logs (app::CommandLogs) once the robot is left
  /// safe; "" for none.
  std::string command_log;
  /// Every device on its real driver against the twin in simulated time, in this process
  /// (app/devices.h); the twin's report (truth, its command logs) written as twin.json.
  bool lockstep = false;
  /// With lockstep: faults on the twin's serial lines and control commands at twin times.
  TwinWireOptions wires;
};

/// `hgrasp run`: the whole task (look, plan, approach, servo, close, lift): the outputs of
/// `hgrasp plan`, servo_*.png (Figure 9: the tracked and the target hand over the left image at
/// key moments), left.avi and report.json with the result, the servo's figures and timings;
/// exit 1 when the task failed (the failure named in the report).
int Run(const RunOptions& options);

struct GenerateOptions {
  std::string family = "random_boxes";          ///< a scene family (kSceneFamilies)
  std::uint64_t first_seed = 1, last_seed = 1;  ///< the seed range, inclusive
  std::string out_dir;
};

/// Scene families `hgrasp generate` draws from: random_boxes is sim::RandomBoxScene, wide_boxes
/// sim::WideBoxScene (drawn more widely: perturbed colours, close and near-square boxes, light,
/// noise, other robots' stripes, walls).
inline constexpr const char* kSceneFamilies[] = {"random_boxes", "wide_boxes"};
/// Most scenes one `hgrasp generate` writes.
inline constexpr std::uint64_t kMaxGenerate = 100000;

/// Checks a family name and seed range (`--family`, `--seeds`).
/// @throws hgrasp::InputError naming the option.
void CheckFamily(const std::string& family, std::uint64_t first_seed, std::uint64_t last_seed);
/// One scene of a (checked) family. The wide family's target is one the robot's model can grasp
/// (grasp::PlanGrasp on the true boxes), drawn again until it is.
sim::Scenario FamilyScenario(const std::string& family, std::uint64_t seed);
/// The scenario file of one scene of a (checked) family: its YAML into *yaml; returns its name.
std::string FamilyScene(const std::string& family, std::uint64_t seed, std::string* yaml);

/// `hgrasp generate`: writes the scenario file of every seed of a family (DIR/<name>.yaml), so a
/// user can read, keep and run them; all or none.
int Generate(const GenerateOptions& options);

struct SweepOptions {
  /// Scenario files, and folders whose *.yaml files are taken (sorted by name).
  std::vector<std::string> inputs;
  /// Generated scenes: a family (kSceneFamilies) over a seed range, written to DIR/scenarios/.
  std::string family = "random_boxes";
  std::optional<std::pair<std::uint64_t, std::uint64_t>> seeds;
  std::string stage = "run";  ///< scan, model, plan or run
  std::string out_dir;
  int jobs = 1;               ///< scene processes at once
  double time_limit_s = 300;  ///< a scene's process is killed after this long (s)
  CalibrationFiles files;
  std::string baseline;        ///< compare with this baseline; regressions exit 1
  std::string write_baseline;  ///< write the sweep's baseline here
  std::string hgrasp;          ///< the program each scene runs with (default: this hgrasp)
  /// Each scene through the real drivers against the twin in lockstep (`STAGE --lockstep`).
  bool lockstep = false;
  /// This process runs shard index/count of the sweep in out_dir (a Slurm array task): its
  /// scenes only, no summary (`hgrasp sweep merge` writes it).
  std::optional<std::pair<int, int>> shard;
  /// Write the manifest and the generated scenario files, run nothing (the shards then run by
  /// --shard on other machines, e.g. through GNU parallel).
  bool prepare = false;
  bool slurm = false;                    ///< submit a job array instead of running here
  int shards = 0;                        ///< array tasks (0: min(scenes, kDefaultShards))
  bool slurm_wait = false;               ///< wait for the array to end (squeue), then merge
  std::vector<std::string> sbatch_args;  ///< more sbatch options (partition, account, ...)
};

/// Array tasks of a Slurm sweep when --shards is not given: at most this many.
inline constexpr int kDefaultShards = 64;
/// Most scene processes at once (--jobs).
inline constexpr int kMaxJobs = 256;

/// `hgrasp sweep`: runs each scene in its own process up to `stage`, scores it against the
/// simulator's truth, and writes summary.json, summary.csv, junit.xml and report.html in
/// out_dir (README, "hgrasp sweep"). Resumes a stopped sweep in the same folder. Exit 0 when
/// every scene has its row and no baseline figure regressed; 1 when stopped or regressed.
int Sweep(const SweepOptions& options);

struct SweepMergeOptions {
  std::string dir;
  std::string baseline, write_baseline;
};

/// `hgrasp sweep merge DIR`: the outputs of a sweep whose scenes ran elsewhere (Slurm shards).
int SweepMerge(const SweepMergeOptions& options);

struct EmulateOptions {
  std::string device;          ///< val2, biclops, sensorhand or laser_board
  std::string side = "right";  ///< val2: which arm's controller (its kinematics)
  std::string link;            ///< optional stable path: a symlink to the pty
  /// Stop after this long (s; positive, finite, at most kMaxEmulateSeconds); without it, at
  /// SIGINT or SIGTERM.
  std::optional<double> seconds;
};

struct TwinCommandOptions {
  std::string scenario;
  std::string dir = "/tmp/hgrasp-twin";  ///< the ports folder (pty links, devices.yaml, ...)
  double rate = 1.0;                     ///< twin seconds per wall second, (0, 1]
  std::optional<double> seconds;         ///< stop after this long (twin time); else at a signal
  std::string camera_host = "127.0.0.1";
  std::array<int, 2> camera_ports = {5600, 5601};  ///< TCP ports of the streams (0: any free)
  TwinWireOptions wires;     ///< faults on the serial lines, control commands at twin times
  std::string head_options;  ///< the Biclops driver's options in devices.yaml (YAML flow)
};

/// `hgrasp twin`: the twin behind the real wires (src/app/twin_command.cc).
int Twin(const TwinCommandOptions& options);

/// Longest --seconds (s): about 11.6 days.
inline constexpr double kMaxEmulateSeconds = 1e6;

/// `hgrasp emulate`: serves one device emulator on a pseudo-terminal and prints the port's path
/// (the link when given) on stdout.
int Emulate(const EmulateOptions& options);

}  // namespace hgrasp::app
