#pragma once
/// @file The whole grasp (paper sections 3-6), one call per stage: Look (scan, segment, model,
/// choose the target), Plan, Approach (open the hand, move through the via and pre-grasp poses
/// by joint targets), Servo (position-based visual servoing to the pre-grasp and then to the
/// grasp pose), Close, Lift (by task.lift, then hold), with its figures in a TaskResult.
///
/// Only the device seam is used (device::RobotDevices): the same task runs the simulator, the
/// emulators and the real robot. The servo needs no camera-to-arm calibration: the grasp pose,
/// planned in W from the scan, is turned once into a target held relative to the cameras
/// (X_CT = X_WC(q_head)^-1 * X_WE), the gripper is measured by its LEDs in the same camera frame,
/// and each correction is a differential move in the gripper frame (servo/control_law.h). The
/// open-loop approach uses the arm kinematics and may be centimetres off; the servo removes that.
///
/// Each servo iteration: the arm is still; the tracker has fused `settle_frames` frames since it
/// stopped; the command X_EE' comes from the filter's pose and the target; it goes to
/// Arm::MoveRelative; the frames of the move only keep time, and once the arm is still the
/// tracker takes the gripper as moved by the command (GripperTracker::ExpectMove: against the
/// real drivers the frames of a move come 0.3 s apart, one per 9600-baud WHERE, too sparse to
/// track a move through). When the gripper strays more than
/// the head tracker's dead band from the cameras' axis, the head re-centres it (between
/// iterations, arm still) and the target and the filter are carried into the new camera frame.
/// When tracking is lost, the LEDs are flashed again (GripperTracker::Initialise) until they are
/// found or recovery_s of device time has passed.
///
/// Every frame grabbed (the scan's too) goes to the frame sink with a TaskView: what the task
/// believes at that moment (gripper pose, target), for pictures and video. Key moments (servo
/// start, pre-grasp reached, grasp reached, lifted) are sent again with TaskView::moment set.
/// Frames grabbed only to wait for a move to end come without images unless the sink needs
/// every frame's (TaskConfig::sink_needs_every_image).

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/geometry.h"
#include "device/robot_devices.h"
#include "grasp/grasp_planner.h"
#include "model/scene_model.h"
#include "robot/arm_kinematics.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/scanner.h"
#include "servo/control_law.h"
#include "servo/gripper_tracker.h"
#include "servo/head_tracking.h"
#include "servo/led_layout.h"
#include "task/box_rise.h"

namespace hgrasp::task {

/// How the task ended (DESIGN.md: named in the report's `failure`).
enum class Failure {
  kNone = 0,
  kNoTarget,      ///< no box of the target's colour was modelled
  kUnreachable,   ///< no feasible grasp, or the arm refused a move
  kTrackingLost,  ///< the gripper's LEDs were not found again after recovery attempts
  kServoTimeout,  ///< the servo did not converge within max_iterations
  kGraspSlipped,  ///< the fingers closed on nothing, or the box left the hand while held
  kDeviceError,   ///< a device returned an error status, or a move never ended
  kInterrupted,   ///< a stop was requested (SIGINT, SIGTERM: TaskConfig::stop)
};

/// "no_target", "unreachable", ... ("" for kNone).
std::string_view ToString(Failure f);

struct TaskConfig {
  /// The target: a colour word (model/colour.h), or an object name read through its colour
  /// word (the robot knows objects only by what it sees).
  std::string target_color;
  std::string target_name;
  double lift_m = 0.05;  ///< how far the box is lifted (m)
  double hold_s = 2.0;   ///< how long it is held up (s)

