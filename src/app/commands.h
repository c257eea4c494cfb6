#pragma once
/// @file The `hgrasp` subcommands. Each returns the process exit status: 0 success, 1 the task
/// failed, 2 bad input or usage (DESIGN.md, "The command").

#include <cstdint>
#include <optional>
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
};

/// `hgrasp calibrate laser`: the laser's self-calibration (paper eq. 6) over a sweep.
int CalibrateLaser(const CalibrateLaserOptions& options);

struct ScanOptions {
  std::string scenario;
  std::string out_dir;
  CalibrationFiles files;
  bool single_camera = false;  ///< light-plane triangulation from the left camera only
};

/// `hgrasp scan`: one laser sweep: range.ply, range.png and report.json.
int Scan(const ScanOptions& options);

struct ModelOptions {
  std::string scenario;
  std::string out_dir;
  CalibrationFiles files;
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
};

/// `hgrasp run`: the whole task (look, plan, approach, servo, close, lift): the outputs of
/// `hgrasp plan`, servo_*.png (Figure 9: the tracked and the target hand over the left image at
/// key moments), left.avi and report.json with the result, the servo's figures and timings;
/// exit 1 when the task failed (the failure named in the report).
int Run(const RunOptions& options);

struct GenerateOptions {
  std::string family = "random_boxes";  ///< a scene family (kSceneFamilies)
  std::uint64_t first_seed = 1, last_seed = 1;  ///< the seed range, inclusive
  std::string out_dir;
};

/// Scene families `hgrasp generate` draws from: random_boxes is sim::RandomBoxScene.
inline constexpr const char* kSceneFamilies[] = {"random_boxes"};
/// Most scenes one `hgrasp generate` writes.
inline constexpr std::uint64_t kMaxGenerate = 100000;

/// `hgrasp generate`: writes the scenario file of every seed of a family (DIR/<name>.yaml), so a
/// user can read, keep and run them; all or none.
int Generate(const GenerateOptions& options);

struct EmulateOptions {
  std::string device;          ///< val2, biclops, sensorhand or laser_board
  std::string side = "right";  ///< val2: which arm's controller (its kinematics)
  std::string link;            ///< optional stable path: a symlink to the pty
  /// Stop after this long (s; positive, finite, at most kMaxEmulateSeconds); without it, at
  /// SIGINT or SIGTERM.
  std::optional<double> seconds;
};

/// Longest --seconds (s): about 11.6 days.
inline constexpr double kMaxEmulateSeconds = 1e6;

/// `hgrasp emulate`: serves one device emulator on a pseudo-terminal and prints the port's path
/// (the link when given) on stdout.
int Emulate(const EmulateOptions& options);

}  // namespace hgrasp::app
