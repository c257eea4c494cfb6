// `hgrasp calibrate cameras`: the head looks at chessboards from several poses and the stereo
// calibration (scan/camera_calibration.h) fits both cameras' intrinsics; on the twin the report
// adds how far they are from its true cameras (never given to the pipeline).

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "app/devices.h"
#include "app/output_dir.h"
#include "app/safe_stop.h"
#include "common/error.h"
#include "common/paths.h"
#include "common/write_file.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/camera_calibration.h"
#include "scan/scanner.h"
#include "servo/head_tracking.h"
#include "sim/renderer.h"
#include "sim/scenario.h"
#include "sim/sim_devices.h"

namespace hgrasp::app {
namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// From each point the head looks at, the board is seen at the image centre and then moved
// towards each side and corner of the image (pan and tilt offsets, deg; at the corners some
// views lose a corner of the board and are skipped): the principal point is told from
// the focal length only by corners all over the image.
constexpr double kPanOffsetsDeg[] = {0.0, 14.0, -14.0, 0.0, 0.0, 14.0, -14.0, 14.0, -14.0};
constexpr double kTiltOffsetsDeg[] = {0.0, 0.0, 0.0, 10.0, -10.0, 10.0, -10.0, -10.0, 10.0};

// The head poses: for each point, the cyclopean axis on it (servo::HeadTracker over the head's
// kinematics, verge as for a scan), then the offsets.
std::vector<device::HeadJoints> HeadPoses(const robot::HeadKinematics& head,
                                          const std::vector<std::array<double, 3>>& points) {
  servo::HeadTrackingOptions aim;
  aim.aim = servo::AimFrame::kCyclopean;
  aim.max_step = kPi;
  aim.deadband = 0.0;
  const servo::HeadTracker tracker(head, aim);
  std::vector<device::HeadJoints> poses;
  for (const std::array<double, 3>& p : points) {
    device::HeadJoints q = scan::kLookHead;
    // Twice: the first aim moves the cameras, whose offset from the axes moves the answer.
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d p_C =
          head.X_WC(robot::HeadKinematics::kLeft, q).inverse() * Eigen::Vector3d(p[0], p[1], p[2]);
      q = tracker.Track(q, p_C).q;
    }
    for (std::size_t i = 0; i < std::size(kPanOffsetsDeg); ++i) {
      device::HeadJoints o = q;
      o.pan += DegToRad(kPanOffsetsDeg[i]);
      o.tilt += DegToRad(kTiltOffsetsDeg[i]);
      poses.push_back(o);
    }
  }
  return poses;
}

