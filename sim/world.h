#pragma once
/// @file The simulated world: models/humanoid.xml plus a scenario's objects, stepped in lockstep
/// with the devices. Joint motions are generated here the way the robot's controllers generate
/// them: synchronised, within the joint speed limits, with gravity compensation.

#include <mujoco/mujoco.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/geometry.h"
#include "sim/robot_errors.h"
#include "sim/scenario.h"

namespace hgrasp::sim {

/// Laser encoder resolution: 36000 counts per revolution, 0.01 deg per count (models/humanoid.xml
/// gives the reason).
constexpr double kLaserCountsPerRev = 36000.0;
constexpr double kLaserRadPerCount = 2.0 * kPi / kLaserCountsPerRev;

/// Stereo frame period (PAL, 25 frames/s).
constexpr double kFramePeriodS = 0.04;

/// The pose of a MuJoCo frame from its position (3) and row-major rotation matrix (9), as in
/// mjData's xpos/xmat, site_xpos/site_xmat, cam_xpos/cam_xmat.
Pose3 PoseFromMujoco(const mjtNum* pos, const mjtNum* mat);

/// A scenario object in the MuJoCo model.
struct SimObject {
  ObjectSpec spec;
  int body = -1;  ///< MuJoCo body id (name "obj_<name>")
  int geom = -1;  ///< MuJoCo geom id (name "obj_<name>")
};

struct WorldOptions {
  std::string model_path = "models/humanoid.xml";  ///< MJCF; the URDF beside it gives limits
  double settle_s = 0.5;  ///< simulated time for the objects to come to rest on the table
  /// MJCF added to <worldbody> besides the scenario's objects (test probes, markers).
  std::string extra_worldbody_xml;
  /// Where the head is really mounted on the torso relative to the model (and to the URDF the
  /// pipeline's kinematics read): X_MT, the true mounting T of the head (body head_pan_link, with
  /// its cameras and laser) in the modelled mounting M. Identity: as modelled. Tests displace it
  /// to show that the visual servo needs no camera-to-arm calibration. Composed with the
  /// scenario's robot_errors mounting (head_mount_error first).
  Pose3 head_mount_error = Pose3::Identity();
};

class World {
 public:
  /// Builds the world; throws InputError when the model cannot be loaded and std::runtime_error
  /// when MuJoCo rejects the composed model. Starts in keyframe "home" and lets the objects
  /// settle on the table.
  explicit World(Scenario scenario, const WorldOptions& options = {});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  /// The true robot: the model with the links moved by robot_errors.
  const mjModel* model() const { return model_; }
  /// The robot as built to its drawings (models/humanoid.xml, as the URDF the pipeline reads):
  /// what the simulated controllers' kinematics know. Same structure as model().
  const mjModel* nominal_model() const { return nominal_model_; }
  /// The errors this robot was built with (sim/robot_errors.h).
  const RobotErrors& robot_errors() const { return errors_; }
  mjModel* mutable_model() { return model_; }
  const mjData* data() const { return data_; }
  mjData* data() { return data_; }
  const Scenario& scenario() const { return scenario_; }
  const std::vector<SimObject>& objects() const { return objects_; }

  double time() const { return data_->time; }

  /// Advances simulated time by `duration_s`, running the joint motion generators. Throws
  /// std::runtime_error if the simulation diverges (NaN or huge state or control).
  void Step(double duration_s);

  /// Starts a synchronised move of `actuators` to `goal` (joint units, as the joints' encoders
  /// read: the link goes where robot_errors put it for that reading; the motion starts after
  /// the joints' command latency): every joint arrives together. Smooth moves follow a cubic profile whose peak speed stays within `speed_limit`
  /// of every joint; constant-speed moves (the laser motor) ramp up over 40 ms, run at
  /// `speed_limit`, and ramp down over 40 ms.
  void StartMotion(const std::vector<int>& actuators, const std::vector<double>& goal,
                   const std::vector<double>& speed_limit, bool constant_speed);
  /// True while any of `actuators` has a motion under way.
  bool Moving(const std::vector<int>& actuators) const;
  /// Ends the motion of `actuators` where their set-points are now.
  void StopMotion(const std::vector<int>& actuators);
  /// What the encoder of the joint driven by `actuator` reads now: the link's angle less its
  /// zero error, the backlash taken up in the last move's direction, in whole encoder steps.
  double EncoderReading(int actuator) const;
  /// The set-point of `actuator` now, as its encoder would read it there.
  double EncoderSetpoint(int actuator) const;

  /// Id of a named model element; std::runtime_error when the model lacks it.
  int Id(mjtObj type, const std::string& name) const;
  /// Position of a named scalar joint (rad or m).
  double JointPosition(const std::string& joint) const;
  /// Speed limit of the joint driven by actuator `actuator` (from models/humanoid.urdf).
  double SpeedLimit(int actuator) const { return speed_limit_[actuator]; }

  /// Pose of a site (name) or body (name) in W.
  Pose3 SitePose(int site) const;
  Pose3 BodyPose(int body) const;

  /// Whether the straight path from `from_W` to `to_W` is free of geometry, ignoring the last
  /// `ignore_near_to_m` metres before `to_W` (the emitter's own housing).
  bool PathClear(const Eigen::Vector3d& from_W, const Eigen::Vector3d& to_W,
                 double ignore_near_to_m) const;

  /// Laser on/off as switched by the laser board.
  bool laser_on() const { return laser_on_; }
  void set_laser_on(bool on) { laser_on_ = on; }

  /// Switches LED `index` of the gripper `side` ("left"/"right") on or off.
  void SetLed(const std::string& side, int index, bool on);
  int LedCount(const std::string& side) const;

  /// Hides every LED (they render dark whatever they are switched to) from simulated time
  /// `from_s` until `until_s`: something passing in front of the hand. Tests of the tracker's
  /// recovery use it. Replaces any earlier window.
  void HideLeds(double from_s, double until_s);
  /// True while the LEDs are hidden.
  bool leds_hidden() const { return leds_hidden_; }

  /// A counter that changes whenever something a camera could see may have changed other than
  /// by motion (LEDs); with the joint positions it keys the renderer's cache.
  std::uint64_t appearance_version() const { return appearance_version_; }

 private:
  struct Motion {
    double start = 0, goal = 0, t0 = 0, duration = 0;
    bool active = false, constant_speed = false;
  };
  void ApplyControllers();
  /// Sets each LED geom's material from its switch and the hiding window.
  void ApplyLeds();

  // The link angle for an encoder reading, the backlash taken up in direction dir_[a].
  double LinkAngle(int actuator, double encoder) const;

  Scenario scenario_;
  RobotErrors errors_;
  std::vector<JointError> joint_error_;  // per actuator
  std::vector<int> dir_;                 // per actuator: the last move's direction (-1, 0, 1)
  mjModel* nominal_model_ = nullptr;
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::vector<SimObject> objects_;
  std::vector<Motion> motion_;       // per actuator
  std::vector<double> speed_limit_;  // per actuator
  std::vector<int> robot_dofs_;      // dofs that get gravity compensation
  bool laser_on_ = false;
  int led_on_material_ = -1, led_off_material_ = -1;
  std::map<int, bool> led_switched_on_;  // LED geom -> switched on
  double hide_from_s_ = 0.0, hide_until_s_ = 0.0;
  bool leds_hidden_ = false;
  std::uint64_t appearance_version_ = 0;
};

}  // namespace hgrasp::sim