  scan::SweepConfig sweep;
  /// Where the head looks for the scan (scan::kLookHead). The look first moves the head there
  /// when it stands more than look_head_tolerance_rad away on any axis (a real Biclops ends its
  /// homing looking ahead); unset: it scans from wherever the head is.
  std::optional<device::HeadJoints> look_head = scan::kLookHead;
  double look_head_tolerance_rad = DegToRad(0.1);
  /// Polled at every frame (the scan's sweep included): when requested the stage ends with
  /// Failure::kInterrupted. May be null.
  const StopRequest* stop = nullptr;
  model::SceneModelConfig model;
  grasp::GraspConfig grasp;
  servo::GripperTrackerOptions tracker;
  servo::ControlLawOptions law;
  servo::HeadTrackingOptions head;
  /// Servo iterations (commanded moves) per servo phase before servo_timeout.
  int max_iterations = 40;
  /// A servo phase has converged within the law's tolerances (TaskConfig() sets 1 mm and
  /// 1 deg), or, after this many iterations, within coarse_translation_tolerance_m and the law's
  /// rotation tolerance.
  int fine_iterations = 10;
  double coarse_translation_tolerance_m = 0.002;
  /// Frames tracked with the arm still before each command.
  int settle_frames = 4;
  /// Device time (s) spent flashing the LEDs to find them again before tracking_lost.
  double recovery_s = 3.0;
  /// Fraction of its joint speed limits the planned arm moves at (Arm::SetSpeed, VAL II SPEED),
  /// set as the approach begins: a controller keeps the speed it was left at (VAL's monitor
  /// comes up at 50 %); the simulated arms run at their limits unless told otherwise.
  double arm_speed = 1.0;
  double grip_force_n = 40.0;  ///< Hand::Close force (N)
  /// The lift is judged by the box: after the hold the stripe positions that lit the box in the
  /// look are scanned again, and the box counts as lifted when what the cameras saw rules out
  /// every rise under min_rise_fraction of lift_m (task/box_rise.h); else grasp_slipped.
  BoxRiseConfig rise;
  /// After the lift's moves the gripper's rise is measured by its LEDs; short by more than
  /// lift_tolerance_m, the rest is moved again, at most max_lift_corrections times.
  double lift_tolerance_m = 0.001;
  int max_lift_corrections = 2;
  double min_rise_fraction = 0.9;
  /// A box the rise scan sees in the hand (min_cells of it) but short of the lift (the middle
  /// of the rises that fit under lift_m by more than relift_tolerance_m, or their low end under
  /// min_rise_fraction of it) is raised by what it lacks (at most a servo step; RiseShortfall)
  /// and scanned again, this many times at most. In simulation the box ends 48-49 mm up of 50
  /// and its rises' middle near 50 mm: it is seldom raised.
  int max_box_relifts = 1;
  double relift_tolerance_m = 0.002;
  /// The grasp holds while the fingers stay at least this far apart (m): closed to less, they
  /// met with nothing between them.
  double min_held_opening_m = 0.01;
  /// A move (arm, hand, head) that has not ended after this much device time is a device error.
  double move_timeout_s = 10.0;
  /// Whether the frame sink needs the images of every frame (a video of the run). When false, or
  /// with no sink, the frames grabbed only to wait for a move to end (the scan's laser moving to
  /// its start, the arm's approach, the head's re-centring) are grabbed without images
  /// (StereoCamera::GrabWithoutImages; the simulator does not render them) and reach the sink
  /// without them. Key moments always come with theirs.
  bool sink_needs_every_image = true;

  TaskConfig();
};

/// What the calibration files and the robot model give the task.
struct RobotModel {
  robot::StereoIntrinsics cameras;
  robot::LaserCalibration laser;
  robot::HeadKinematics head;
  std::array<robot::ArmKinematics, 2> arms;  ///< left, right
  servo::LedLayouts leds;
};

/// Reads the robot model: the stereo intrinsics, the laser calibration and the LED layouts
/// (paths resolved through ResolveDataPath) and the kinematics from models/humanoid.urdf.
/// @throws hgrasp::InputError naming the file and field of bad input.
RobotModel LoadRobotModel(const std::string& cameras_path, const std::string& laser_path,
                          const std::string& leds_path);

/// One servo phase's figures.
struct ServoPhase {
  std::string name;  ///< "pregrasp" or "grasp"
  int iterations = 0;
  bool converged = false;
  servo::ServoError final_error;  ///< the last error by the filter, in the gripper frame
  std::vector<servo::ServoError> errors;  ///< the error by the filter before each move, in order
  double sim_s = 0;                       ///< device time spent (s)
};

/// Figures of one stage.
struct StageTiming {
  std::string name;
  double wall_s = 0;    ///< wall-clock time (s)
  double device_s = 0;  ///< device time (frame time stamps) (s)
  int frames = 0;       ///< frames grabbed
};

struct TaskResult {
  Failure failure = Failure::kNone;
  std::string message;  ///< what failed, in words ("" when ok)
  /// With kDeviceError: the device that failed, by its key in the scenario's devices block
  /// ("arm_right", "hand_left", "head", "laser", "leds", "cameras").
  std::string failed_device;

