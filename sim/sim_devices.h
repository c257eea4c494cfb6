#pragma once
/// @file Simulated implementations of every device of the seam (src/device/), backed by one
/// World. Time is lockstep: commands set targets at once, and each StereoCamera::Grab advances
/// simulated time by one frame period (40 ms) and renders the exposure.

#include <memory>

#include "device/robot_devices.h"
#include "sim/stereo_rig.h"
#include "sim/world.h"

namespace hgrasp::sim {

/// The simulated robot: the world, its stereo rig and the devices over them.
class SimRobot {
 public:
  explicit SimRobot(Scenario scenario, const WorldOptions& options = {});

  World& world() { return *world_; }
  StereoRig& rig() { return *rig_; }
  /// The devices, to be moved into the pipeline; they refer to this SimRobot, which must
  /// outlive them.
  device::RobotDevices TakeDevices();

 private:
  std::unique_ptr<World> world_;
  std::unique_ptr<StereoRig> rig_;
};

/// The individual devices (exposed for tests).
device::RobotDevices MakeSimDevices(World* world, StereoRig* rig);

}  // namespace hgrasp::sim
