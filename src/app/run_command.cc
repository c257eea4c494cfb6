// `hgrasp run`: the whole task (task::GraspTask) on the devices the scenario names, with its
// pictures, the left camera's video and the report; the simulator's ground truth added to the
// report only when every device is simulated (never given to the pipeline).

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <optional>

#include "app/commands.h"
#include "app/devices.h"
#include "app/look_report.h"
#include "app/output_dir.h"
#include "app/pictures.h"
#include "common/error.h"
#include "common/write_file.h"
#include "sim/scenario.h"
#include "sim/sim_devices.h"
#include "sim/truth.h"
#include "task/grasp_task.h"

namespace hgrasp::app {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The left image, kPictureScale times its size, with the planned grasp (red), the servo's
// current target when it is another pose (the pre-grasp, orange) and the tracked hand (green)
// as wireframes (after the paper's Figure 9), and the time and stage written in a corner.
cv::Mat ServoPicture(const device::StereoFrame& frame, const task::TaskView& view,
                     const PinholeCamera& camera) {
  cv::Mat picture;
  cv::resize(frame.left, picture, cv::Size(), kPictureScale, kPictureScale, cv::INTER_LINEAR);
  // HandBoxes of a pose in CL are the hand's boxes in CL: drawn with X_CW the identity.
  const Pose3 identity = Pose3::Identity();
  if (view.X_CG) {
    DrawHand(&picture, camera, identity, grasp::HandBoxes(*view.X_CG, view.opening_m, {}),
             cv::Scalar(40, 40, 255));
  }
  if (view.X_CT && !(view.X_CG && view.X_CT->isApprox(*view.X_CG, 1e-9))) {
    DrawHand(&picture, camera, identity, grasp::HandBoxes(*view.X_CT, view.opening_m, {}),
             cv::Scalar(0, 160, 255));
  }
  if (view.X_CE) {
    DrawHand(&picture, camera, identity, grasp::HandBoxes(*view.X_CE, view.opening_m, {}),
             cv::Scalar(60, 220, 60));
  }
  char text[96];
  std::snprintf(text, sizeof text, "t %.2f s  %s%s%s", frame.t_s, std::string(view.stage).c_str(),
                view.moment.empty() ? "" : ": ", std::string(view.moment).c_str());
  cv::putText(picture, text, cv::Point(8, 22), cv::FONT_HERSHEY_SIMPLEX, 0.6,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  return picture;
}

// --command-log FILE: checked before the robot moves, so that a path that cannot be written is
// a usage error (exit 2) and not a lost log after the run.
void CheckCommandLogPath(const std::string& path) {
  if (path.empty()) return;
  const fs::path p(path);
  const fs::path folder = p.has_parent_path() ? p.parent_path() : fs::path(".");
  std::error_code ec;
  if (!p.has_filename() || !fs::is_directory(folder, ec) || fs::is_directory(p, ec)) {
    throw InputError("", "--command-log", path, "a file in an existing folder");
  }
}

// The real drivers' command logs, written once the robot is left safe (what the drivers did
// after that, their destructors' stops, is not in them).
void WriteCommandLog(const std::string& path, const device::RobotDevices& devices) {
  if (path.empty()) return;
  WriteFileWhole(path, CommandLogs(devices).dump(1) + "\n");
  spdlog::info("run: wrote the drivers' command logs to {}", path);
}

nlohmann::json ErrorJson(const servo::ServoError& e) {
  return {{"translation_m", e.translation_m}, {"rotation_deg", RadToDeg(e.rotation_rad)}};
}

}  // namespace

int Run(const RunOptions& o) {
  const auto t0 = Clock::now();
  const sim::Scenario scenario = sim::LoadScenario(o.scenario);
  task::TaskConfig config = TaskConfigFor(scenario);
  const task::RobotModel robot_model =
      task::LoadRobotModel(o.files.cameras, o.files.laser, o.files.leds);
  OutputDir out_dir(o.out_dir);
  CheckCommandLogPath(o.command_log);
  const StopSignals signals;
  config.stop = signals.request();
  if (!o.lockstep && o.wires.any()) {
    throw InputError("", "--lockstep", "not given",
                     "given with --corrupt, --dropouts or --at (the twin's wires are in process "
                     "only in lockstep; against `hgrasp twin`, give them to it)");
  }
  Robot robot = OpenRobot(scenario, signals.request(), o.lockstep ? &o.wires : nullptr);
  if (EndedAtStart(robot, scenario, &out_dir, "run")) {
    WriteCommandLog(o.command_log, robot.devices);
    return 1;
  }
  device::RobotDevices& dev = robot.devices;
  const TruthWorld* const truth = robot.truth();  // null on a real robot
  const bool sim_truth = truth != nullptr;
  const fs::path out(out_dir.staging());

  cv::VideoWriter video;
  if (o.video && !o.lean) {
    // Motion JPEG in AVI: OpenCV's own encoder, no codec library needed.
    const cv::Size size(kPictureScale * 320, kPictureScale * 240);
    if (!video.open((out / "left.avi").string(), cv::CAP_OPENCV_MJPEG,
                    cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25.0, size)) {
      spdlog::warn("run: cannot write {}; no video", (out / "left.avi").string());
    }
    video.set(cv::VIDEOWRITER_PROP_QUALITY, 75);
  }
  nlohmann::json truth_run = nlohmann::json::object();
  task::GraspTask* task_ptr = nullptr;
  // The target (truth only) and its pose at the look, before anything touched it.
  const sim::SimObject* target_object = nullptr;
  Pose3 X_WO_look = Pose3::Identity();
  // How far the target has moved and turned since the look: a box the hand knocked over on the
  // way in or in the close shows where it happened, whatever the task then reports.
  auto target_moved = [&]() -> nlohmann::json {
    const Pose3 X_WO = truth->world->BodyPose(target_object->body);
    const Eigen::AngleAxisd turn(X_WO_look.linear().transpose() * X_WO.linear());
    return {{"object_moved_m", (X_WO.translation() - X_WO_look.translation()).norm()},
            {"object_turned_deg", RadToDeg(turn.angle())}};
  };
  int pictures = 0;
  std::string stage;  // the stage of the last frame, to say when a new one begins
  auto sink = [&](const device::StereoFrame& frame, const task::TaskView& view) {
    if (view.stage != stage) {
      // Said as it begins (its first frame): a user watching the robot, or a test that stops a
      // device during the scan, knows where the task is.
      stage = std::string(view.stage);
      spdlog::info("run: {} (device time {:.2f} s)", stage, frame.t_s);
    }
    const bool key = !view.moment.empty();
    if (!key && !video.isOpened()) return;
    const cv::Mat picture = ServoPicture(frame, view, robot_model.cameras.left);
    if (!key) {
      video.write(picture);
      return;
    }
    WritePng(picture, (out / ("servo_" + std::string(view.moment) + ".png")).string());
    ++pictures;
    // Said as it happens: a user watching the robot (or a test cutting a link during the servo)
    // knows where the task is.
    spdlog::info("run: {} (device time {:.2f} s)", view.moment, frame.t_s);
    if (sim_truth && task_ptr->result().plan && view.moment != "lifted") {
      // Where the gripper truly is against the planned pose it is servoed to: the pre-grasp
      // until it is reached, then the grasp.
      const Pose3 X_WCL = robot_model.head.X_WC(robot::HeadKinematics::kLeft, frame.head);
      const grasp::GraspPlan& plan = *task_ptr->result().plan;
      const Pose3& X_WT = view.moment == "grasp_reached" ? plan.X_WE : plan.X_WE_pre;
      const sim::PoseError e = sim::GripperPoseError(*truth->world, plan.side, X_WCL, X_WT);
      nlohmann::json& at = truth_run[std::string(view.moment)];
      at = {{"gripper_to_plan_m", e.translation_m},
            {"gripper_to_plan_deg", RadToDeg(e.rotation_rad)}};
      if (target_object != nullptr) at.update(target_moved());
    }
  };
  ScanTruthRecorder scan_truth(robot);
  // Only the video shows every frame; the pictures are the key moments', which always come with
  // their images: frames grabbed to wait for a move need none (the twin does not render them).
  config.sink_needs_every_image = video.isOpened();
  task::GraspTask task(&dev, robot_model, config,
                       [&](const device::StereoFrame& frame, const task::TaskView& view) {
                         scan_truth.OnFrame(frame, view);
                         sink(frame, view);
                       });
  task_ptr = &task;
  // The truth of the look and the plan is taken before anything touches the objects, and so is
  // the target object's true height (truth only).
  std::optional<nlohmann::json> look_truth;
  const bool looked = task.Look();
  scan_truth.Stop();
  const bool planned = looked && task.Plan();
  if (sim_truth) {
    look_truth = LookTruth(*truth, task.result(), scan_truth.truth());
    if (task.result().target) {
      target_object =
          TargetObject(*truth->world, task.result().scene->boxes[*task.result().target]);
      if (target_object != nullptr) X_WO_look = truth->world->BodyPose(target_object->body);
    }
  }
  // The close, and (truth only) where the target is after it.
  auto close = [&] {
    const bool closed = task.Close();
    if (target_object != nullptr) truth_run["closed"] = target_moved();
    return closed;
  };
  const bool ok = planned && task.Approach() && task.Servo() && close() && task.Lift();
  // Lockstep: when the task ended on the twin's clock (since it started, as its --at times).
  const std::optional<double> task_end_twin_s =
      robot.lockstep ? std::optional<double>(robot.lockstep->time() - robot.lockstep->start_time())
                     : std::nullopt;
  if (!ok) {
    // Said at once, before the safe stop (which may take a while on slow lines).
    spdlog::warn("run: {} ({}): leaving the robot safe", task::ToString(task.result().failure),
                 task.result().message);
  }
  // Whatever happened, the robot is left safe before anything is written (DESIGN.md rule 8).
  const SafeStopReport safe = robot.LeaveSafe();
  WriteCommandLog(o.command_log, dev);
  const task::TaskResult& r = task.result();

  nlohmann::json report = LookReport(scenario, look_truth ? &*look_truth : nullptr, r, robot_model,
                                     true, out_dir.staging(), o.lean);
  report["ok"] = ok;
  report["failure"] = ok ? nlohmann::json(nullptr) : nlohmann::json(task::ToString(r.failure));
  report["failure_detail"] = ok ? nlohmann::json(nullptr) : nlohmann::json(r.message);
  report["failed_device"] =
      r.failed_device.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.failed_device);
  report["safe_stop"] = safe.Json();
  // lift_height: the least rise of the box that the cameras' rise scan after the hold leaves
  // possible (null when it was not measured, or nothing fits); the gripper's, by its LEDs, beside
  // it.
  nlohmann::json rise = nullptr;
  const bool measured = r.box_rise && r.box_rise->consistent();
  if (r.box_rise) {
    rise = {{"min", measured ? nlohmann::json(r.box_rise->min_m) : nlohmann::json(nullptr)},
            {"max", measured ? nlohmann::json(r.box_rise->max_m) : nlohmann::json(nullptr)},
            {"box_cells", r.box_rise->box_cells},
            {"cells", r.box_rise->cells}};
  }
  report["result"] = {
      {"lifted", r.lifted},
      {"lift_height", measured ? nlohmann::json(r.box_rise->min_m) : nlohmann::json(nullptr)},
      {"box_rise", rise},
      {"gripper_rise", r.gripper_rise_m},
      {"lift_corrections", r.lift_corrections},
      {"box_relifts", r.box_relifts}};
  report["task"] = {{"lift", config.lift_m}, {"hold_s", config.hold_s}};
  nlohmann::json phases = nlohmann::json::array();
  for (const task::ServoPhase& p : r.servo) {
    nlohmann::json errors = nlohmann::json::array();
    for (const servo::ServoError& e : p.errors) errors.push_back(ErrorJson(e));
    phases.push_back({{"phase", p.name},
                      {"iterations", p.iterations},
                      {"converged", p.converged},
                      {"final_error_by_filter", ErrorJson(p.final_error)},
                      {"errors_by_filter", errors},
                      {"device_s", p.sim_s}});
  }
  report["servo"] = {{"phases", phases},
                     {"recoveries", r.recoveries},
                     {"flashes", r.flashes},
                     {"measurements", r.measurements},
                     {"image_measurements", r.image_measurements},
                     {"head_moves", r.head_moves},
                     {"held_opening_m", r.held_opening_m}};
  nlohmann::json timing = nlohmann::json::object();
  nlohmann::json stages = nlohmann::json::array();
  for (const task::StageTiming& s : r.stages) {
    timing[s.name] = s.wall_s;
    stages.push_back(
        {{"stage", s.name}, {"wall_s", s.wall_s}, {"device_s", s.device_s}, {"frames", s.frames}});
  }
  if (r.scene) {
    timing["scan"] = timing["look"].get<double>() - r.scene->segment_s - r.scene->model_s;
    timing["segment"] = r.scene->segment_s;
    timing["model"] = r.scene->model_s;
  }
  timing["total"] = Seconds(t0);
  report["timing_s"] = timing;
  // Simulated (device) time against wall time, per stage and for the whole task.
  report["stages"] = stages;
  report["device_time_s"] = r.device_s;
  if (task_end_twin_s) report["lockstep"] = {{"task_end_twin_s", *task_end_twin_s}};
  report["wall_time_s"] = r.wall_s;
  if (sim_truth) {
    if (target_object != nullptr) {
      const double rise = truth->world->BodyPose(target_object->body).translation().z() -
                          X_WO_look.translation().z();
      truth_run["object"] = target_object->spec.name;
      truth_run["object_rise_m"] = rise;
    }
    report["truth"]["run"] = truth_run;
  }
  if (video.isOpened()) video.release();
  WriteFileWhole(out_dir.Path("report.json"), report.dump(2) + "\n");
  WriteTwinRecord(robot, out_dir);
  out_dir.Commit();

  std::string servo;
  for (const task::ServoPhase& p : r.servo) {
    servo += fmt::format(" {} {} iterations, {:.1f} mm {:.2f} deg;", p.name, p.iterations,
                         1e3 * p.final_error.translation_m, RadToDeg(p.final_error.rotation_rad));
  }
  spdlog::info(
      "run: {}; servo:{} box risen at least {:.1f} mm (cameras), gripper {:.1f} mm; device time "
      "{:.1f} s, wall {:.1f} s ({:.2f}x real time); {} pictures; wrote {}",
      ok ? "lifted" : std::string(task::ToString(r.failure)), servo,
      r.box_rise && r.box_rise->consistent() ? 1e3 * r.box_rise->min_m : std::nan(""),
      1e3 * r.gripper_rise_m, r.device_s, Seconds(t0),
      r.device_s > 0 ? r.device_s / Seconds(t0) : 0.0, pictures, o.out_dir);
  if (!ok) spdlog::warn("run: {}: {}", task::ToString(r.failure), r.message);
  return ok ? 0 : 1;
}

}  // namespace hgrasp::app
