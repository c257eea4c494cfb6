#pragma once
// One scan of a scenario by the simulated robot, as `hgrasp scan` takes it, for tests that check
// later stages against the simulator's ground truth.

#include "common/paths.h"
#include "robot/calibration.h"
#include "robot/head_kinematics.h"
#include "scan/scanner.h"
#include "sim/sim_devices.h"

namespace hgrasp::scan::testing {

/// Scans with `robot` (which must not have given its devices away yet), with the shipped
/// calibration of the simulated robot. The head stays where the scan left it.
inline RangeImage ScanInSim(sim::SimRobot* robot) {
  auto dev = robot->TakeDevices();
  Scanner scanner(robot::HeadKinematics::FromUrdfFile(ResolveDataPath("models/humanoid.urdf")),
                  robot::LoadStereoIntrinsics(ResolveDataPath("calibration/sim/cameras.yaml")),
                  robot::LoadLaserCalibration(ResolveDataPath("calibration/sim/laser.yaml")));
  return scanner.Scan(dev, {}).range;
}

}  // namespace hgrasp::scan::testing
