#pragma once
/// @file The wide box scenes (`hgrasp generate --family wide_boxes`): scenes drawn more widely
/// than RandomBoxScene, to measure perception on scenes nobody tuned it on (issue 37). Every draw
/// comes from the seed (DESIGN.md rule 6).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sim/scenario.h"

namespace hgrasp::sim {

/// What the wide family draws, each uniform unless said otherwise.
struct WideSceneOptions {
  int min_boxes = 1, max_boxes = 3;
  double min_edge_m = 0.04, max_edge_m = 0.15;  ///< every edge
  /// The target's narrower horizontal edge: at most the open hand's span less its clearance
  /// on each side (grasp::HandGeometry: 0.10 m open, 0.01 m clearance) and 5 mm for the scan's
  /// error in the box's width.
  double max_target_width_m = 0.075;
  /// Chance that a box's footprint is near-square (its y edge within 3 % of its x edge).
  double square_chance = 0.25;
  double min_gap_m = 0.02;    ///< smallest footprint distance between two boxes
  double close_gap_m = 0.03;  ///< a "close" box lies min_gap_m..close_gap_m from another
  double close_chance = 0.5;  ///< chance that each box after the first is drawn close to one
  double min_mass_kg = 0.1, max_mass_kg = 0.45;
  double min_ambient = 0.25, max_ambient = 0.5;
  double max_camera_noise = 3.0;
  double specular_chance = 0.15;     ///< per box: its surface mirrors the laser
  double interference_chance = 0.3;  ///< per scene: another robot's stripe sweeps the table
  double wall_chance = 0.25;         ///< per scene: a wall behind the table
  double min_wall_x = 0.55, max_wall_x = 0.9;
  /// Colours: hue within +-hue_deg of the palette colour's, saturation and value scaled by
  /// [0.75, 1] and [0.75, 1.05] (chromatic colours); white, grey and black keep a tint of at
  /// most 0.06 saturation and values of 0.82-0.97, 0.40-0.60 and 0.08-0.22.
  double hue_deg = 8.0;
  /// Each box is in both cameras' images from the look pose (scan::kLookHead) with this margin
  /// (pixels), and the middle of its top is seen by both cameras past every other box.
  double view_margin_px = 8.0;
  /// When set, a drawn scene is kept only if this accepts its boxes (the target first): e.g. the
  /// grasp planner on the true boxes (`hgrasp generate` sets it so that the target is one the
  /// robot can grasp; the twin alone knows no planner).
  std::function<bool(const std::vector<ObjectSpec>& boxes)> target_graspable;
};

/// A scenario of the wide family, every draw from `seed`:
///  - 1-3 boxes, each in a different palette colour (drawn without replacement) perturbed in
///    hue, saturation and value as WideSceneOptions says; the colour's palette name is written
///    as the object's color_name (the truth the colour namer is scored against) and in its name
///    "<colour>_box";
///  - the first box is the target (task {color: its colour name}, lift 0.05 m): its narrower
///    horizontal edge is at most max_target_width_m;
///  - per box: edges, yaw in [-180, 180) deg, centre in the workspace (kWorkspaceMinX..MaxY of
///    random_scene.h), near-square by chance, at least min_gap_m from every other box and, by
///    chance, at most close_gap_m from one; mass, specular by chance; redrawn until it lies on
///    the table, apart, in both cameras' view and its top seen past the others (whole scene
///    drawn again when a box cannot be placed, or when target_graspable refuses the boxes);
///  - ambient light, camera noise, by chance one interfering stripe (a robot at the table's
///    side, sweeping +-15-25 deg about the workspace's centre) and a wall.
/// Robot errors: the defaults (on). The result passes ParseScenario's checks.
/// Throws std::invalid_argument for options out of range, std::runtime_error when no scene can
/// be placed.
Scenario WideBoxScene(std::uint64_t seed, const WideSceneOptions& options = {});

/// Whether every corner of `box` projects into both cameras' images (320 x 240, fovy 55 deg, the
/// twin's model) at least margin_px inside, with the head at scan::kLookHead's joints, computed
/// from the robot's URDF (models/humanoid.urdf).
bool BoxInBothViews(const ObjectSpec& box, double margin_px);

/// Whether the middle of `box`'s top is seen by both cameras at the look pose past `other` (the
/// straight line from each camera's centre to it misses the other box).
bool TopSeenPast(const ObjectSpec& box, const ObjectSpec& other);

/// RGB (0-1) to hue (deg, 0-360), saturation and value (0-1), and back.
Eigen::Vector3d RgbToHsv(const Eigen::Vector3d& rgb);
Eigen::Vector3d HsvToRgb(const Eigen::Vector3d& hsv);

}  // namespace hgrasp::sim