  // Look
  std::optional<scan::ScanResult> scan;
  std::optional<model::SceneModel> scene;
  std::optional<int> target;
  device::HeadJoints scan_head;  ///< the head's joints during the scan
  // Plan
  std::optional<grasp::GraspPlan> plan;
  // Servo
  std::vector<ServoPhase> servo;
  std::int64_t recoveries = 0;          ///< times tracking was lost and found again by flashing
  std::int64_t flashes = 0;             ///< single-LED flash frames
  std::int64_t measurements = 0;        ///< gripper poses fused by the filter
  std::int64_t image_measurements = 0;  ///< of those, from the image-level fallback
  int head_moves = 0;                   ///< head re-centrings
  // Close and lift
  double held_opening_m = 0;  ///< finger opening after closing (m)
  /// Lifted and still held after hold_s: the cameras measured the box risen by at least
  /// min_rise_fraction of lift_m, and the fingers still hold something.
  bool lifted = false;
  /// The box's cells in the look's scan, before the grasp (none: too few of them): the rise's
  /// measure starts from them.
  std::optional<BoxHeights> box_before;
  /// The rises of the box the cameras' rise scan after the hold leaves possible; unset when the
  /// task ended before it.
  std::optional<BoxRise> box_rise;
  /// Rise of the gripper measured by the cameras (its LEDs) between the grasp and the end of
  /// the hold (m, W z through the head kinematics).
  double gripper_rise_m = 0;
  int lift_corrections = 0;  ///< moves after the lift's own, for its shortfall
  int box_relifts = 0;       ///< raises for the box's shortfall seen by the rise scan

  std::vector<StageTiming> stages;
  double wall_s = 0;    ///< the whole task (s)
  double device_s = 0;  ///< device time from the first frame to the last (s)

  bool ok() const { return failure == Failure::kNone; }
};

/// What the task believes when a frame arrives.
struct TaskView {
  std::string_view stage;   ///< "look", "approach", "servo", ...
  std::string_view moment;  ///< "" for ordinary frames; else the key moment's name
  device::Side side = device::Side::kLeft;
  std::optional<Pose3> X_CE;  ///< the tracked gripper pose in CL (when tracking)
  std::optional<Pose3> X_CT;  ///< the servo target in CL (while servoing)
  std::optional<Pose3> X_CG;  ///< the planned grasp in CL (once planned)
  double opening_m = 0;       ///< the finger opening to draw the hands with
};

using FrameSink = std::function<void(const device::StereoFrame&, const TaskView&)>;

class GraspTask {
 public:
  /// The task drives `dev` (which must outlive it) with `model` and `config`. While it lives,
  /// dev.cameras is wrapped so that every frame also reaches `sink` (may be empty).
  GraspTask(device::RobotDevices* dev, RobotModel model, TaskConfig config, FrameSink sink = {});
  ~GraspTask();
  GraspTask(const GraspTask&) = delete;
  GraspTask& operator=(const GraspTask&) = delete;

  // The stages, in order; each returns false (and sets result().failure) when the task cannot
  // go on. A stage needs the ones before it to have succeeded.
  bool Look();
  bool Plan();
  bool Approach();
  bool Servo();
  bool Close();
  bool Lift();

  /// Every stage in order, stopping at the first failure.
  const TaskResult& Run();

