#pragma once
/// @file Seeded random box scenes for accuracy regression tests: a few boxes of random size, yaw
/// and place in DESIGN.md's workspace, apart from each other, each in a different named colour.
/// Every draw comes from the seed (DESIGN.md rule 6).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/scenario.h"

namespace hgrasp::sim {

/// DESIGN.md's workspace (m in W): where random scenes put the box centres.
constexpr double kWorkspaceMinX = 0.20, kWorkspaceMaxX = 0.40;
constexpr double kWorkspaceMinY = -0.15, kWorkspaceMaxY = 0.15;

/// A colour of the random scenes' palette: its name (one of kColorNames) and albedo.
struct NamedColor {
  std::string_view name;
  Eigen::Vector3d rgb;  ///< RGB, each 0-1
};

/// The ten colours random scenes paint boxes with, in kColorNames' order. The model library's
/// colour namer is tuned to these values: change them together.
const std::array<NamedColor, 10>& RandomScenePalette();

struct RandomSceneOptions {
  int min_boxes = 1;              ///< >= 1
  int max_boxes = 3;              ///< >= min_boxes, <= 10 (one palette colour each)
  double min_edge_m = 0.04;       ///< each edge uniform in [min_edge_m, max_edge_m] (m)
  double max_edge_m = 0.15;       ///< within [kMinObjectEdge, kMaxObjectEdge]
  double max_camera_noise = 2.0;  ///< camera_noise drawn uniformly in [0, this] (grey levels)
  double min_gap_m = 0.03;        ///< smallest distance between two boxes' footprints (m), >= 0
};

/// A scenario of min_boxes..max_boxes boxes resting on the table, every draw from `seed`:
///  - the box count uniform in [min_boxes, max_boxes];
///  - per box: edges uniform in [min_edge_m, max_edge_m], yaw uniform in [-180, 180) deg, centre
///    uniform in the workspace (kWorkspaceMinX..MaxX, kWorkspaceMinY..MaxY), redrawn until its
///    footprint is at least min_gap_m from every earlier box's (rejection sampling); when a box
///    cannot be placed after many draws the whole scene is drawn again, and after many such
///    attempts with one box fewer (never fewer than min_boxes: std::runtime_error then);
///  - colours: distinct, drawn from RandomScenePalette() without replacement;
///  - camera_noise uniform in [0, max_camera_noise].
/// Fixed: name "random_<seed>", seed = `seed`, objects "<colour>_box" (the colour's palette name),
/// specular false, mass 0.2 kg, default lighting, no wall, no interference, task target
/// {color: the first box's colour} with lift 0.05 m, path empty. The result passes the checks of
/// ParseScenario (footprints on the table and apart, unique names).
///
/// The draws use std::mt19937_64 (fully specified by the standard) and this file's own
/// uniform-distribution code, not std::uniform_*_distribution (whose algorithms the standard
/// leaves to the library), so a seed gives the same scene with every standard library.
///
/// Throws std::invalid_argument when `options` are out of the ranges above.
Scenario RandomBoxScene(std::uint64_t seed, const RandomSceneOptions& options = {});

class Draw;

/// Colours for `count` boxes without replacement: indices into RandomScenePalette(), the first
/// `count` entries of a Fisher-Yates shuffle drawn from `draw` (count <= 10).
std::array<int, 10> DrawPaletteOrder(Draw* draw, int count);

/// Places a scene's boxes with `place(count, &boxes)` (true when all `count` fit), `attempts`
/// times for `wanted` boxes, then as often for one box fewer, down to min_boxes; false when no
/// attempt placed them.
bool PlaceWithFewerBoxes(int wanted, int min_boxes, int attempts,
                         const std::function<bool(int, std::vector<ObjectSpec>*)>& place,
                         std::vector<ObjectSpec>* boxes);

/// The colour name a random scene gave each object (same order as scenario.objects): the name
/// before "_box". Throws std::invalid_argument when an object's name is not "<palette name>_box".
std::vector<std::string> RandomSceneColorNames(const Scenario& scenario);

}  // namespace hgrasp::sim