nlohmann::json CameraJson(const PinholeCamera& c) {
  return {{"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy}};
}

// How far `c` is from the true camera `t`: the larger focal error (%), the principal point's
// distance (px).
nlohmann::json CameraError(const PinholeCamera& c, const PinholeCamera& t) {
  const double focal_pct =
      100.0 * std::max(std::abs(c.fx / t.fx - 1.0), std::abs(c.fy / t.fy - 1.0));
  return {{"focal_pct", focal_pct}, {"principal_point_px", std::hypot(c.cx - t.cx, c.cy - t.cy)}};
}

}  // namespace

int CalibrateCameras(const CalibrateCamerasOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const sim::Scenario scenario = sim::LoadScenario(o.scenario);
  const robot::StereoIntrinsics nominal = robot::LoadStereoIntrinsics(ResolveDataPath(o.cameras));
  const std::string out_expected = "a path for the camera intrinsics file";
  CheckOutputFile(o.out_file, "--out", out_expected);
  if (!o.report_file.empty()) {
    CheckOutputFile(o.report_file, "--report", "a path for the report (JSON)");
  }
  if (o.look_at.empty()) throw InputError("", "--at", "", "at least one point to look at");
  const std::string board_expected = "a board of 3-20 inner corners a side, cols != rows";
  if (o.board_cols < 3 || o.board_cols > 20 || o.board_rows < 3 || o.board_rows > 20 ||
      o.board_cols == o.board_rows) {
    throw InputError("", "--board",
                     std::to_string(o.board_cols) + "x" + std::to_string(o.board_rows),
                     board_expected);
  }
  if (!(o.square_mm >= 5.0 && o.square_mm <= 100.0)) {
    throw InputError("", "--square-mm", std::to_string(o.square_mm), "a square edge of 5-100 mm");
  }
  const robot::HeadKinematics head =
      robot::HeadKinematics::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));

  const StopSignals signals;
  Robot robot = OpenRobot(scenario, signals.request(), CleanLockstepWires(o.lockstep));
  if (EndedAtStart(robot, scenario, nullptr, "calibrate cameras")) return 1;
  scan::CameraCalibrationConfig config;
  config.board = {o.board_cols, o.board_rows, 1e-3 * o.square_mm};
  config.head_poses = HeadPoses(head, o.look_at);
  config.views_dir = o.views_dir;
  config.stop = signals.request();
  scan::CameraCalibrationReport report;
  const bool ok = scan::CalibrateCameras(robot.devices, config, &report);
  robot.LeaveSafe();

  nlohmann::json json = {{"scenario", scenario.name},
                         {"ok", ok},
                         {"failure", ok ? nlohmann::json(nullptr) : nlohmann::json(report.failure)},
                         {"poses", report.poses},
                         {"views_used", report.views_used},
                         {"missed_poses", report.missed}};
  std::string truth_line;
  if (ok) {
    const scan::StereoCalibration& fit = report.fit;
    json["fit"] = {{"left", CameraJson(fit.cameras.left)},
                   {"right", CameraJson(fit.cameras.right)},
                   {"baseline_m", fit.baseline_m},
                   {"rms_px", fit.rms_px}};
    if (const TruthWorld* twin = robot.truth()) {
      // The twin's true cameras, and their optical centres now (the verge is the calibration's).
      sim::StereoRig& rig = *twin->rig;
      const PinholeCamera truth[2] = {rig.renderer().Intrinsics(rig.camera_id(0)),
                                      rig.renderer().Intrinsics(rig.camera_id(1))};
      const double true_baseline =
          (sim::Renderer::OpticalFramePose(twin->world->data(), rig.camera_id(0)).translation() -
           sim::Renderer::OpticalFramePose(twin->world->data(), rig.camera_id(1)).translation())
              .norm();
      const nlohmann::json left = CameraError(fit.cameras.left, truth[0]);
      const nlohmann::json right = CameraError(fit.cameras.right, truth[1]);
      json["truth"] = {{"left", CameraJson(truth[0])},
                       {"right", CameraJson(truth[1])},
                       {"baseline_m", true_baseline},
                       {"calibrated_error",
                        {{"left", left},
                         {"right", right},
                         {"baseline_mm", 1e3 * std::abs(fit.baseline_m - true_baseline)}}},
                       {"nominal_error",
                        {{"left", CameraError(nominal.left, truth[0])},
                         {"right", CameraError(nominal.right, truth[1])}}}};
      truth_line = fmt::format(
          "; against the twin's cameras: focal {:.3f}% / {:.3f}%, principal point {:.2f} / {:.2f} "
          "px, baseline {:.3f} mm off (the nominal file's focal {:.3f}% / {:.3f}%)",
          left["focal_pct"].get<double>(), right["focal_pct"].get<double>(),
          left["principal_point_px"].get<double>(), right["principal_point_px"].get<double>(),
          1e3 * std::abs(fit.baseline_m - true_baseline),
          json["truth"]["nominal_error"]["left"]["focal_pct"].get<double>(),
          json["truth"]["nominal_error"]["right"]["focal_pct"].get<double>());
    }
  }
  if (!o.report_file.empty()) {
    CreateOutputFileParents(o.report_file, "--report", "a path for the report (JSON)");
    WriteFileWhole(o.report_file, json.dump(2) + "\n");
  }
  if (!ok) {
    const bool interrupted = report.status == device::Status::kInterrupted;
    const std::string kind = interrupted                    ? "interrupted: "
                             : report.failed_device.empty() ? ""
                                                            : "device_error: ";
    spdlog::error("calibrate cameras: {}{}; {} not written", kind,
                  interrupted ? signals.request()->Reason() : report.failure, o.out_file);
    return 1;
  }
  const scan::StereoCalibration& fit = report.fit;
  CreateOutputFileParents(o.out_file, "--out", out_expected);
  char note[256];
  std::snprintf(note, sizeof note,
                "Measured by `hgrasp calibrate cameras %s`: %d stereo views of a %dx%d chessboard "
                "of %.1f mm squares,\nreprojection RMS %.3f px; fitted baseline %.2f mm.",
                o.scenario.c_str(), fit.views, o.board_cols, o.board_rows, o.square_mm, fit.rms_px,
                1e3 * fit.baseline_m);
  robot::SaveStereoIntrinsics(fit.cameras, o.out_file, note);
  spdlog::info(
      "calibrate cameras: {} of {} views, RMS {:.3f} px; left f {:.2f}/{:.2f} c ({:.2f}, {:.2f}), "
      "right f {:.2f}/{:.2f} c ({:.2f}, {:.2f}), baseline {:.2f} mm{}; wrote {} ({:.1f} s)",
      report.views_used, report.poses, fit.rms_px, fit.cameras.left.fx, fit.cameras.left.fy,
      fit.cameras.left.cx, fit.cameras.left.cy, fit.cameras.right.fx, fit.cameras.right.fy,
      fit.cameras.right.cx, fit.cameras.right.cy, 1e3 * fit.baseline_m, truth_line, o.out_file,
      Seconds(t0));
  return 0;
}

}  // namespace hgrasp::app