  const TaskResult& result() const { return result_; }
  const RobotModel& model() const { return model_; }
  const TaskConfig& config() const { return config_; }
  /// The tracker of the planned arm's gripper (after Approach).
  const servo::GripperTracker* tracker() const { return tracker_ ? &*tracker_ : nullptr; }

 private:
  class SinkCamera;

  void OnFrame(const device::StereoFrame& frame);
  TaskView View(std::string_view moment) const;
  /// Sends the last frame (which must have its images) to the sink again, as the key moment
  /// `moment`.
  void Moment(std::string_view moment);
  void BeginStage(std::string_view name);
  void EndStage();
  /// Records the failure, ends the stage; returns false.
  bool Fail(Failure f, std::string message);
  /// True for kOk; else fails with device_error naming `what`.
  /// kOk: true. Else the task fails: kInterrupted for Status::kInterrupted, else kDeviceError
  /// naming `device` (a devices key), what it said and `what` was asked.
  bool DeviceOk(device::Status s, std::string_view device, std::string_view what);
  /// The devices keys of the planned side's arm and hand: "arm_left", "hand_right", ...
  std::string ArmKey() const;
  std::string HandKey() const;
  /// One frame, tracked when `track` and a tracker runs; without images (when the sink does
  /// not need them) when not `images`, which must then not be tracked.
  bool GrabFrame(bool track, bool images = true);
  /// Grabs frames until `done` holds (false and device_error after move_timeout_s).
  /// Grabs frames until done(&finished) gives finished; false (the task failed) when done
  /// returns false, a grab fails, a stop is requested, or it takes move_timeout_s. Untracked
  /// frames are grabbed without images.
  bool WaitUntil(const std::function<bool(bool*)>& done, std::string_view what, bool track);
  // Whether the device has stopped moving (*still); false when its read failed (the task has
  // then failed, naming it).
  bool ArmStill(bool* still);
  bool HandStill(bool* still);
  bool HeadStill(bool* still);
  /// Tracks the frame; on loss, flashes the LEDs until found again (or tracking_lost).
  bool TrackFrame(const device::StereoFrame& frame);
  bool Recover();
  /// Turns the head so that p_C (in CL) comes onto the axis, unless it is inside the dead band;
  /// carries the target and the filter into the new camera frame.
  bool AimHead(const Eigen::Vector3d& p_C, bool* moved);
  bool ServoTo(const Pose3& X_WT, std::string name, std::string_view reached_moment);
  /// Arm::MoveRelative; when refused, the same move halved, up to three times. *moved: the move
  /// the arm took (X_EEnew or a part of it), when it took one.
  device::Status MoveRelative(device::Arm& arm, const Pose3& X_EEnew, Pose3* moved);
  /// MoveRelative, then frames until the arm is still; the tracker takes the move on trust.
  bool MoveAndWait(const Pose3& X_EEnew, std::string_view what, std::string_view refused);
  /// Scans the held box again and measures its rise (result_.box_rise), the hand's cells left
  /// out at the fingers' `opening_m`; false when a device failed (the failure is set).
  bool ScanRise(double opening_m);

  device::RobotDevices* dev_;
  RobotModel model_;
  TaskConfig config_;
  FrameSink sink_;
  SinkCamera* camera_ = nullptr;  // owned by dev_->cameras while the task lives
  servo::HeadTracker head_tracker_;

  TaskResult result_;
  std::optional<servo::GripperTracker> tracker_;
  std::optional<Pose3> X_CT_;  // the servo target in CL, while servoing
  std::string_view stage_ = "";
  device::StereoFrame last_frame_;
  bool have_frame_ = false;
  double first_t_s_ = 0;
  std::int64_t frames_ = 0;
  double opening_m_ = 0;
  std::chrono::steady_clock::time_point task_wall_, stage_wall_;
  double stage_device_s_ = 0;
  std::int64_t stage_frames_ = 0;
  bool stage_started_with_frame_ = false;
};

}  // namespace hgrasp::task
