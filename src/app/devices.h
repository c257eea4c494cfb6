#pragma once
/// @file The composition root's choice of devices (DESIGN.md rule 2): every device comes from the
/// simulated robot unless the scenario's `devices` block names a real driver for it, in which
/// case that driver is opened on its port. The same binary drives the twin, the emulators and
/// the robot.

#include <string>

#include "device/robot_devices.h"
#include "sim/scenario.h"
#include "sim/sim_devices.h"

namespace hgrasp::app {

/// Whether every device of the scenario is simulated (then the simulator's ground truth
/// describes what the devices saw and may go into reports).
bool AllSimulated(const sim::Scenario& scenario);

/// The devices for `scenario`: the simulated ones from `robot`, the others opened on their
/// ports. Throws hgrasp::InputError naming the field (devices.KEY.port, ...) and the system's
/// reason when a port or pipeline cannot be opened.
device::RobotDevices MakeDevices(const sim::Scenario& scenario, sim::SimRobot* robot);

}  // namespace hgrasp::app
