#pragma once
/// @file Simulator ground truth for reports and tests (never read by the pipeline).

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "sim/stereo_rig.h"
#include "sim/world.h"

namespace hgrasp::sim {

/// JSON of a pose: {"p": [x, y, z], "R": [[...], [...], [...]]} (row-major rotation).
nlohmann::json PoseJson(const Pose3& X);

/// Ground truth now: objects (centre pose, size, colour), head joints, both cameras (optical
/// frame pose X_WC and intrinsics), and the laser's light plane in W for each encoder count in
/// `encoder_counts` with the head where it is now: {"count", "n_W", "d"} meaning n.p + d = 0.
nlohmann::json TruthJson(const World& world, const StereoRig& rig,
                         const std::vector<std::int32_t>& encoder_counts);

/// Distance (m) from p_W to the nearest true surface of the world: the table (a box, x
/// kTableMinX..kTableMaxX, y kTableMinY..kTableMaxY, z -0.04..0, see sim/scenario.h), the wall if
/// the scenario has one (the box the world builds: x wall_x..wall_x + 0.02, y -1..1, z 0..1; its
/// face x = wall_x faces the robot), and every scenario object (a box of size spec.size_O at its
/// current pose world.BodyPose(body)). The robot's own geometry is not included. Exact unsigned
/// distance to each box's surface: from inside a box, the distance to its nearest face.
double DistanceToTrueSurface(const World& world, const Eigen::Vector3d& p_W);

/// Unsigned distance (m) from p_W to the surface of the box of full edge lengths `size_O`
/// centred at X_WO; inside the box, the distance to the nearest face.
double DistanceToBoxSurface(const Pose3& X_WO, const Eigen::Vector3d& size_O,
                            const Eigen::Vector3d& p_W);

/// How far a calibrated light plane lies from the simulator's, over encoder counts.
struct LaserPlaneError {
  double worst_deg = 0;  ///< largest angle between the normals
  double worst_mm = 0;   ///< largest distance, at points of the true plane near the workspace
};

/// Compares `planes_W(count)` (a calibration's plane in W) with the true plane for every 10th
/// count in [lo, hi]. The distance is measured at the true plane's points nearest to five
/// workspace points (the middle and the corners of DESIGN.md's workspace, 0-0.15 m high).
LaserPlaneError CompareLaserPlanes(const StereoRig& rig,
                                   const std::function<Plane(std::int32_t)>& planes_W,
                                   std::int32_t lo, std::int32_t hi);

}  // namespace hgrasp::sim
