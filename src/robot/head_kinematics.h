#pragma once
/// @file Head kinematics from models/humanoid.urdf: where the cameras and the laser are for given
/// head joints.
///
/// Frames (DESIGN.md rule 4): W world (the URDF root "world"), H = the URDF link
/// "camera_bracket", the head platform that carries both cameras and the laser; CL, CR the left
/// and right camera optical frames "camera_left_optical", "camera_right_optical" (x right, y
/// down, z forward); S the URDF link "laser_plane", whose x-z plane is the light plane.
/// H moves with pan and tilt only; the optical frames move in H with verge only.

#include <string>
#include <utility>

#include "common/geometry.h"
#include "device/head.h"
#include "robot/kinematic_tree.h"

namespace hgrasp::robot {

class HeadKinematics {
 public:
  static constexpr int kLeft = 0;   ///< camera index of the left camera (CL)
  static constexpr int kRight = 1;  ///< camera index of the right camera (CR)

  /// Loads the head from a URDF file (normally ResolveDataPath("models/humanoid.urdf")).
  /// @throws hgrasp::InputError naming the file when it cannot be read, is not valid URDF, or
  ///         lacks one of the links and joints named above and the joints head_pan, head_tilt,
  ///         head_verge_left, head_verge_right (a mimic of head_verge_left) and laser.
  static HeadKinematics FromUrdfFile(const std::string& path);

  /// X_WH: the camera bracket in W.
  Pose3 X_WH(const device::HeadJoints& q) const;

  /// X_WC: optical frame of `camera` (kLeft or kRight) in W.
  Pose3 X_WC(int camera, const device::HeadJoints& q) const;

  /// X_HC: optical frame of `camera` (kLeft or kRight) in H; it depends on the verge angle only.
  Pose3 X_HC(int camera, double verge) const;

  /// X_WS: the URDF's laser_plane frame in W with the laser joint at `laser_rad`. Ground truth of
  /// the model, for tests and the simulator only: the pipeline gets the light plane from its
  /// calibration (robot/calibration.h).
  Pose3 X_WS(const device::HeadJoints& q, double laser_rad) const;

  /// The kinematic tree the head was read from.
  const KinematicTree& tree() const { return tree_; }

 private:
  explicit HeadKinematics(KinematicTree tree) : tree_(std::move(tree)) {}
  static const std::string& OpticalLink(int camera);

  KinematicTree tree_;
};

}  // namespace hgrasp::robot
