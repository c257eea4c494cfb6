#pragma once
/// @file The composition root's choice of devices (DESIGN.md rule 2): every device comes from the
/// simulated robot unless the scenario's `devices` block names a real driver for it, in which
/// case that driver is opened on its port with its options (drivers/config/device_config.h).
/// The simulated robot, its MuJoCo world and its EGL context are built only when some device
/// is simulated: on the real robot nothing of the twin exists. The same binary drives the twin,
/// the emulators and the robot.

#include <memory>
#include <string>

#include "app/safe_stop.h"
#include "device/robot_devices.h"
#include "sim/scenario.h"
#include "sim/sim_devices.h"

namespace hgrasp::app {

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
  device::RobotDevices devices;
  bool all_simulated = false;

  /// The twin when every device is simulated: only then does its ground truth describe what
  /// the devices saw (and may go into reports). Else nullptr.
  sim::SimRobot* truth() const { return all_simulated ? twin.get() : nullptr; }

  /// app::LeaveSafe on the devices (safe_stop.h); logs what did not take it.
  SafeStopReport LeaveSafe();

 private:
  bool left_safe_ = false;
};

/// The devices of `scenario`, opened: the twin built only when some device is simulated.
/// Throws hgrasp::InputError naming the field (devices.KEY.port, ...) and the system's reason
/// when a port or pipeline cannot be opened.
Robot OpenRobot(const sim::Scenario& scenario);

/// The devices for `scenario`: the simulated ones from `twin` (null only when no device is
/// simulated), the others opened on their ports. Throws as OpenRobot.
device::RobotDevices MakeDevices(const sim::Scenario& scenario, sim::SimRobot* twin);

}  // namespace hgrasp::app
