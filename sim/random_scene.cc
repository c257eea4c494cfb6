#include "sim/random_scene.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>

#include "common/geometry.h"
#include "sim/draw.h"

namespace hgrasp::sim {
namespace {

// Draws per box before the scene is drawn again, and scene attempts before one box fewer. With
// the default options a box is rejected in well under 1% of scenes; the limits only matter for
// options that leave (almost) no room.
constexpr int kDrawsPerBox = 1000;
constexpr int kSceneAttempts = 100;

using Footprint = std::array<Eigen::Vector2d, 4>;

void CheckOptions(const RandomSceneOptions& o) {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("RandomBoxScene: " + what);
  };
  const int colors = static_cast<int>(RandomScenePalette().size());
  if (o.min_boxes < 1 || o.max_boxes < o.min_boxes || o.max_boxes > colors) {
    fail("expected 1 <= min_boxes <= max_boxes <= " + std::to_string(colors) + ", got " +
         std::to_string(o.min_boxes) + ", " + std::to_string(o.max_boxes));
  }
  if (!(o.min_edge_m >= kMinObjectEdge && o.min_edge_m <= o.max_edge_m &&
        o.max_edge_m <= kMaxObjectEdge)) {
    fail("expected " + std::to_string(kMinObjectEdge) +
         " <= min_edge_m <= max_edge_m <= " + std::to_string(kMaxObjectEdge) + " m, got " +
         std::to_string(o.min_edge_m) + ", " + std::to_string(o.max_edge_m));
  }
  if (!(o.max_camera_noise >= 0.0)) {
    fail("expected max_camera_noise >= 0, got " + std::to_string(o.max_camera_noise));
  }
  if (!(o.min_gap_m >= 0.0)) fail("expected min_gap_m >= 0, got " + std::to_string(o.min_gap_m));
}

// Draws `count` boxes apart from each other; false when one cannot be placed.
bool PlaceBoxes(int count, const RandomSceneOptions& options, Draw* draw,
                std::vector<ObjectSpec>* boxes) {
  boxes->clear();
  std::vector<Footprint> footprints;
  for (int i = 0; i < count; ++i) {
    bool placed = false;
    for (int k = 0; k < kDrawsPerBox && !placed; ++k) {
      ObjectSpec o;
      for (int axis = 0; axis < 3; ++axis) {
        o.size_O[axis] = draw->Real(options.min_edge_m, options.max_edge_m);
      }
      o.yaw = draw->Real(-kPi, kPi);
      o.position_W.x() = draw->Real(kWorkspaceMinX, kWorkspaceMaxX);
      o.position_W.y() = draw->Real(kWorkspaceMinY, kWorkspaceMaxY);
      const Footprint f = ObjectFootprint(o);
      placed = FootprintOnTable(f);
      for (const Footprint& other : footprints) {
        // Separated: with min_gap_m = 0, overlapping footprints (distance 0) stay apart too.
        placed = placed && !FootprintsOverlap(f, other) &&
                 FootprintDistance(f, other) >= options.min_gap_m;
      }
      if (placed) {
        boxes->push_back(o);
        footprints.push_back(f);
      }
    }
    if (!placed) return false;
  }
  return true;
}

}  // namespace

const std::array<NamedColor, 10>& RandomScenePalette() {
  static const std::array<NamedColor, 10> kPalette = {{
      {"red", {0.85, 0.10, 0.10}},
      {"orange", {0.95, 0.50, 0.08}},
      {"yellow", {0.95, 0.85, 0.10}},
      {"green", {0.15, 0.70, 0.20}},
      {"cyan", {0.10, 0.75, 0.80}},
      {"blue", {0.15, 0.30, 0.85}},
      {"magenta", {0.80, 0.15, 0.75}},
      {"white", {0.92, 0.92, 0.90}},
      {"grey", {0.50, 0.50, 0.50}},
      {"black", {0.15, 0.15, 0.15}},
  }};
  return kPalette;
}

std::array<int, 10> DrawPaletteOrder(Draw* draw, int count) {
  std::array<int, 10> colors;
  for (int i = 0; i < 10; ++i) colors[i] = i;
  for (int i = 0; i < count; ++i) std::swap(colors[i], colors[draw->Int(i, 9)]);
  return colors;
}

bool PlaceWithFewerBoxes(int wanted, int min_boxes, int attempts,
                         const std::function<bool(int, std::vector<ObjectSpec>*)>& place,
                         std::vector<ObjectSpec>* boxes) {
  for (int count = wanted; count >= min_boxes; --count) {
    for (int attempt = 0; attempt < attempts; ++attempt) {
      if (place(count, boxes)) return true;
    }
  }
  return false;
}

Scenario RandomBoxScene(std::uint64_t seed, const RandomSceneOptions& options) {
  CheckOptions(options);
  Draw draw(seed);
  const std::array<NamedColor, 10>& palette = RandomScenePalette();

  const int wanted = draw.Int(options.min_boxes, options.max_boxes);
  const std::array<int, 10> colors = DrawPaletteOrder(&draw, wanted);
  std::vector<ObjectSpec> boxes;
  if (!PlaceWithFewerBoxes(
          wanted, options.min_boxes, kSceneAttempts,
          [&](int count, std::vector<ObjectSpec>* b) {
            return PlaceBoxes(count, options, &draw, b);
          },
          &boxes)) {
    throw std::runtime_error("RandomBoxScene: seed " + std::to_string(seed) + ": could not place " +
                             std::to_string(options.min_boxes) + " boxes " +
                             std::to_string(options.min_gap_m) + " m apart in the workspace");
  }

  Scenario s;
  s.name = "random_" + std::to_string(seed);
  s.seed = seed;
  s.camera_noise = draw.Real(0.0, options.max_camera_noise);
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    ObjectSpec& o = boxes[i];
    const NamedColor& c = palette[colors[i]];
    o.name = std::string(c.name) + "_box";
    o.shape = "box";
    o.color_rgb = c.rgb;
    o.mass = 0.2;
    o.specular = false;
    s.objects.push_back(std::move(o));
  }
  TaskSpec task;
  task.target_color = std::string(palette[colors[0]].name);
  task.lift_m = 0.05;
  s.task = task;
  return s;
}

std::vector<std::string> RandomSceneColorNames(const Scenario& scenario) {
  constexpr std::string_view kSuffix = "_box";
  std::vector<std::string> names;
  for (const ObjectSpec& o : scenario.objects) {
    const std::string_view n = o.name;
    bool known = false;
    if (n.size() > kSuffix.size() && n.substr(n.size() - kSuffix.size()) == kSuffix) {
      const std::string_view color = n.substr(0, n.size() - kSuffix.size());
      for (const NamedColor& c : RandomScenePalette()) known = known || c.name == color;
      if (known) names.emplace_back(color);
    }
    if (!known) {
      throw std::invalid_argument("RandomSceneColorNames: object '" + o.name +
                                  "' is not named <palette colour>_box");
    }
  }
  return names;
}

}  // namespace hgrasp::sim
