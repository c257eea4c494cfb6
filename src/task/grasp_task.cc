#include "task/grasp_task.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <utility>

#include "common/error.h"
#include "common/paths.h"
#include "model/colour.h"
#include "robot/kinematic_tree.h"

namespace hgrasp::task {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kCL = robot::HeadKinematics::kLeft;

double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

std::string_view ToString(Failure f) {
  switch (f) {
    case Failure::kNone:
      return "";
    case Failure::kNoTarget:
      return "no_target";
    case Failure::kUnreachable:
      return "unreachable";
    case Failure::kTrackingLost:
      return "tracking_lost";
    case Failure::kServoTimeout:
      return "servo_timeout";
    case Failure::kGraspSlipped:
      return "grasp_slipped";
    case Failure::kDeviceError:
      return "device_error";
    case Failure::kInterrupted:
      return "interrupted";
  }
  return "unknown";
}

TaskConfig::TaskConfig() {
  // Re-centre the gripper only when it strays well off the axis: each head move costs device
  // time, and the target and the filter have to be carried through it.
  head.deadband = DegToRad(8.0);
  head.max_step = DegToRad(20.0);
  // Stop well inside the 5 mm / 2 deg the grasp must reach: the filter's pose is what stops
  // the servo, and it is itself off by a millimetre or two and a degree (see fine_iterations).
  law.translation_tolerance = 0.001;
  law.rotation_tolerance = DegToRad(1.0);
}

RobotModel LoadRobotModel(const std::string& cameras_path, const std::string& laser_path,
                          const std::string& leds_path) {
  const std::string urdf = ResolveDataPath("models/humanoid.urdf");
  const auto tree = robot::KinematicTree::FromUrdfFile(urdf);
  return RobotModel{
      robot::LoadStereoIntrinsics(ResolveDataPath(cameras_path)),
      robot::LoadLaserCalibration(ResolveDataPath(laser_path)),
      robot::HeadKinematics::FromUrdfFile(urdf),
      {robot::ArmKinematics::FromTree(tree, "left"), robot::ArmKinematics::FromTree(tree, "right")},
      servo::LoadLedLayouts(ResolveDataPath(leds_path))};
}

// The cameras as the task sees them: each frame grabbed (by the scanner, the tracker or the
// task) is also given to the task, which keeps it and passes it to the sink.
class GraspTask::SinkCamera final : public device::StereoCamera {
 public:
  SinkCamera(std::unique_ptr<device::StereoCamera> inner, GraspTask* task)
      : inner_(std::move(inner)), task_(task) {}

  device::Status Grab(device::StereoFrame* frame) override {
    const device::Status s = inner_->Grab(frame);
    if (s == device::Status::kOk) task_->OnFrame(*frame);
    return s;
  }

  device::Status GrabWithoutImages(device::StereoFrame* frame) override {
    // A sink that needs every frame's images (a video) gets them.
    const bool images = task_->sink_ && task_->config_.sink_needs_every_image;
    const device::Status s = images ? inner_->Grab(frame) : inner_->GrabWithoutImages(frame);
    if (s == device::Status::kOk) task_->OnFrame(*frame);
    return s;
  }

  // The camera's own latency: without it the tracker saw every camera as having none and
  // looked at frames exposed before the LEDs switched (under line faults, a third of them).
  int frames_in_flight() const override { return inner_->frames_in_flight(); }

  std::unique_ptr<device::StereoCamera> Release() { return std::move(inner_); }

