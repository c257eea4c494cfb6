#pragma once
/// @file The composition root's choice of devices (DESIGN.md rule 2): every device comes from the
/// simulated robot unless the scenario's `devices` block names a real driver for it, in which
/// case that driver is opened on its port with its options (drivers/config/device_config.h).
/// The simulated robot, its MuJoCo world and its EGL context are built only when some device
/// is simulated: on the real robot nothing of the twin exists. The same binary drives the twin,
/// the emulators and the robot.
///
/// In lockstep (`--lockstep`) every device is its real driver, talking to the twin (sim::Twin in
/// lockstep) in this process in simulated time: no pty, no port, no wall clock. The drivers'
/// options are the scenario's where its `devices` block names that driver (its ports unused),
/// else their defaults; the cameras are the twin's (sim::LockstepCamera).

#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "app/safe_stop.h"
#include "app/twin_faults.h"
#include "common/clock.h"
#include "config/device_config.h"
#include "device/robot_devices.h"
#include "sim/scenario.h"
#include "sim/sim_devices.h"
#include "sim/twin/lockstep_camera.h"
#include "sim/twin/twin.h"

namespace hgrasp::app {

/// A device that failed while the robot was being started (the head's homing).
struct StartFailure {
  std::string device;  ///< a devices key
  device::Status status = device::Status::kOk;
  std::string detail;  ///< what the driver said

  /// "device_error", or "interrupted" when a stop signal ended the start.
  std::string failure() const;
  /// {"scenario", "seed", "ok": false, "failure", "failure_detail", "failed_device",
  ///  "safe_stop"}: the report of a command that ended before it began.
  nlohmann::json Report(const sim::Scenario& scenario, const SafeStopReport& safe) const;
};

/// Where a command's ground truth comes from: the world the devices act in and the true
/// cameras on it (sim::TruthJson, sim::ScanTruth, sim::BoxTruth read them). Only a run on the
/// twin has one: every device simulated, or every real driver against the lockstep twin (whose
/// world the task's thread may read between its waits: the clock runs the twin on that same
/// thread). Reports take their `truth` block from it; the pipeline never sees it.
struct TruthWorld {
  sim::World* world = nullptr;
  sim::StereoRig* rig = nullptr;
};

/// The robot a command works with. It is left safe (LeaveSafe) when the command is done; if
/// the command never gets there (an exception), its destructor does it.
struct Robot {
  Robot() = default;
  Robot(Robot&&) = default;
  Robot& operator=(Robot&&) = delete;
  ~Robot();

  /// The simulated robot; null when every device is real. Declared first: the simulated
  /// devices refer to it, so it goes last.
  std::unique_ptr<sim::SimRobot> twin;
  /// Lockstep: the clock of the whole run, the twin behind the real drivers and its cameras'
  /// frames (before the devices, which talk to them). Null otherwise.
  std::unique_ptr<SimClock> clock;
  std::unique_ptr<sim::Twin> lockstep;
  std::shared_ptr<sim::LockstepFrames> frames;
  /// Lockstep: the true cameras on the twin's world, for the truth (rendered only by a report).
  std::unique_ptr<sim::StereoRig> lockstep_truth_rig;
  device::RobotDevices devices;
  bool all_simulated = false;

  /// The ground truth of what the devices saw, when there is one: the simulated robot's when
  /// every device is simulated, the lockstep twin's in lockstep. Else nullptr (a real robot, or
  /// a mix: then the world does not describe every device).
  const TruthWorld* truth() const { return truth_world ? &*truth_world : nullptr; }
  std::optional<TruthWorld> truth_world;

  /// app::LeaveSafe on the devices (safe_stop.h); logs what did not take it.
  SafeStopReport LeaveSafe();

  /// Set when a device failed as the robot was started: the command reports it and ends.
  std::optional<StartFailure> start_failure;

 private:
  bool left_safe_ = false;
};

class OutputDir;

/// Lockstep: writes the twin's account beside the report (twin.json: truth, exposures, every
/// command its emulators executed) into `out`'s staging; nothing otherwise.
void WriteTwinRecord(const Robot& robot, OutputDir& out);

/// When the robot failed to start: leaves it safe, writes the start failure's report into `out`
/// (null: no report, as `calibrate laser` has none), logs it for `command` and returns true.
bool EndedAtStart(Robot& robot, const sim::Scenario& scenario, OutputDir* out,
                  std::string_view command);

/// The devices of `scenario`, opened and started: the twin built only when some device is
/// simulated; a real Biclops head homed (ConfigureAndHome) unless its options say not to, with
/// `stop` polled meanwhile (a failure is Robot::start_failure). Throws hgrasp::InputError
/// naming the field (devices.KEY.port, ...) and the system's reason when a port or pipeline
/// cannot be opened.
/// With `lockstep`, every device on its real driver against the lockstep twin (above), its
/// wires as `*lockstep` asks (faults; control commands at twin times, logged as they run).
/// Throws hgrasp::InputError for wire options out of range.
Robot OpenRobot(const sim::Scenario& scenario, const StopRequest* stop = nullptr,
                const TwinWireOptions* lockstep = nullptr);

/// OpenRobot's `lockstep` for a command that runs in lockstep on clean wires (no faults, no
/// control commands: `scan`, `model`, `plan`, `calibrate` with --lockstep); nullptr when
/// `lockstep` is false.
const TwinWireOptions* CleanLockstepWires(bool lockstep);

/// The devices block of a lockstep run: every device on its real driver, with the options the
/// scenario's block gives that driver, else the defaults (cameras: none here, the twin's).
drivers::DevicesConfig LockstepDevices(const drivers::DevicesConfig& given);

/// The devices for `scenario`: the simulated ones from `twin` (null only when no device is
/// simulated), the others opened on their ports. Throws as OpenRobot.
device::RobotDevices MakeDevices(const sim::Scenario& scenario, sim::SimRobot* twin);

/// The command log (command_log()) of every device that is a real serial driver, keyed as the
/// twin's serial lines (sim::kTwinLines: arm_left, arm_right, hand_left, hand_right, head,
/// laser_board; the laser and the LEDs share the board's one log) and in the encoding of the
/// twin's report (twin.json "commands"): VAL II lines as typed; SensorHand commands as the
/// lowercase hex of their frames; Biclops commands as {"axis", "opcode", "value"}
/// (pmd::CommandValue); laser board commands as the hex of their payload, "/", their code.
/// An entry the driver cannot confirm (drivers/serial/command_log.h) is {"unconfirmed": ENTRY}.
/// Simulated devices are left out.
nlohmann::json CommandLogs(const device::RobotDevices& devices);

}  // namespace hgrasp::app
