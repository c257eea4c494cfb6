#pragma once
// One scan of a scenario by the simulated robot, as `hgrasp scan` takes it, for tests that check
// later stages against the simulator's ground truth.

#include "common/paths.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/scanner.h"
#include "sim/sim_devices.h"

namespace hgrasp::scan::testing {

/// Scans through `dev` (the simulated robot's devices), with the shipped calibration of the
/// simulated robot. The head stays where the scan left it.
inline RangeImage ScanWith(device::RobotDevices& dev) {
  Scanner scanner(robot::HeadKinematics::FromUrdfFile(ResolveDataPath("models/humanoid.urdf")),
                  robot::LoadStereoIntrinsics(ResolveDataPath("calibration/sim/cameras.yaml")),
                  robot::LoadLaserCalibration(ResolveDataPath("calibration/sim/laser.yaml")));
  return scanner.Scan(dev, {}).range;
}

/// As ScanWith, taking `robot`'s devices (it must not have given them away yet).
inline RangeImage ScanInSim(sim::SimRobot* robot) {
  device::RobotDevices dev = robot->TakeDevices();
  return ScanWith(dev);
}

}  // namespace hgrasp::scan::testing
