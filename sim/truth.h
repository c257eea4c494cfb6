#pragma once
/// @file Simulator ground truth for reports and tests (never read by the pipeline).

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "device/status.h"
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

/// Codes of TrueFaceLabels: no true surface, the table top, the wall.
constexpr int kTruthNone = -1, kTruthTable = 0, kTruthWall = 1;

/// Code of face `face` of scenario object `object_index` (index into world.objects()):
/// 2 + 6 * object_index + face, with face 0 +x, 1 -x, 2 +y, 3 -y, 4 +z (the top), 5 -z (the
/// bottom), in the object's own frame O.
inline int TruthFaceCode(int object_index, int face) { return 2 + 6 * object_index + face; }

/// The face (0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z of O) of the box of full edge lengths `size_O`
/// centred at X_WO whose rectangle lies nearest to p_W, inside the box too. Beyond an edge or a
/// corner several faces are equally near: the one whose plane p_W lies farthest beyond is taken
/// (exact ties go to the lower face number).
int NearestBoxFace(const Pose3& X_WO, const Eigen::Vector3d& size_O, const Eigen::Vector3d& p_W);

/// The true surface under each point p_W[i] (W, m), from the simulator's label image of camera
/// `camera` (kLeft or kRight) as rig->View(camera) renders it now: the point is projected with
/// that view's pose X_WC and intrinsics, and the geom labelled at the nearest pixel says what the
/// camera sees there:
///  - a scenario object (index i in world.objects()): TruthFaceCode(i, face), the face of its box
///    (at world.BodyPose) nearest to the point (NearestBoxFace);
///  - the table: kTruthTable; the wall: kTruthWall;
///  - the robot's own geoms, the background, or a point outside the image or behind the camera:
///    kTruthNone.
/// A point farther than tol_m (m) from that geom's surface (DistanceToBoxSurface; the table and
/// wall as in DistanceToTrueSurface) gets kTruthNone: it does not lie on what the camera sees
/// there (an occlusion edge, a surface hidden behind another, or a bad range). So does a point
/// whose nearest face turns away from the camera (outward normal pointing away from the optical
/// centre): the label image shows the same box's front there, not that face.
std::vector<int> TrueFaceLabels(const World& world, StereoRig* rig, int camera,
                                const std::vector<Eigen::Vector3d>& p_W, double tol_m = 0.005);

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

/// The true W seen from the W the pipeline believes in: X_WtrueWbelieved = X_WCL(true) *
/// X_WCL(believed)^-1. The pipeline sees the world through its left camera, whose pose it
/// believes to be X_WCL_believed (head kinematics at the frame's joints); with the head mounted
/// as modelled this is the identity, with WorldOptions::head_mount_error it is that error seen
/// from W.
Pose3 TrueFromBelievedWorld(const World& world, const Pose3& X_WCL_believed);

/// How far the true gripper frame E of arm `side` lies from X_WE_believed (a pose the pipeline
/// holds in its believed W, e.g. the planned grasp), compared in the true W.
struct PoseError {
  double translation_m = 0.0;
  double rotation_rad = 0.0;
};
PoseError GripperPoseError(const World& world, device::Side side, const Pose3& X_WCL_believed,
                           const Pose3& X_WE_believed);

}  // namespace hgrasp::sim
