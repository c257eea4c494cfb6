#pragma once
/// @file The composition root's choice of devices (DESIGN.md rule 2): every device comes from the
/// simulated robot unless the scenario's `devices` block names a real driver for it, in which
/// case that driver is opened on its port with its options (drivers/config/device_config.h).
/// The simulated robot, its MuJoCo world and its EGL context are built only when some device
/// is simulated: on the real robot nothing of the twin exists. The same binary drives the twin,
/// the emulators and the robot.

#include <memory>
#include <string>

#include "device/robot_devices.h"
#include "sim/scenario.h"
#include "sim/sim_devices.h"

namespace hgrasp::app {

/// The robot a command works with.
struct Robot {
  /// The simulated robot; null when every device is real.
  std::unique_ptr<sim::SimRobot> twin;
  device::RobotDevices devices;

  /// The twin when every device is simulated: only then does its ground truth describe what
  /// the devices saw (and may go into reports). Else nullptr.
  sim::SimRobot* truth() const { return all_simulated ? twin.get() : nullptr; }
  bool all_simulated = false;
};

/// The devices of `scenario`, opened: the twin built only when some device is simulated.
/// Throws hgrasp::InputError naming the field (devices.KEY.port, ...) and the system's reason
/// when a port or pipeline cannot be opened.
Robot OpenRobot(const sim::Scenario& scenario);

/// The devices for `scenario`: the simulated ones from `twin` (null only when no device is
/// simulated), the others opened on their ports. Throws as OpenRobot.
device::RobotDevices MakeDevices(const sim::Scenario& scenario, sim::SimRobot* twin);

}  // namespace hgrasp::app
