#pragma once
/// @file A Puma 260 arm's VAL II controller, as its console presents it: the monitor's prompt,
/// echo and line editing, the commands the driver uses (WHERE, SPEED, DO MOVE, DO APPRO,
/// DO READY, ABORT) with VAL's error messages between asterisks, over a model of the arm's
/// joint motion. Byte for byte as drivers/val2/PROTOCOL.md describes it.
///
/// The arm model (Val2ArmModel) is an interface: TrapezoidArmModel moves the six joints with
/// trapezoidal profiles within the URDF's limits; a simulated arm can take its place. The
/// controller's kinematics (TRANS, HERE, WHERE's location) are robot::ArmKinematics from
/// models/humanoid.urdf; VAL's world frame is the arm's base link (<side>_base) and its tool
/// frame the gripper frame E.

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "common/geometry.h"
#include "device/arm.h"
#include "device/status.h"
#include "emulators/emulator.h"
#include "emulators/motion.h"
#include "robot/arm_kinematics.h"
#include "val2/val2_codec.h"

namespace hgrasp::drivers {

/// The arm under the controller: six joints moved in joint space.
class Val2ArmModel {
 public:
  virtual ~Val2ArmModel() = default;
  /// Joint angles (rad, models/humanoid.urdf convention) and rates (rad/s).
  virtual device::Joint6 q() const = 0;
  virtual device::Joint6 qd() const = 0;
  virtual bool moving() const = 0;
  /// Coordinated joint motion to `q_target` (rad): every joint starts and arrives together, none
  /// faster than `speed_fraction` of its speed limit. Replaces a motion under way.
  virtual void MoveJoints(const device::Joint6& q_target, double speed_fraction) = 0;
  /// Decelerates every joint to rest where it is.
  virtual void Stop() = 0;
  /// Advances the motion by dt (s).
  virtual void Advance(double dt) = 0;
};

/// Six TrapezoidAxis, one per joint.
class TrapezoidArmModel final : public Val2ArmModel {
 public:
  /// `limits`: position (rad), speed (rad/s) and acceleration (rad/s^2) limits of each joint.
  TrapezoidArmModel(const std::array<AxisLimits, 6>& limits, const device::Joint6& q0);

  device::Joint6 q() const override;
  device::Joint6 qd() const override;
  bool moving() const override;
  void MoveJoints(const device::Joint6& q_target, double speed_fraction) override;
  void Stop() override;
  void Advance(double dt) override;

 private:
  std::vector<TrapezoidAxis> axes_;
};

/// One command the controller executed (state-changing commands only: SPEED, MOVE, APPRO,
/// READY, ABORT), for the tests' no-loss, no-duplicate, no-alteration checks.
struct Val2Executed {
  double t_s = 0.0;       ///< emulator time (s)
  std::string line;       ///< the command line as it ran (trailing blanks, which VAL ignores, cut)
  val2::Command command;  ///< parsed
};

class Val2Emulator final : public DeviceEmulator {
 public:
  /// `X_WB`: VAL's world frame (the arm's base) in W. `kinematics`: the arm's, in W.
  Val2Emulator(std::unique_ptr<Val2ArmModel> model, robot::ArmKinematics kinematics,
               const Pose3& X_WB, double speed_percent = 50.0);

  void Receive(std::span<const std::uint8_t> in, double t_s,
               std::vector<std::uint8_t>* out) override;
  void Advance(double t_s, std::vector<std::uint8_t>* out) override;

  /// State-changing commands executed, in order.
  const std::vector<Val2Executed>& executed() const { return executed_; }
  /// Lines that ran and were refused, with the message (no asterisks).
  const std::vector<std::pair<std::string, std::string>>& refused() const { return refused_; }
  /// The monitor's speed (percent).
  double speed_percent() const { return speed_percent_; }
  /// The line being typed at the console.
  const std::string& input_line() const { return discipline_.buffer(); }
  /// What WHERE would print now.
  val2::WhereReport Where() const;
  Val2ArmModel& model() { return *model_; }
  const Val2ArmModel& model() const { return *model_; }
  const robot::ArmKinematics& kinematics() const { return kinematics_; }
  /// VAL's world frame (the arm's base) in W.
  const Pose3& X_WB() const { return X_WB_; }
  /// VAL's READY position (deg).
  static constexpr std::array<double, 6> kReadyDeg = {0.0, -90.0, 90.0, 0.0, 0.0, 0.0};

 private:
  /// Runs one command line; returns its output (lines ending CR LF), without the prompt.
  std::string Execute(const std::string& line, double t_s);
  /// Starts a joint motion to q (rad) unless it is out of range; the error message or "".
  std::string MoveTo(const device::Joint6& q);
  /// The joint solution for the tool pose X_BE (in VAL's world frame) nearest the current
  /// joints within the limits; false when there is none.
  bool Solve(const Pose3& X_BE, device::Joint6* q) const;

  std::unique_ptr<Val2ArmModel> model_;
  robot::ArmKinematics kinematics_;
  Pose3 X_WB_;
  double speed_percent_;
  val2::LineDiscipline discipline_;
  double last_t_ = -1.0;
  std::vector<Val2Executed> executed_;
  std::vector<std::pair<std::string, std::string>> refused_;
};

/// The arm `side` of models/humanoid.urdf (found through HGRASP_ROOT) at rest at `q0_deg`, monitor
/// speed 50 %. The default pose holds the gripper over the workspace (0.29 m forward, 0.24 m above
/// the table for the right arm), well away from the shoulder, elbow and wrist singularities.
std::unique_ptr<Val2Emulator> MakeVal2Emulator(device::Side side = device::Side::kRight,
                                               const std::array<double, 6>& q0_deg = {
                                                   0.0, -60.0, 30.0, 0.0, -45.0, 0.0});

}  // namespace hgrasp::drivers
