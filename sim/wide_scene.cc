#include "sim/wide_scene.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "common/geometry.h"
#include "common/paths.h"
#include "robot/head_kinematics.h"
#include "scan/scanner.h"  // scan::kLookHead: where the pipeline looks from (a constant only)
#include "sim/draw.h"
#include "sim/random_scene.h"

namespace hgrasp::sim {
namespace {

constexpr int kDrawsPerBox = 2000;
constexpr int kSceneAttempts = 200;
constexpr double kFovyDeg = 55.0;  // models/humanoid.xml: both cameras
constexpr int kWidth = 320, kHeight = 240;

using Footprint = std::array<Eigen::Vector2d, 4>;

// The two cameras' optical frames at the look pose, from the robot's model.
const std::array<Pose3, 2>& LookCameras() {
  static const std::array<Pose3, 2> cameras = [] {
    const robot::HeadKinematics head =
        robot::HeadKinematics::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
    return std::array<Pose3, 2>{head.X_WC(robot::HeadKinematics::kLeft, scan::kLookHead),
                                head.X_WC(robot::HeadKinematics::kRight, scan::kLookHead)};
  }();
  return cameras;
}

std::array<Eigen::Vector3d, 8> Corners(const ObjectSpec& box) {
  const Pose3 X_WO = box.X_WO();
  std::array<Eigen::Vector3d, 8> c;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d s((i & 1) ? 0.5 : -0.5, (i & 2) ? 0.5 : -0.5, (i & 4) ? 0.5 : -0.5);
    c[i] = X_WO * s.cwiseProduct(box.size_O);
  }
  return c;
}

// Whether the segment a-b passes through the box (slab test in the box's frame).
bool SegmentHitsBox(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const ObjectSpec& box) {
  const Pose3 X_OW = box.X_WO().inverse();
  const Eigen::Vector3d p = X_OW * a, d = X_OW * b - p;
  double t0 = 0.0, t1 = 1.0;
  for (int k = 0; k < 3; ++k) {
    const double h = box.size_O[k] / 2;
    if (std::abs(d[k]) < 1e-12) {
      if (std::abs(p[k]) > h) return false;
      continue;
    }
    double ta = (-h - p[k]) / d[k], tb = (h - p[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

// A palette colour perturbed in hue, saturation and value.
Eigen::Vector3d PerturbedColour(const NamedColor& c, const WideSceneOptions& o, Draw* draw) {
  Eigen::Vector3d hsv = RgbToHsv(c.rgb);
  if (c.name == "white" || c.name == "grey" || c.name == "black") {
    const double lo = c.name == "white" ? 0.82 : c.name == "grey" ? 0.40 : 0.08;
    const double hi = c.name == "white" ? 0.97 : c.name == "grey" ? 0.60 : 0.22;
    hsv = {draw->Real(0.0, 360.0), draw->Real(0.0, 0.06), draw->Real(lo, hi)};
  } else {
    hsv[0] = std::fmod(hsv[0] + draw->Real(-o.hue_deg, o.hue_deg) + 360.0, 360.0);
    hsv[1] = std::min(1.0, hsv[1] * draw->Real(0.75, 1.0));
    hsv[2] = std::min(1.0, hsv[2] * draw->Real(0.75, 1.05));
  }
  return HsvToRgb(hsv);
}

// One box's shape and place; `target`: its narrower horizontal edge fits the open hand.
ObjectSpec DrawBox(bool target, const WideSceneOptions& o, Draw* draw) {
  ObjectSpec b;
  for (int axis = 0; axis < 3; ++axis) b.size_O[axis] = draw->Real(o.min_edge_m, o.max_edge_m);
  if (draw->Unit() < o.square_chance) {
    b.size_O.y() = std::clamp(b.size_O.x() * draw->Real(0.97, 1.03), o.min_edge_m, o.max_edge_m);
  }
  if (target && std::min(b.size_O.x(), b.size_O.y()) > o.max_target_width_m) {
    const int axis = draw->Int(0, 1);
    b.size_O[axis] = draw->Real(o.min_edge_m, o.max_target_width_m);
  }
  b.yaw = draw->Real(-kPi, kPi);
  b.position_W = {draw->Real(kWorkspaceMinX, kWorkspaceMaxX),
                  draw->Real(kWorkspaceMinY, kWorkspaceMaxY)};
  return b;
}

// Whether `b` may join `placed`: on the table, apart, in view, its top and theirs seen past
// each other; `close`: within close_gap_m of one of them.
bool Fits(const ObjectSpec& b, const std::vector<ObjectSpec>& placed, bool close,
          const WideSceneOptions& o) {
  const Footprint f = ObjectFootprint(b);
  if (!FootprintOnTable(f) || !BoxInBothViews(b, o.view_margin_px)) return false;
  double nearest = std::numeric_limits<double>::infinity();
  for (const ObjectSpec& other : placed) {
    const Footprint g = ObjectFootprint(other);
    if (FootprintsOverlap(f, g)) return false;
    const double d = FootprintDistance(f, g);
    if (d < o.min_gap_m || !TopSeenPast(b, other) || !TopSeenPast(other, b)) return false;
    nearest = std::min(nearest, d);
  }
  return !close || nearest <= o.close_gap_m;
}

bool PlaceBoxes(int count, const WideSceneOptions& o, Draw* draw, std::vector<ObjectSpec>* boxes) {
  boxes->clear();
  for (int i = 0; i < count; ++i) {
    const bool close = i > 0 && draw->Unit() < o.close_chance;
    bool placed = false;
    for (int k = 0; k < kDrawsPerBox && !placed; ++k) {
      ObjectSpec b = DrawBox(i == 0, o, draw);
      placed = Fits(b, *boxes, close, o);
      if (placed) boxes->push_back(std::move(b));
    }
    if (!placed) return false;
  }
  return !o.target_graspable || o.target_graspable(*boxes);
}

void CheckOptions(const WideSceneOptions& o) {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("WideBoxScene: " + what);
  };
  if (o.min_boxes < 1 || o.max_boxes < o.min_boxes || o.max_boxes > 10) {
    fail("expected 1 <= min_boxes <= max_boxes <= 10");
  }
  if (!(o.min_edge_m >= kMinObjectEdge && o.min_edge_m <= o.max_target_width_m &&
        o.max_target_width_m <= o.max_edge_m && o.max_edge_m <= kMaxObjectEdge)) {
    fail(
        "expected kMinObjectEdge <= min_edge_m <= max_target_width_m <= max_edge_m <= "
        "kMaxObjectEdge");
  }
  if (!(o.min_gap_m >= 0 && o.close_gap_m >= o.min_gap_m)) {
    fail("expected 0 <= min_gap_m <= close_gap_m");
  }
  if (!(o.min_mass_kg >= kMinMass && o.min_mass_kg <= o.max_mass_kg && o.max_mass_kg <= kMaxMass)) {
    fail("expected kMinMass <= min_mass_kg <= max_mass_kg <= kMaxMass");
  }
  if (!(o.min_ambient >= 0 && o.min_ambient <= o.max_ambient && o.max_ambient <= 1)) {
    fail("expected 0 <= min_ambient <= max_ambient <= 1");
  }
  if (!(o.min_wall_x > kMinWallX && o.min_wall_x <= o.max_wall_x && o.max_wall_x <= kMaxWallX)) {
    fail("expected kMinWallX < min_wall_x <= max_wall_x <= kMaxWallX");
  }
  if (!(o.max_camera_noise >= 0 && o.hue_deg >= 0 && o.view_margin_px >= 0)) {
    fail("expected max_camera_noise, hue_deg and view_margin_px >= 0");
  }
}

// Another robot at the table's side, its stripe sweeping about the workspace's centre.
InterferenceSpec DrawInterference(Draw* draw) {
  InterferenceSpec s;
  const double side = draw->Unit() < 0.5 ? -1.0 : 1.0;
  s.origin_W = {draw->Real(0.1, 0.8), side * draw->Real(0.6, 0.9), draw->Real(0.4, 0.7)};
  const double half = DegToRad(draw->Real(15.0, 25.0));
  const double centre = DegToRad(draw->Real(-5.0, 5.0));
  s.sweep_min = centre - half;
  s.sweep_max = centre + half;
  s.period_s = draw->Real(1.0, 3.0);
  return s;
}

}  // namespace

Eigen::Vector3d RgbToHsv(const Eigen::Vector3d& rgb) {
  const double mx = rgb.maxCoeff(), mn = rgb.minCoeff(), c = mx - mn;
  double h = 0.0;
  if (c > 0) {
    if (mx == rgb.x()) {
      h = 60.0 * std::fmod((rgb.y() - rgb.z()) / c + 6.0, 6.0);
    } else if (mx == rgb.y()) {
      h = 60.0 * ((rgb.z() - rgb.x()) / c + 2.0);
    } else {
      h = 60.0 * ((rgb.x() - rgb.y()) / c + 4.0);
    }
  }
  return {h, mx > 0 ? c / mx : 0.0, mx};
}

Eigen::Vector3d HsvToRgb(const Eigen::Vector3d& hsv) {
  const double c = hsv[2] * hsv[1];
  const double hp = std::fmod(hsv[0], 360.0) / 60.0;
  const double x = c * (1.0 - std::abs(std::fmod(hp, 2.0) - 1.0));
  Eigen::Vector3d rgb;
  switch (static_cast<int>(hp)) {
    case 0:
      rgb = {c, x, 0};
      break;
    case 1:
      rgb = {x, c, 0};
      break;
    case 2:
      rgb = {0, c, x};
      break;
    case 3:
      rgb = {0, x, c};
      break;
    case 4:
      rgb = {x, 0, c};
      break;
    default:
      rgb = {c, 0, x};
      break;
  }
  return rgb + Eigen::Vector3d::Constant(hsv[2] - c);
}

bool BoxInBothViews(const ObjectSpec& box, double margin_px) {
  const double f = (kHeight / 2.0) / std::tan(DegToRad(kFovyDeg) / 2.0);
  for (const Pose3& X_WC : LookCameras()) {
    const Pose3 X_CW = X_WC.inverse();
    for (const Eigen::Vector3d& p_W : Corners(box)) {
      const Eigen::Vector3d p = X_CW * p_W;
      if (p.z() <= 0) return false;
      const double u = f * p.x() / p.z() + kWidth / 2.0, v = f * p.y() / p.z() + kHeight / 2.0;
      if (u < margin_px || u > kWidth - margin_px || v < margin_px || v > kHeight - margin_px) {
        return false;
      }
    }
  }
  return true;
}

bool TopSeenPast(const ObjectSpec& box, const ObjectSpec& other) {
  const Eigen::Vector3d top(box.position_W.x(), box.position_W.y(), box.size_O.z() + 1e-3);
  for (const Pose3& X_WC : LookCameras()) {
    if (SegmentHitsBox(X_WC.translation(), top, other)) return false;
  }
  return true;
}

Scenario WideBoxScene(std::uint64_t seed, const WideSceneOptions& o) {
  CheckOptions(o);
  Draw draw(seed);
  const std::array<NamedColor, 10>& palette = RandomScenePalette();
  const int wanted = draw.Int(o.min_boxes, o.max_boxes);
  const std::array<int, 10> colors = DrawPaletteOrder(&draw, wanted);
  std::vector<ObjectSpec> boxes;
  if (!PlaceWithFewerBoxes(
          wanted, o.min_boxes, kSceneAttempts,
          [&](int count, std::vector<ObjectSpec>* b) { return PlaceBoxes(count, o, &draw, b); },
          &boxes)) {
    throw std::runtime_error("WideBoxScene: seed " + std::to_string(seed) +
                             ": could not place the boxes");
  }

  Scenario s;
  s.name = "wide_" + std::to_string(seed);
  s.seed = seed;
  s.camera_noise = draw.Real(0.0, o.max_camera_noise);
  s.ambient = draw.Real(o.min_ambient, o.max_ambient);
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    ObjectSpec& b = boxes[i];
    const NamedColor& c = palette[colors[i]];
    b.name = std::string(c.name) + "_box";
    b.color_name = std::string(c.name);
    b.color_rgb = PerturbedColour(c, o, &draw);
    b.mass = draw.Real(o.min_mass_kg, o.max_mass_kg);
    b.specular = draw.Unit() < o.specular_chance;
    s.objects.push_back(std::move(b));
  }
  if (draw.Unit() < o.interference_chance) s.interference.push_back(DrawInterference(&draw));
  if (draw.Unit() < o.wall_chance) s.wall_x = draw.Real(o.min_wall_x, o.max_wall_x);
  TaskSpec task;
  task.target_color = std::string(palette[colors[0]].name);
  task.lift_m = 0.05;
  s.task = task;
  return s;
}

}  // namespace hgrasp::sim
