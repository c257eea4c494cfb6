// `hgrasp calibrate laser` and `hgrasp scan`: the scanner driven through the device seam, with
// the simulator's ground truth added to what they report (never given to the pipeline).

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "app/devices.h"
#include "app/output_dir.h"
#include "common/error.h"
#include "common/paths.h"
#include "common/write_file.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/range_io.h"
#include "scan/scanner.h"
#include "sim/scenario.h"
#include "sim/sim_devices.h"
#include "sim/truth.h"

namespace hgrasp::app {
namespace {

namespace fs = std::filesystem;

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

robot::HeadKinematics Head() {
  return robot::HeadKinematics::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
}

}  // namespace

int CalibrateLaser(const CalibrateLaserOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const sim::Scenario scenario = sim::LoadScenario(o.scenario);
  const auto cameras = robot::LoadStereoIntrinsics(ResolveDataPath(o.files.cameras));
  // --out is checked before the sweep: a folder or a path under a file cannot take the file.
  const std::string out_expected = "a path for the laser calibration file";
  CheckOutputFile(o.out_file, "--out", out_expected);
  const auto head = Head();
  const StopSignals signals;
  Robot robot = OpenRobot(scenario, signals.request(), CleanLockstepWires(o.lockstep));
  if (EndedAtStart(robot, scenario, nullptr, "calibrate laser")) return 1;
  device::RobotDevices& dev = robot.devices;
  scan::LaserCalibrationReport report;
  scan::SweepConfig sweep;
  sweep.stop = signals.request();
  std::string aim_failed;
  const device::Status aimed = scan::MoveHeadForScan(dev, scan::kLookHead, sweep.stop, &aim_failed);
  if (aimed != device::Status::kOk) {
    report.status = aimed;
    report.failed_device = aim_failed;
    report.failure = aim_failed + ": " + std::string(device::ToString(aimed)) +
                     " moving the head to the scan pose";
  }
  const std::optional<robot::LaserCalibration> calibrated =
      aimed == device::Status::kOk ? scan::CalibrateLaser(dev, head, cameras, sweep, {}, &report)
                                   : std::nullopt;
  // The head's angles for the truth below are read before the safe stop.
  device::HeadState hs;
  const device::Status head_read = calibrated ? dev.head->Read(&hs) : device::Status::kOk;
  robot.LeaveSafe();
  if (!calibrated) {
    // Nothing is written: a calibration below its stated quality, or none at all.
    const char* kind = report.status == device::Status::kInterrupted ? "interrupted: "
                       : report.failed_device.empty()                ? ""
                                                                     : "device_error: ";
    const std::string failure = report.status == device::Status::kInterrupted
                                    ? signals.request()->Reason() + " during the sweep"
                                    : report.failure;
    spdlog::error("calibrate laser: {}{}; {} not written", kind, failure, o.out_file);
    return 1;
  }
  const robot::LaserCalibration& cal = *calibrated;
  CreateOutputFileParents(o.out_file, "--out", out_expected);
  robot::SaveLaserCalibration(cal, o.out_file);
  spdlog::info("calibrate laser: {}; wrote {} ({:.1f} s)", report.Figures(), o.out_file,
               Seconds(t0));
  if (robot.truth() == nullptr) return 0;

  // Ground truth: the calibrated plane against the simulator's at every count of the sweep.
  if (head_read != device::Status::kOk) return 0;  // written; no truth to add
  const Pose3 X_WH = head.X_WH(hs.q);
  const std::int32_t lo = std::min(sweep.start_count, sweep.end_count);
  const std::int32_t hi = std::max(sweep.start_count, sweep.end_count);
  const sim::LaserPlaneError error = sim::CompareLaserPlanes(
      *robot.truth()->rig, [&](std::int32_t c) { return cal.PlaneH(c).TransformedBy(X_WH); }, lo,
      hi);
  spdlog::info(
      "calibrate laser: against the simulator's planes over counts {}..{}: worst {:.4f} deg, "
      "{:.3f} mm",
      lo, hi, error.worst_deg, error.worst_mm);
  return 0;
}

int Scan(const ScanOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const sim::Scenario scenario = sim::LoadScenario(o.scenario);
  const auto cameras = robot::LoadStereoIntrinsics(ResolveDataPath(o.files.cameras));
  const auto laser = robot::LoadLaserCalibration(ResolveDataPath(o.files.laser));
  OutputDir out(o.out_dir);
  const StopSignals signals;
  Robot robot = OpenRobot(scenario, signals.request(), CleanLockstepWires(o.lockstep));
  if (EndedAtStart(robot, scenario, &out, "scan")) return 1;
  device::RobotDevices& dev = robot.devices;
  scan::StripeFrameConfig config;
  config.stereo = !o.single_camera;
  scan::Scanner scanner(Head(), cameras, laser, config);
  scan::SweepConfig sweep;
  sweep.stop = signals.request();
  const auto t_scan = std::chrono::steady_clock::now();
  std::string aim_failed;
  const device::Status aimed = scan::MoveHeadForScan(dev, scan::kLookHead, sweep.stop, &aim_failed);
  scan::ScanResult result;
  if (aimed == device::Status::kOk) {
    result = scanner.Scan(dev, sweep);
  } else {
    result.status = aimed;
    result.failed_device = aim_failed;
  }
  const double scan_s = Seconds(t_scan);
  const SafeStopReport safe = robot.LeaveSafe();
  if (result.status != device::Status::kOk) {
    // A device failed or a stop signal came: the report says which and what it said; there is
    // no range to write.
    const bool interrupted = result.status == device::Status::kInterrupted;
    const std::string failure = interrupted ? "interrupted" : "device_error";
    const std::string detail = interrupted ? signals.request()->Reason() + " during the scan"
                                           : result.failed_device + ": " +
                                                 std::string(device::ToString(result.status)) +
                                                 " during the scan";
    nlohmann::json report = {{"scenario", scenario.name},
                             {"seed", scenario.seed},
                             {"ok", false},
                             {"failure", failure},
                             {"failure_detail", detail},
                             {"failed_device", interrupted ? nlohmann::json(nullptr)
                                                           : nlohmann::json(result.failed_device)},
                             {"safe_stop", safe.Json()},
                             {"timing_s", {{"scan", scan_s}, {"total", Seconds(t0)}}}};
    WriteFileWhole(out.Path("report.json"), report.dump(2) + "\n");
    WriteTwinRecord(robot, out);
    out.Commit();
    spdlog::error("scan: {}: {}; wrote {}", failure, detail, o.out_dir);
    return 1;
  }

  // A sweep in which no frame showed the stripe is a failed scan: the laser is off or out of
  // view, or the cameras see something else.
  const bool seen = result.points > 0;
  nlohmann::json report;
  report["scenario"] = scenario.name;
  report["seed"] = scenario.seed;
  report["ok"] = seen;
  report["failure"] = seen ? nlohmann::json(nullptr) : nlohmann::json("no_stripe");
  if (!seen) {
    report["failure_detail"] = "no stripe point in any of the " +
                               std::to_string(result.range.cols()) +
                               " frames of the sweep (is the laser on, and in the cameras' view?)";
  }
  report["range"] = {{"points", result.points},
                     {"rejected", result.rejected},
                     {"gaps_rescanned", result.gaps_rescanned},
                     {"frames_rescanned", result.frames_rescanned},
                     {"gaps_left", result.gaps_left}};
  report["timing_s"] = {{"scan", scan_s}, {"total", Seconds(t0)}};
  report["safe_stop"] = safe.Json();
  std::string truth_line;
  if (const TruthWorld* twin = robot.truth()) {
    // Ground truth (only when every device is the twin's, simulated or in lockstep: then what
    // the devices saw is the twin's): how far the accepted points lie from the true surfaces.
    double sum2 = 0;
    int n = 0, beyond_5mm = 0;
    std::vector<double> errors;
    for (int r = 0; r < result.range.rows(); ++r) {
      for (int c = 0; c < result.range.cols(); ++c) {
        const scan::RangeCell& cell = result.range.at(r, c);
        if (!cell.valid) continue;
        const double e = sim::DistanceToTrueSurface(*twin->world, cell.p_W);
        sum2 += e * e, ++n;
        beyond_5mm += e > 0.005;
        errors.push_back(e);
      }
    }
    std::sort(errors.begin(), errors.end());
    const auto percentile = [&](double q) {
      return errors.empty() ? 0.0 : errors[static_cast<size_t>(q * (errors.size() - 1))];
    };
    const double rms = n > 0 ? std::sqrt(sum2 / n) : 0.0;
    nlohmann::json truth = sim::TruthJson(*twin->world, *twin->rig, {});
    truth["range"] = {{"rms_to_surface_m", rms},
                      {"median_to_surface_m", percentile(0.5)},
                      {"p99_to_surface_m", percentile(0.99)},
                      {"beyond_5mm", beyond_5mm},
                      {"mode", o.single_camera ? "single_camera" : "stereo"}};
    report["truth"] = truth;
    truth_line = fmt::format(
        "; to the true surfaces RMS {:.3f} mm, median {:.3f} mm, 99th percentile {:.3f} mm, {} "
        "beyond 5 mm",
        1e3 * rms, 1e3 * percentile(0.5), 1e3 * percentile(0.99), beyond_5mm);
  }

  if (!o.lean) {
    scan::WritePly(result.range, out.Path("range.ply"));
    scan::WriteRangePng(result.range, out.Path("range.png"));
  }
  WriteFileWhole(out.Path("report.json"), report.dump(2) + "\n");
  WriteTwinRecord(robot, out);
  out.Commit();
  spdlog::info("scan: {} points, {} rejected rows{}; scan {:.2f} s, total {:.2f} s; wrote {}",
               result.points, result.rejected, truth_line, scan_s, Seconds(t0), o.out_dir);
  if (result.gaps_rescanned > 0) {
    spdlog::info(
        "scan: the sweep missed {} stretches of stripe positions; {} frames swept "
        "again, {} gaps left",
        result.gaps_rescanned, result.frames_rescanned, result.gaps_left);
  }
  if (!seen) {
    spdlog::error("scan: no_stripe: {}", report["failure_detail"].get<std::string>());
    return 1;
  }
  return 0;
}

}  // namespace hgrasp::app