 private:
  std::unique_ptr<device::StereoCamera> inner_;
  GraspTask* task_;
};

GraspTask::GraspTask(device::RobotDevices* dev, RobotModel model, TaskConfig config, FrameSink sink)
    : dev_(dev),
      model_(std::move(model)),
      config_(std::move(config)),
      sink_(std::move(sink)),
      head_tracker_(model_.head, config_.head) {
  servo::ValidateControlLawOptions(config_.law);
  auto camera = std::make_unique<SinkCamera>(std::move(dev_->cameras), this);
  camera_ = camera.get();
  dev_->cameras = std::move(camera);
}

GraspTask::~GraspTask() { dev_->cameras = camera_->Release(); }

void GraspTask::OnFrame(const device::StereoFrame& frame) {
  if (!have_frame_) first_t_s_ = frame.t_s;
  last_frame_ = frame;
  have_frame_ = true;
  ++frames_;
  if (sink_) sink_(frame, View(""));
}

TaskView GraspTask::View(std::string_view moment) const {
  TaskView v;
  v.stage = stage_;
  v.moment = moment;
  if (result_.plan) v.side = result_.plan->side;
  if (tracker_ && tracker_->tracking()) v.X_CE = tracker_->pose();
  v.X_CT = X_CT_;
  if (result_.plan && have_frame_) {
    v.X_CG = model_.head.X_WC(kCL, last_frame_.head).inverse() * result_.plan->X_WE;
  }
  v.opening_m = opening_m_;
  return v;
}

void GraspTask::Moment(std::string_view moment) {
  if (!sink_ || !have_frame_) return;
  // Key moments follow tracked or settling frames, never a wait's frame without images.
  HGRASP_DEMAND_MSG(!last_frame_.left.empty(), "a key moment's frame has no images");
  sink_(last_frame_, View(moment));
}

void GraspTask::BeginStage(std::string_view name) {
  if (result_.stages.empty()) task_wall_ = Clock::now();
  stage_ = name;
  stage_wall_ = Clock::now();
  stage_device_s_ = have_frame_ ? last_frame_.t_s : 0.0;
  stage_frames_ = frames_;
  stage_started_with_frame_ = have_frame_;
}

void GraspTask::EndStage() {
  if (tracker_) {
    result_.flashes = tracker_->flashes();
    result_.recoveries = tracker_->recoveries();
    result_.measurements = tracker_->measurements();
    result_.image_measurements = tracker_->image_measurements();
  }
  StageTiming t;
  t.name = std::string(stage_);
  t.wall_s = Since(stage_wall_);
  t.frames = static_cast<int>(frames_ - stage_frames_);
  if (have_frame_) {
    // The first stage starts at its first frame's exposure (the device clock's zero is not ours).
    t.device_s = last_frame_.t_s - (stage_started_with_frame_ ? stage_device_s_ : first_t_s_);
  }
  result_.stages.push_back(t);
  result_.wall_s = Since(task_wall_);
  result_.device_s = have_frame_ ? last_frame_.t_s - first_t_s_ : 0.0;
}

bool GraspTask::Fail(Failure f, std::string message) {
  result_.failure = f;
  result_.message = std::move(message);
  EndStage();
  return false;
}

bool GraspTask::DeviceOk(device::Status s, std::string_view device, std::string_view what) {
  if (s == device::Status::kOk) return true;
  if (s == device::Status::kInterrupted) {
    return Fail(Failure::kInterrupted,
                (config_.stop != nullptr ? config_.stop->Reason() : std::string("interrupted")) +
                    " during the " + std::string(what));
  }
  result_.failed_device = device;
  return Fail(Failure::kDeviceError, std::string(device) + ": " +
                                         std::string(device::ToString(s)) + " (" +
                                         std::string(what) + ")");
}

std::string GraspTask::ArmKey() const {
  return "arm_" + std::string(device::ToString(result_.plan->side));
}

std::string GraspTask::HandKey() const {
  return "hand_" + std::string(device::ToString(result_.plan->side));
}

bool GraspTask::GrabFrame(bool track, bool images) {
  HGRASP_DEMAND(images || !track);
  device::StereoFrame frame;
  const device::Status s =
      images ? dev_->cameras->Grab(&frame) : dev_->cameras->GrabWithoutImages(&frame);
  if (!DeviceOk(s, "cameras", "grab")) return false;
  if (StopRequested(config_.stop)) {
    return Fail(Failure::kInterrupted, config_.stop->Reason() + " during the " +
                                           std::string(stage_));
  }
  return !track || TrackFrame(frame);
}

bool GraspTask::WaitUntil(const std::function<bool(bool*)>& done, std::string_view what,
                          bool track) {
  // The move's time counts from the last frame before it; with none yet, from the first one
  // (a camera's clock need not start at 0: a real one counts from its own start).
  std::optional<double> t0;
  if (have_frame_) t0 = last_frame_.t_s;
  for (;;) {
    // Untracked, the frames only keep time while the move goes on: nobody looks at their images.
    if (!GrabFrame(track, /*images=*/track)) return false;
    if (!t0) t0 = last_frame_.t_s;
    bool finished = false;
    if (!done(&finished)) return false;
    if (finished) return true;
    if (last_frame_.t_s - *t0 > config_.move_timeout_s) {
      return Fail(Failure::kDeviceError, std::string(what) + " did not end within " +
                                             std::to_string(config_.move_timeout_s) + " s");
    }
  }
}

bool GraspTask::ArmStill(bool* still) {
  device::ArmState s;
  if (!DeviceOk(dev_->ArmOf(result_.plan->side).Read(&s), ArmKey(), "read")) return false;
  *still = !s.moving;
  return true;
}

bool GraspTask::HandStill(bool* still) {
  device::HandState s;
  if (!DeviceOk(dev_->HandOf(result_.plan->side).Read(&s), HandKey(), "read")) return false;
  *still = !s.moving;
  return true;
}

bool GraspTask::HeadStill(bool* still) {
  device::HeadState s;
  if (!DeviceOk(dev_->head->Read(&s), "head", "read")) return false;
  *still = !s.moving;
  return true;
}

bool GraspTask::TrackFrame(const device::StereoFrame& frame) {
  if (!tracker_ || (!tracker_->tracking() && !tracker_->lost())) return true;
  const servo::TrackerStatus s = tracker_->Track(frame);
  if (s == servo::TrackerStatus::kLost) return Recover();
  return true;
}

bool GraspTask::Recover() {
  const double t0 = last_frame_.t_s;
  for (;;) {
    const servo::TrackerStatus s = tracker_->Initialise(*dev_->leds, *dev_->cameras);
    if (s == servo::TrackerStatus::kOk) return true;
    if (s == servo::TrackerStatus::kDeviceError) {
      return DeviceOk(tracker_->device_status(), tracker_->failed_device(), "flashing the LEDs");
    }
    if (last_frame_.t_s - t0 > config_.recovery_s) {
      return Fail(Failure::kTrackingLost, "the gripper's LEDs were not found again in " +
                                              std::to_string(config_.recovery_s) +
                                              " s of flashing");
    }
  }
}

bool GraspTask::AimHead(const Eigen::Vector3d& p_C, bool* moved) {
  *moved = false;
  const device::HeadJoints q_old = last_frame_.head;  // the joints p_C was measured at
  const servo::HeadTrackingResult aim = head_tracker_.Track(q_old, p_C);
  if (!aim.moved) return true;
  if (!DeviceOk(dev_->head->MoveTo(aim.q), "head", "move")) return false;
  // The cameras move: no gripper measurement until they are still again, and then a few
  // frames more while the axes settle on their set-points.
  if (!WaitUntil([this](bool* still) { return HeadStill(still); }, "head move", /*track=*/false)) {
    return false;
  }
  for (int k = 0; k < config_.settle_frames; ++k) {
    if (!GrabFrame(false)) return false;
  }
  // The filter carried into the new camera frame by the head kinematics (the joints latched
  // with the frames); the target follows from the same kinematics at every iteration.
  tracker_->CarryThroughCameraMove(head_tracker_.X_CnewC(q_old, last_frame_.head));
  ++result_.head_moves;
  *moved = true;
  return true;
}

device::Status GraspTask::MoveRelative(device::Arm& arm, const Pose3& X_EEnew, Pose3* moved) {
  // The controller refuses a move whose end it cannot solve for (near a wrist singularity, its
  // local solver may not converge): try the same direction, shorter, before giving up.
  Pose3 step = X_EEnew;
  device::Status s = device::Status::kRejected;
  for (int attempt = 0; attempt < 4; ++attempt) {
    s = arm.MoveRelative(step);
    *moved = step;
    if (s != device::Status::kRejected) return s;
    const Eigen::AngleAxisd turn(step.linear());
    step.linear() = Eigen::AngleAxisd(0.5 * turn.angle(), turn.axis()).toRotationMatrix();
    step.translation() *= 0.5;
  }
  return s;
}

bool GraspTask::MoveAndWait(const Pose3& X_EEnew, std::string_view what,
                            std::string_view refused) {
  Pose3 moved = Pose3::Identity();
  const device::Status s = MoveRelative(dev_->ArmOf(result_.plan->side), X_EEnew, &moved);
  if (s == device::Status::kRejected) return Fail(Failure::kUnreachable, std::string(refused));
  if (!DeviceOk(s, ArmKey(), "move")) return false;
  if (!WaitUntil([this](bool* still) { return ArmStill(still); }, what, /*track=*/false)) {
    return false;
  }
  tracker_->ExpectMove(moved, last_frame_.t_s);
  return true;
}

bool GraspTask::Look() {
  BeginStage("look");
  device::HeadState head;
  if (!DeviceOk(dev_->head->Read(&head), "head", "read")) return false;
  if (config_.look_head) {
    const device::HeadJoints& q = *config_.look_head;
    const double tol = config_.look_head_tolerance_rad;
    if (std::abs(head.q.pan - q.pan) > tol || std::abs(head.q.tilt - q.tilt) > tol ||
        std::abs(head.q.verge - q.verge) > tol) {
      if (!DeviceOk(dev_->head->MoveTo(q), "head", "move")) return false;
      if (!WaitUntil([this](bool* still) { return HeadStill(still); }, "head move", false)) {
        return false;
      }
      for (int k = 0; k < config_.settle_frames; ++k) {
        if (!GrabFrame(false)) return false;
      }
      if (!DeviceOk(dev_->head->Read(&head), "head", "read")) return false;
    }
  }
  result_.scan_head = head.q;
  scan::Scanner scanner(model_.head, model_.cameras, model_.laser);
  scan::SweepConfig sweep = config_.sweep;
  if (sweep.stop == nullptr) sweep.stop = config_.stop;
  result_.scan = scanner.Scan(*dev_, sweep);
  if (result_.scan->status == device::Status::kInterrupted) {
    return DeviceOk(result_.scan->status, "", "scan");
  }
  if (result_.scan->status != device::Status::kOk) {
    result_.failed_device = result_.scan->failed_device;
    return Fail(Failure::kDeviceError, result_.scan->failed_device + ": " +
                                           std::string(device::ToString(result_.scan->status)) +
                                           " during the scan");
  }
  result_.scene = model::ModelScene(result_.scan->range, config_.model);
  const std::optional<std::string_view> colour =
      config_.target_color.empty() ? model::ColourOfName(config_.target_name)
                                   : std::optional<std::string_view>(config_.target_color);
  if (!colour) {
    return Fail(Failure::kNoTarget, "target name '" + config_.target_name +
                                        "' names no colour; the robot knows objects by colour");
  }
  if (result_.scene->boxes.empty()) return Fail(Failure::kNoTarget, "no box found");
  result_.target = model::ChooseByColour(result_.scene->colours, *colour);
  if (!result_.target) return Fail(Failure::kNoTarget, "no " + std::string(*colour) + " box found");
  // The box as the look saw it, to measure its rise by after the lift.
  result_.box_before = MeasureBoxHeights(
      result_.scan->range, result_.scene->boxes[*result_.target],
      result_.scene->colours[*result_.target].name_index, 0.0, config_.rise);
  EndStage();
  return true;
}

bool GraspTask::Plan() {
  BeginStage("plan");
  const auto& arms = model_.arms;
  result_.plan =
      grasp::PlanGrasp(result_.scene->boxes, *result_.target, {&arms[0], &arms[1]}, config_.grasp);
  if (!result_.plan) {
    return Fail(Failure::kUnreachable,
                "no reachable grasp of box " + std::to_string(*result_.target));
  }
  EndStage();
  return true;
}

bool GraspTask::Approach() {
  BeginStage("approach");
  const grasp::GraspPlan& plan = *result_.plan;
  device::Arm& arm = dev_->ArmOf(plan.side);
  opening_m_ = plan.opening_m;
  if (!DeviceOk(arm.SetSpeed(config_.arm_speed), ArmKey(), "speed")) return false;
  if (!DeviceOk(dev_->HandOf(plan.side).Open(plan.opening_m), HandKey(), "open")) return false;
  // Above the pre-grasp first, then down to it: the hand comes onto the box from above.
  for (const device::Joint6* q : {&plan.q_via, &plan.q_pre}) {
    if (!DeviceOk(arm.MoveJoints(*q), ArmKey(), "move")) return false;
    const auto still = [this](bool* done) {
      bool arm_still = false, hand_still = false;
      if (!ArmStill(&arm_still) || !HandStill(&hand_still)) return false;
      *done = arm_still && hand_still;
      return true;
    };
    if (!WaitUntil(still, "arm move", false)) return false;
  }
  tracker_.emplace(plan.side, model_.leds.Of(plan.side), model_.cameras, model_.head,
                   config_.tracker);
  EndStage();
  return true;
}

bool GraspTask::ServoTo(const Pose3& X_WT, std::string name, std::string_view reached) {
  ServoPhase phase;
  phase.name = std::move(name);
  const double t0 = last_frame_.t_s;
  for (;;) {
    // The arm is still: let the filter settle on it.
    for (int k = 0; k < config_.settle_frames; ++k) {
      if (!GrabFrame(true)) return false;
    }
    // The target held relative to the cameras: carried through any head motion by the head
    // kinematics at the joints latched with the frame (X_C'T = X_C'C X_CT = X_WC'^-1 X_WT).
    X_CT_ = model_.head.X_WC(kCL, last_frame_.head).inverse() * X_WT;
    const servo::ServoCommand cmd =
        servo::ComputeServoCommand(tracker_->pose(), *X_CT_, config_.law);
    phase.final_error = cmd.error;
    phase.errors.push_back(cmd.error);
    // Within the law's tolerance; or, after fine_iterations, within the coarse one (the arm's
    // smallest moves and the filter's noise can keep the error from ever settling in the fine).
    const bool coarse = phase.iterations >= config_.fine_iterations &&
                        cmd.error.translation_m <= config_.coarse_translation_tolerance_m &&
                        cmd.error.rotation_rad <= config_.law.rotation_tolerance;
    if (cmd.converged || coarse) {
      phase.converged = true;
      break;
    }
    if (phase.iterations >= config_.max_iterations) {
      phase.sim_s = last_frame_.t_s - t0;
      result_.servo.push_back(phase);
      return Fail(Failure::kServoTimeout, "servo to the " + phase.name + " did not converge in " +
                                              std::to_string(config_.max_iterations) +
                                              " iterations");
    }
    // Keep the gripper in view; after a head move, measure again before commanding.
    bool moved = false;
    if (!AimHead(tracker_->pose().translation(), &moved)) return false;
    if (moved) continue;
    ++phase.iterations;
    if (!MoveAndWait(cmd.X_EEnew, "arm move",
                     "the arm refused the servo move towards the " + phase.name +
                         " (out of reach)")) {
      return false;
    }
  }
  phase.sim_s = last_frame_.t_s - t0;
  result_.servo.push_back(phase);
  Moment(reached);
  return true;
}

bool GraspTask::Servo() {
  BeginStage("servo");
  const grasp::GraspPlan& plan = *result_.plan;
  // Find the gripper and identify its LEDs by flashing them (paper section 6).
  const servo::TrackerStatus s = tracker_->Initialise(*dev_->leds, *dev_->cameras);
  if (s == servo::TrackerStatus::kDeviceError) {
    return DeviceOk(tracker_->device_status(), tracker_->failed_device(), "flashing the LEDs");
  }
  if (s != servo::TrackerStatus::kOk && !Recover()) return false;
  // Look at the gripper and the grasp together.
  const Pose3 X_CW = model_.head.X_WC(kCL, last_frame_.head).inverse();
  const Eigen::Vector3d between =
      0.5 * (tracker_->pose().translation() + X_CW * plan.X_WE.translation());
  bool moved = false;
  if (!AimHead(between, &moved)) return false;
  X_CT_ = model_.head.X_WC(kCL, last_frame_.head).inverse() * plan.X_WE_pre;
  Moment("servo_start");
  if (!ServoTo(plan.X_WE_pre, "pregrasp", "pregrasp_reached")) return false;
  if (!ServoTo(plan.X_WE, "grasp", "grasp_reached")) return false;
  EndStage();
  return true;
}

bool GraspTask::Close() {
  BeginStage("close");
  const device::Side side = result_.plan->side;
  if (!DeviceOk(dev_->HandOf(side).Close(config_.grip_force_n), HandKey(), "close")) return false;
  if (!WaitUntil([this](bool* still) { return HandStill(still); }, "hand close", true)) {
    return false;
  }
  device::HandState hand;
  if (!DeviceOk(dev_->HandOf(side).Read(&hand), HandKey(), "read")) return false;
  result_.held_opening_m = hand.opening_m;
  opening_m_ = hand.opening_m;
  if (hand.opening_m < config_.min_held_opening_m) {
    return Fail(Failure::kGraspSlipped, "the fingers closed on nothing (opening " +
                                            std::to_string(1e3 * hand.opening_m) + " mm)");
  }
  EndStage();
  return true;
}

bool GraspTask::ScanRise(double opening_m) {
  // The stripe positions that light the modelled box at any rise the check tries.
  scan::Scanner scanner(model_.head, model_.cameras, model_.laser);
  const model::BoxModel& box = result_.scene->boxes[*result_.target];
  const auto [first, last] =
      CountsLightingBox(box, config_.lift_m, model_.laser, model_.head.X_WH(last_frame_.head),
                        config_.sweep, config_.rise);
  scan::SweepConfig sweep = RiseSweep(first, last, config_.sweep, config_.rise);
  if (sweep.stop == nullptr) sweep.stop = config_.stop;
  const scan::ScanResult rescan = scanner.Scan(*dev_, sweep);
  if (rescan.status == device::Status::kInterrupted) return DeviceOk(rescan.status, "", "scan");
  if (rescan.status != device::Status::kOk) {
    result_.failed_device = rescan.failed_device;
    return Fail(Failure::kDeviceError, rescan.failed_device + ": " +
                                           std::string(device::ToString(rescan.status)) +
                                           " during the scan of the lifted box");
  }
  const Eigen::Vector3d camera_W = model_.head.X_WC(kCL, last_frame_.head).translation();
  // The hand's cells are not the box's (a black or an orange box would count them): where its
  // LEDs put it, else where the plan put it, raised by the lift.
  Pose3 X_WE_up = result_.plan->X_WE;
  X_WE_up.translation().z() += config_.lift_m;
  if (tracker_->tracking()) X_WE_up = model_.head.X_WC(kCL, last_frame_.head) * tracker_->pose();
  const std::vector<grasp::OrientedBox> hand_region =
      HandRegion(X_WE_up, opening_m, config_.grasp.hand, config_.rise);
  result_.box_rise = MeasureRise(rescan.range, box,
                                 result_.scene->colours[*result_.target].name_index, camera_W,
                                 config_.lift_m, config_.rise,
                                 result_.box_before ? &*result_.box_before : nullptr, hand_region);
  return true;
}

bool GraspTask::Lift() {
  BeginStage("lift");
  const device::Side side = result_.plan->side;
  // Straight up in W, expressed in the gripper frame for the arm's relative move.
  Pose3 X_WC = model_.head.X_WC(kCL, last_frame_.head);
  const bool tracking = tracker_->tracking();
  const Pose3 X_WE = tracking ? X_WC * tracker_->pose() : result_.plan->X_WE;
  const double z0 = X_WE.translation().z();
  Pose3 up = Pose3::Identity();
  up.translation() = X_WE.linear().transpose() * Eigen::Vector3d(0, 0, config_.lift_m);
  // In steps of at most a servo step, each as far as the controller accepts.
  const int steps = static_cast<int>(std::ceil(config_.lift_m / config_.law.max_translation_step));
  for (int k = 0; k < steps; ++k) {
    Pose3 step = Pose3::Identity();
    step.translation() = up.translation() / steps;
    if (!MoveAndWait(step, "lift", "the arm refused the lift (out of reach)")) return false;
  }
  // The rise as the cameras see the gripper: a loaded arm, or a controller's relative moves,
  // can come up short (through the twin's VAL II consoles, 3-4 mm of 50). The shortfall is
  // moved again, as the servo moves to a target.
  for (int k = 0; k < config_.max_lift_corrections && tracker_->tracking(); ++k) {
    const Pose3 X_WE_now = model_.head.X_WC(kCL, last_frame_.head) * tracker_->pose();
    const double short_m = config_.lift_m - (X_WE_now.translation().z() - z0);
    if (short_m <= config_.lift_tolerance_m) break;
    Pose3 step = Pose3::Identity();
    step.translation() = X_WE_now.linear().transpose() *
                         Eigen::Vector3d(0, 0, std::min(short_m, config_.law.max_translation_step));
    if (!MoveAndWait(step, "lift", "the arm refused the lift (out of reach)")) return false;
    ++result_.lift_corrections;
  }
  // Hold it up.
  const double t_up = last_frame_.t_s;
  while (last_frame_.t_s - t_up < config_.hold_s) {
    if (!GrabFrame(true)) return false;
  }
  if (tracker_->tracking()) {
    X_WC = model_.head.X_WC(kCL, last_frame_.head);
    result_.gripper_rise_m = (X_WC * tracker_->pose()).translation().z() - z0;
  }
  device::HandState hand;
  if (!DeviceOk(dev_->HandOf(side).Read(&hand), HandKey(), "read")) return false;
  result_.held_opening_m = hand.opening_m;
  Moment("lifted");
  if (hand.opening_m < config_.min_held_opening_m) {
    return Fail(Failure::kGraspSlipped, "the box slipped out of the hand while held up");
  }
  // The box itself, as the cameras see it now: the gripper may have risen without it.
  if (!ScanRise(hand.opening_m)) return false;
  // Seen in the hand but short of the lift, or seen too vaguely to rule out a short rise: it
  // slid a little in the fingers, or the arm sags under it (through the twin's wires the box
  // ended 44-47 mm up of 50, and a bound of 45 mm on a box that ended 44.5 mm up is no lift to
  // trust). Raised by what it lacks (RiseShortfall) and scanned again.
  for (int k = 0; k < config_.max_box_relifts && tracker_->tracking(); ++k) {
    const double short_m =
        RiseShortfall(*result_.box_rise, config_.lift_m, config_.min_rise_fraction * config_.lift_m,
                      config_.relift_tolerance_m, config_.law.max_translation_step,
                      config_.rise.min_cells);
    if (short_m <= 0.0) break;
    const Pose3 X_WE_now = model_.head.X_WC(kCL, last_frame_.head) * tracker_->pose();
    Pose3 step = Pose3::Identity();
    step.translation() = X_WE_now.linear().transpose() * Eigen::Vector3d(0, 0, short_m);
    if (!MoveAndWait(step, "lift", "the arm refused the lift (out of reach)")) return false;
    ++result_.box_relifts;
    X_WC = model_.head.X_WC(kCL, last_frame_.head);
    result_.gripper_rise_m = (X_WC * tracker_->pose()).translation().z() - z0;
    if (!ScanRise(hand.opening_m)) return false;
  }
  const BoxRise& rise = *result_.box_rise;
  if (!rise.consistent()) {
    return Fail(Failure::kGraspSlipped,
                "the cameras saw the box where no box raised straight up can be (" +
                    std::to_string(rise.box_cells) + " of its cells): it tipped or moved");
  }
  // The rises tried are whole millimetres: 45 mm passes a 45 mm bound.
  if (rise.min_m < config_.min_rise_fraction * config_.lift_m - 1e-9) {
    char why[200];
    std::snprintf(why, sizeof why,
                  "the cameras cannot rule out that the box rose only %.1f mm (rises %.1f-%.1f "
                  "mm fit what they saw, %d of its cells), under %.0f%% of the %.1f mm lift",
                  1e3 * rise.min_m, 1e3 * rise.min_m, 1e3 * rise.max_m, rise.box_cells,
                  100 * config_.min_rise_fraction, 1e3 * config_.lift_m);
    return Fail(Failure::kGraspSlipped, why);
  }
  result_.lifted = true;
  EndStage();
  return true;
}

const TaskResult& GraspTask::Run() {
  for (bool (GraspTask::*stage)() : {&GraspTask::Look, &GraspTask::Plan, &GraspTask::Approach,
                                     &GraspTask::Servo, &GraspTask::Close, &GraspTask::Lift}) {
    if (!(this->*stage)()) break;
  }
  return result_;
}

}  // namespace hgrasp::task
