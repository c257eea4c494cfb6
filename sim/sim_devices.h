#pragma once
/// @file Simulated implementations of every device of the seam (src/device/), backed by one
/// World. Time is lockstep: commands set targets at once, and each StereoCamera::Grab advances
/// simulated time by one frame period (40 ms) and renders the exposure (GrabWithoutImages
/// advances it without rendering).

#include <memory>
#include <optional>

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

/// Pose X_WE of arm `side`'s gripper frame with the arm at joint angles `q` (the rest of the
/// robot as it is now), from the simulator's nominal model (World::nominal_model): what the
/// simulated Puma controller knows, not where the arm truly is.
Pose3 ArmForwardKinematics(const World& world, device::Side side, const device::Joint6& q);

/// Joint angles that put arm `side`'s gripper frame at X_WE, found by damped least squares from
/// `q_start` (a local solution, as the Puma controller's tool moves are); nullopt when it does
/// not converge to 0.1 um / 1 urad or leaves the joint ranges.
std::optional<device::Joint6> ArmInverseKinematics(const World& world, device::Side side,
                                                   const Pose3& X_WE,
                                                   const device::Joint6& q_start);

}  // namespace hgrasp::sim
