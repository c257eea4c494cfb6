#include "sim/scenario.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "common/error.h"
#include "common/yaml_file.h"
#include "common/yaml_reader.h"
#include "common/yaml_util.h"

namespace hgrasp::sim {

Pose3 ObjectSpec::X_WO() const {
  Pose3 X_WO = Pose3::Identity();
  X_WO.linear() = RotZ(yaw);
  X_WO.translation() = Eigen::Vector3d(position_W.x(), position_W.y(), size_O.z() / 2.0);
  return X_WO;
}

Pose3 BoardSpec::X_WB() const {
  Pose3 X_WB = Pose3::Identity();
  X_WB.linear() = RotZ(yaw) * Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitY()).toRotationMatrix();
  X_WB.translation() = position_W;
  return X_WB;
}

Eigen::Vector3d BoardSpec::CornerB(int i, int j) const {
  return Eigen::Vector3d((i - 0.5 * (cols - 1)) * square_m, (j - 0.5 * (rows - 1)) * square_m, 0);
}

Eigen::Vector2d BoardSpec::HalfExtent() const {
  // (cols + 1) squares and a border of one square each side.
  return Eigen::Vector2d(0.5 * (cols + 3) * square_m, 0.5 * (rows + 3) * square_m);
}

double InterferenceSpec::AngleAt(double t_s) const {
  double phase = std::fmod(t_s, period_s) / period_s;  // in (-1, 1)
  if (phase < 0.0) phase += 1.0;
  const double u = phase < 0.5 ? 2.0 * phase : 2.0 * (1.0 - phase);  // 0 -> 1 -> 0
  return sweep_min + (sweep_max - sweep_min) * u;
}

namespace {

// ---------------------------------------------------------------------------------------------
// Footprints on the table.

using Footprint = std::array<Eigen::Vector2d, 4>;

std::string Fixed(double v, int digits = 3) {
  if (std::abs(v) < 0.5 * std::pow(10.0, -digits)) v = 0.0;  // no "-0.000"
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << v;
  return s.str();
}

// Strict scalars and message helpers: common/yaml_util.h.
using yaml::Index;
using yaml::IsQuoted;
using yaml::Join;
using yaml::Keys;
using yaml::OneOf;
using yaml::ParseBool;
using yaml::ParseNumber;
using yaml::ParseUnsigned;
using yaml::QuoteHint;
using yaml::Render;

bool IsIdentifier(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-' || c == '.';
    if (!ok) return false;
  }
  return true;
}

using yaml::Entries;

// An object's nodes needed again for the checks across objects. Assigned once each: assigning
// to a YAML::Node that already refers to a node would overwrite that node, not rebind.
struct ObjectNodes {
  YAML::Node name, position;
};

// ---------------------------------------------------------------------------------------------
// The parser: every check names "FILE:LINE", the field path, the value and what was expected.

class Parser : public yaml::Reader {
 public:
  using yaml::Reader::Reader;

  Scenario Parse(const std::string& text);

 private:
  std::string Name(const YAML::Node& n, const std::string& field) const {
    const std::string s = Text(n, field, "a name of letters, digits, '_', '-' or '.'");
    if (!IsIdentifier(s)) Fail(n, field, "a name of letters, digits, '_', '-' or '.'");
    return s;
  }

  ObjectSpec ParseObject(const YAML::Node& n, const std::string& field, ObjectNodes* nodes) const;
  InterferenceSpec ParseInterference(const YAML::Node& n, const std::string& field) const;
  TaskSpec ParseTask(const YAML::Node& n, const std::string& field, YAML::Node* name_node) const;
  BoardSpec ParseBoard(const YAML::Node& n, const std::string& field) const;
  void CheckBoard(const Scenario& s, std::size_t i, const YAML::Node& n) const;
  RobotErrorsSpec ParseRobotErrors(const YAML::Node& n, const std::string& field) const;
  void CheckAcrossObjects(const Scenario& s, const std::vector<ObjectNodes>& nodes) const;
};

ObjectSpec Parser::ParseObject(const YAML::Node& n, const std::string& field,
                               ObjectNodes* nodes) const {
  const Entries e = MapOf(
      n, field,
      {"name", "shape", "size", "position", "yaw_deg", "color", "color_name", "mass", "specular"},
      "an object: a map with name, shape, size, position, color and optionally yaw_deg, "
      "color_name, mass, specular");
  ObjectSpec o;
  nodes->name = Require(e, n, field, "name", "an object name");
  o.name = Name(nodes->name, Join(field, "name"));

  const YAML::Node& shape = Require(e, n, field, "shape", "a shape: box");
  o.shape = Text(shape, Join(field, "shape"), "box (the only shape so far)");
  if (o.shape != "box") Fail(shape, Join(field, "shape"), "box (the only shape so far)");

  const std::string size_field = Join(field, "size");
  const std::string size_expected = "three positive edge lengths in m";
  const YAML::Node& size = Require(e, n, field, "size", size_expected + ", as [x, y, z]");
  o.size_O = Numbers(size, size_field, 3, size_expected + ", as [x, y, z]");
  if ((o.size_O.array() <= 0.0).any()) Fail(size, size_field, size_expected);
  if ((o.size_O.array() < kMinObjectEdge).any() || (o.size_O.array() > kMaxObjectEdge).any()) {
    Fail(size, size_field,
         "edge lengths between " + Fixed(kMinObjectEdge, 2) + " and " + Fixed(kMaxObjectEdge, 2) +
             " m");
  }

  const std::string pos_expected = "the box centre's x, y in W in m, as [x, y]";
  nodes->position = Require(e, n, field, "position", pos_expected);
  o.position_W = Numbers(nodes->position, Join(field, "position"), 2, pos_expected);

  if (const YAML::Node* yaw = Find(e, "yaw_deg")) {
    const std::string yaw_expected =
        "a yaw about W z of -" + Fixed(kMaxYawDeg, 0) + " to " + Fixed(kMaxYawDeg, 0) + " deg";
    const double deg = Number(*yaw, Join(field, "yaw_deg"), yaw_expected);
    if (std::abs(deg) > kMaxYawDeg) Fail(*yaw, Join(field, "yaw_deg"), yaw_expected);
    o.yaw = DegToRad(deg);
  }

  const std::string color_field = Join(field, "color");
  const std::string color_expected = "an RGB colour, three numbers 0-1, as [r, g, b]";
  const YAML::Node& color = Require(e, n, field, "color", color_expected);
  o.color_rgb = Numbers(color, color_field, 3, color_expected);
  if ((o.color_rgb.array() < 0.0).any() || (o.color_rgb.array() > 1.0).any()) {
    Fail(color, color_field, color_expected);
  }

  if (const YAML::Node* name = Find(e, "color_name")) {
    const std::string expected =
        "the colour's name, " + OneOf(Keys(kColorNames.begin(), kColorNames.end()));
    o.color_name = Text(*name, Join(field, "color_name"), expected);
    bool known = false;
    for (std::string_view c : kColorNames) known = known || o.color_name == c;
    if (!known) Fail(*name, Join(field, "color_name"), expected);
  }

  if (const YAML::Node* mass = Find(e, "mass")) {
    const std::string mass_expected = "a mass of " + Fixed(kMinMass, 2) + "-" + Fixed(kMaxMass, 2) +
                                      " kg (the Puma 260 with its hand lifts about 0.5 kg)";
    o.mass = Number(*mass, Join(field, "mass"), mass_expected);
    if (o.mass < kMinMass || o.mass > kMaxMass) Fail(*mass, Join(field, "mass"), mass_expected);
  }

  if (const YAML::Node* specular = Find(e, "specular")) {
    const std::optional<bool> b = ParseBool(*specular);
    if (!b) Fail(*specular, Join(field, "specular"), "true or false" + QuoteHint(*specular));
    o.specular = *b;
  }
  return o;
}

InterferenceSpec Parser::ParseInterference(const YAML::Node& n, const std::string& field) const {
  const Entries e = MapOf(n, field, {"origin", "sweep_deg", "period_s"},
                          "an interfering laser: a map with origin, sweep_deg, period_s");
  InterferenceSpec s;
  const std::string origin_expected =
      "the source position in W in m, as [x, y, z]: in the room (|x|, |y| <= " +
      Fixed(kMaxInterferenceReach, 0) +
      " m) above the table top (0 < z <= " + Fixed(kMaxInterferenceHeight, 0) + " m)";
  const YAML::Node& origin = Require(e, n, field, "origin", origin_expected);
  s.origin_W = Numbers(origin, Join(field, "origin"), 3, origin_expected);
  if (std::abs(s.origin_W.x()) > kMaxInterferenceReach ||
      std::abs(s.origin_W.y()) > kMaxInterferenceReach || s.origin_W.z() <= 0.0 ||
      s.origin_W.z() > kMaxInterferenceHeight) {
    Fail(origin, Join(field, "origin"), origin_expected);
  }

  const std::string sweep_expected =
      "the plane's angle range in degrees, as [min, max], min < max, each within +-" +
      Fixed(kMaxSweepDeg, 0);
  const YAML::Node& sweep = Require(e, n, field, "sweep_deg", sweep_expected);
  const Eigen::VectorXd sweep_deg = Numbers(sweep, Join(field, "sweep_deg"), 2, sweep_expected);
  if (sweep_deg[0] >= sweep_deg[1] || std::abs(sweep_deg[0]) > kMaxSweepDeg ||
      std::abs(sweep_deg[1]) > kMaxSweepDeg) {
    Fail(sweep, Join(field, "sweep_deg"), sweep_expected);
  }
  s.sweep_min = DegToRad(sweep_deg[0]);
  s.sweep_max = DegToRad(sweep_deg[1]);

  const std::string period_expected =
      "a sweep period in s, > 0 and at most " + Fixed(kMaxPeriodS, 0);
  const YAML::Node& period = Require(e, n, field, "period_s", period_expected);
  s.period_s = Number(period, Join(field, "period_s"), period_expected);
  if (s.period_s <= 0.0 || s.period_s > kMaxPeriodS) {
    Fail(period, Join(field, "period_s"), period_expected);
  }
  return s;
}

BoardSpec Parser::ParseBoard(const YAML::Node& n, const std::string& field) const {
  const Entries e =
      MapOf(n, field, {"cols", "rows", "square_mm", "position", "yaw_deg", "tilt_deg"},
            "a chessboard: a map with cols, rows, square_mm, position and "
            "optionally yaw_deg, tilt_deg");
  BoardSpec b;
  const std::string corners_expected = "a whole number of inner corners, " +
                                       std::to_string(kMinBoardCorners) + "-" +
                                       std::to_string(kMaxBoardCorners);
  for (const auto& [key, value] : {std::pair<const char*, int*>{"cols", &b.cols},
                                   std::pair<const char*, int*>{"rows", &b.rows}}) {
    const YAML::Node& node = Require(e, n, field, key, corners_expected);
    const double v = Number(node, Join(field, key), corners_expected);
    if (v != std::round(v) || v < kMinBoardCorners || v > kMaxBoardCorners) {
      Fail(node, Join(field, key), corners_expected);
    }
    *value = static_cast<int>(v);
  }
  if (b.cols == b.rows) {
    Fail(n["rows"], Join(field, "rows"),
         "a number of corners other than cols' (a square pattern has no orientation OpenCV can "
         "tell)");
  }
  const std::string square_expected = "a square edge of " + Fixed(1e3 * kMinBoardSquare, 0) + "-" +
                                      Fixed(1e3 * kMaxBoardSquare, 0) + " mm";
  const YAML::Node& square = Require(e, n, field, "square_mm", square_expected);
  b.square_m = 1e-3 * Number(square, Join(field, "square_mm"), square_expected);
  if (b.square_m < kMinBoardSquare - 1e-12 || b.square_m > kMaxBoardSquare + 1e-12) {
    Fail(square, Join(field, "square_mm"), square_expected);
  }
  const std::string pos_expected =
      "the printed face's centre in W in m, as [x, y, z]: over the table top (x in [" +
      Fixed(kTableMinX, 2) + ", " + Fixed(kTableMaxX, 2) + "], y in [" + Fixed(kTableMinY, 2) +
      ", " + Fixed(kTableMaxY, 2) + "]), 0 < z <= " + Fixed(kMaxBoardHeight, 1);
  const YAML::Node& position = Require(e, n, field, "position", pos_expected);
  b.position_W = Numbers(position, Join(field, "position"), 3, pos_expected);
  const Eigen::Vector3d& p = b.position_W;
  if (p.x() < kTableMinX || p.x() > kTableMaxX || p.y() < kTableMinY || p.y() > kTableMaxY ||
      p.z() <= 0.0 || p.z() > kMaxBoardHeight) {
    Fail(position, Join(field, "position"), pos_expected);
  }
  if (const YAML::Node* yaw = Find(e, "yaw_deg")) {
    const std::string yaw_expected =
        "a yaw about W z of -" + Fixed(kMaxYawDeg, 0) + " to " + Fixed(kMaxYawDeg, 0) + " deg";
    const double deg = Number(*yaw, Join(field, "yaw_deg"), yaw_expected);
    if (std::abs(deg) > kMaxYawDeg) Fail(*yaw, Join(field, "yaw_deg"), yaw_expected);
    b.yaw = DegToRad(deg);
  }
  if (const YAML::Node* tilt = Find(e, "tilt_deg")) {
    const std::string tilt_expected = "a tilt of -90 to 90 deg (0: face up)";
    const double deg = Number(*tilt, Join(field, "tilt_deg"), tilt_expected);
    if (std::abs(deg) > 90.0) Fail(*tilt, Join(field, "tilt_deg"), tilt_expected);
    b.tilt = DegToRad(deg);
  }
  return b;
}

void Parser::CheckBoard(const Scenario& s, std::size_t i, const YAML::Node& n) const {
  const BoardSpec& b = s.boards[i];
  const std::string field = Join(Index("boards", i), "position");
  const Pose3 X_WB = b.X_WB();
  const Eigen::Vector2d half = b.HalfExtent();
  // The plate (5 mm thick, behind the face) sampled on a grid: above the table, clear of every
  // object and of every other board.
  constexpr int kSamples = 9;
  for (int a = 0; a < kSamples; ++a) {
    for (int c = 0; c < kSamples; ++c) {
      for (double depth : {0.0, -0.005}) {
        const Eigen::Vector3d p_B(half.x() * (2.0 * a / (kSamples - 1) - 1.0),
                                  half.y() * (2.0 * c / (kSamples - 1) - 1.0), depth);
        const Eigen::Vector3d p_W = X_WB * p_B;
        if (p_W.z() < 0.0) {
          Fail(n["position"], field,
               "a board above the table top (its plate reaches z = " + Fixed(p_W.z()) + " m)");
        }
        for (std::size_t j = 0; j < s.objects.size(); ++j) {
          const ObjectSpec& o = s.objects[j];
          const Eigen::Vector3d p_O = o.X_WO().inverse() * p_W;
          if ((p_O.cwiseAbs().array() <= 0.5 * o.size_O.array() + 0.005).all()) {
            Fail(n["position"], field,
                 "a board clear of every object by 5 mm (it reaches into " + Index("objects", j) +
                     " '" + o.name + "')");
          }
        }
        for (std::size_t j = 0; j < i; ++j) {
          const BoardSpec& other = s.boards[j];
          const Eigen::Vector3d p_O = other.X_WB().inverse() * p_W;
          if (std::abs(p_O.x()) <= other.HalfExtent().x() &&
              std::abs(p_O.y()) <= other.HalfExtent().y() && p_O.z() <= 0.005 && p_O.z() >= -0.01) {
            Fail(n["position"], field,
                 "a board clear of every other board (it reaches into " + Index("boards", j) + ")");
          }
        }
      }
    }
  }
}

TaskSpec Parser::ParseTask(const YAML::Node& n, const std::string& field,
                           YAML::Node* name_node) const {
  const Entries e = MapOf(n, field, {"target", "lift"},
                          "a task: a map with target ({color: ...} or {name: ...}) and lift");
  TaskSpec t;
  const std::string target_field = Join(field, "target");
  const std::string target_expected = "exactly one of color and name, e.g. {color: yellow}";
  const YAML::Node& target = Require(e, n, field, "target", target_expected);
  const Entries te = MapOf(target, target_field, {"color", "name"}, target_expected);
  const YAML::Node* color = Find(te, "color");
  const YAML::Node* name = Find(te, "name");
  if ((color == nullptr) == (name == nullptr)) Fail(target, target_field, target_expected);
  if (color != nullptr) {
    const std::string color_field = Join(target_field, "color");
    const std::string color_expected =
        "a colour name, " + OneOf(Keys(kColorNames.begin(), kColorNames.end()));
    t.target_color = Text(*color, color_field, color_expected);
    bool known = false;
    for (std::string_view c : kColorNames) known = known || t.target_color == c;
    if (!known) Fail(*color, color_field, color_expected);
  } else {
    t.target_name = Name(*name, Join(target_field, "name"));
    *name_node = *name;
  }

  if (const YAML::Node* lift = Find(e, "lift")) {
    const std::string lift_expected = "a lift height in m, > 0 and <= " + Fixed(kMaxLift, 2);
    t.lift_m = Number(*lift, Join(field, "lift"), lift_expected);
    if (t.lift_m <= 0.0 || t.lift_m > kMaxLift) Fail(*lift, Join(field, "lift"), lift_expected);
  }
  return t;
}

RobotErrorsSpec Parser::ParseRobotErrors(const YAML::Node& n, const std::string& field) const {
  RobotErrorsSpec r;
  // Each value, its unit, and a bound far beyond any real robot's (a typo, not a robot).
  struct Value {
    const char* key;
    double* value;
    double max;
    const char* what;
  };
  const Value values[] = {
      {"arm_joint_zero_deg", &r.arm_joint_zero_deg, 5.0, "a joint zero std. dev. in deg"},
      {"arm_link_mm", &r.arm_link_mm, 10.0, "a link offset std. dev. in mm"},
      {"arm_backlash_deg", &r.arm_backlash_deg, 2.0, "a full backlash in deg"},
      {"arm_encoder_deg", &r.arm_encoder_deg, 1.0, "an encoder resolution in deg"},
      {"arm_latency_ms", &r.arm_latency_ms, 500.0, "a command latency in ms"},
      {"head_encoder_deg", &r.head_encoder_deg, 1.0, "an encoder resolution in deg"},
      {"head_latency_ms", &r.head_latency_ms, 500.0, "a command latency in ms"},
      {"head_mount_mm", &r.head_mount_mm, 50.0, "a mounting std. dev. in mm"},
      {"head_mount_deg", &r.head_mount_deg, 10.0, "a mounting std. dev. in deg"},
      {"camera_focal_pct", &r.camera_focal_pct, 10.0, "a focal length std. dev. in %"},
  };
  Keys keys = {"enabled"};
  for (const Value& v : values) keys.push_back(v.key);
  const Entries e = MapOf(n, field, keys,
                          "a map of robot errors, e.g. {enabled: false} or {arm_joint_zero_deg: "
                          "0.2}: " +
                              OneOf(keys));
  if (const YAML::Node* enabled = Find(e, "enabled")) {
    const std::optional<bool> b = ParseBool(*enabled);
    if (!b) Fail(*enabled, Join(field, "enabled"), "true or false" + QuoteHint(*enabled));
    r.enabled = *b;
  }
  for (const Value& v : values) {
    if (const YAML::Node* node = Find(e, v.key)) {
      const std::string expected = std::string(v.what) + ", 0-" + Fixed(v.max, 0) + " (0: off)";
      *v.value = Number(*node, Join(field, v.key), expected);
      if (*v.value < 0.0 || *v.value > v.max) Fail(*node, Join(field, v.key), expected);
    }
  }
  return r;
}

void Parser::CheckAcrossObjects(const Scenario& s, const std::vector<ObjectNodes>& nodes) const {
  std::vector<Footprint> footprints;
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    const ObjectSpec& o = s.objects[i];
    const std::string field = Index("objects", i);
    footprints.push_back(ObjectFootprint(o));
    constexpr double kTol = 1e-9;
    for (const Eigen::Vector2d& c : footprints.back()) {
      if (c.x() < kTableMinX - kTol || c.x() > kTableMaxX + kTol || c.y() < kTableMinY - kTol ||
          c.y() > kTableMaxY + kTol) {
        Fail(nodes[i].position, Join(field, "position"),
             "a footprint inside the table top, x in [" + Fixed(kTableMinX, 2) + ", " +
                 Fixed(kTableMaxX, 2) + "] m, y in [" + Fixed(kTableMinY, 2) + ", " +
                 Fixed(kTableMaxY, 2) + "] m (the corner at (" + Fixed(c.x()) + ", " +
                 Fixed(c.y()) + ") is outside)");
      }
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (s.objects[j].name == o.name) {
        Fail(nodes[i].name, Join(field, "name"),
             "a unique object name (" + Index("objects", j) + " is also called '" + o.name + "')");
      }
    }
  }
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (FootprintsOverlap(footprints[i], footprints[j])) {
        Fail(nodes[i].position, Join(Index("objects", i), "position"),
             "a footprint clear of every other object (it overlaps " + Index("objects", j) + " '" +
                 s.objects[j].name + "')");
      }
    }
  }
}

Scenario Parser::Parse(const std::string& text) {
  const std::string top_expected =
      "a map of scenario fields: name, seed, camera_noise, camera_samples, lighting, wall, "
      "objects, interference, boards, task, robot_errors, devices";
  const YAML::Node root = yaml::LoadDocument(text, path(), top_expected);
  if (!root.IsMap()) Fail(root, "top level", top_expected);
  const Entries e = MapOf(root, "",
                          {"name", "seed", "camera_noise", "camera_samples", "lighting", "wall",
                           "objects", "interference", "boards", "task", "robot_errors", "devices"},
                          top_expected);

  Scenario s;
  s.path = path();
  s.name = Name(Require(e, root, "", "name", "a scenario name"), "name");

  if (const YAML::Node* seed = Find(e, "seed")) {
    const std::optional<std::uint64_t> v = ParseUnsigned(*seed);
    if (!v) Fail(*seed, "seed", "a non-negative integer (the random seed)" + QuoteHint(*seed));
    s.seed = *v;
  }

  if (const YAML::Node* noise = Find(e, "camera_noise")) {
    const std::string expected = "a camera noise std. dev. of 0-" + Fixed(kMaxCameraNoise, 0) +
                                 " grey levels (of 255; a real camera shows 1-3)";
    s.camera_noise = Number(*noise, "camera_noise", expected);
    if (s.camera_noise < 0.0 || s.camera_noise > kMaxCameraNoise) {
      Fail(*noise, "camera_noise", expected);
    }
  }

  if (const YAML::Node* samples = Find(e, "camera_samples")) {
    const std::string expected = "samples a pixel of the colour frames: 1, 4, 9 or 16";
    const double v = Number(*samples, "camera_samples", expected);
    if (v != 1 && v != 4 && v != 9 && v != 16) Fail(*samples, "camera_samples", expected);
    s.camera_samples = static_cast<int>(v);
  }

  if (const YAML::Node* lighting = Find(e, "lighting")) {
    const Entries le = MapOf(*lighting, "lighting", {"ambient"}, "a map such as {ambient: 0.35}");
    if (const YAML::Node* ambient = Find(le, "ambient")) {
      const std::string expected = "an ambient light level 0-1";
      s.ambient = Number(*ambient, "lighting.ambient", expected);
      if (s.ambient < 0.0 || s.ambient > 1.0) Fail(*ambient, "lighting.ambient", expected);
    }
  }

  std::vector<ObjectNodes> object_nodes;
  if (const YAML::Node* objects = Find(e, "objects")) {
    if (!objects->IsSequence()) Fail(*objects, "objects", "a list of objects");
    for (std::size_t i = 0; i < objects->size(); ++i) {
      object_nodes.emplace_back();
      s.objects.push_back(ParseObject((*objects)[i], Index("objects", i), &object_nodes.back()));
    }
  }

  YAML::Node wall_x_node;
  if (const YAML::Node* wall = Find(e, "wall")) {
    const std::string wall_expected =
        "a wall plane x in m, > " + Fixed(kMinWallX, 2) + " and at most " + Fixed(kMaxWallX, 1);
    const Entries we = MapOf(*wall, "wall", {"x"}, "a map such as {x: 0.9}");
    wall_x_node = Require(we, *wall, "wall", "x", wall_expected);
    s.wall_x = Number(wall_x_node, "wall.x", wall_expected);
    if (*s.wall_x <= kMinWallX || *s.wall_x > kMaxWallX) {
      Fail(wall_x_node, "wall.x", wall_expected);
    }
  }

  if (const YAML::Node* interference = Find(e, "interference")) {
    if (!interference->IsSequence()) {
      Fail(*interference, "interference", "a list of interfering lasers");
    }
    for (std::size_t i = 0; i < interference->size(); ++i) {
      const YAML::Node& node = (*interference)[i];
      const std::string field = Index("interference", i);
      s.interference.push_back(ParseInterference(node, field));
      // A laser inside a box lights nothing the cameras see.
      for (std::size_t j = 0; j < s.objects.size(); ++j) {
        const ObjectSpec& o = s.objects[j];
        const Eigen::Vector3d p_O = o.X_WO().inverse() * s.interference.back().origin_W;
        if ((p_O.cwiseAbs().array() <= 0.5 * o.size_O.array()).all()) {
          Fail(node["origin"], Join(field, "origin"),
               "a source outside every object (it is inside " + Index("objects", j) + " '" +
                   o.name + "')");
        }
      }
    }
  }

  if (const YAML::Node* boards = Find(e, "boards")) {
    if (!boards->IsSequence()) Fail(*boards, "boards", "a list of calibration chessboards");
    for (std::size_t i = 0; i < boards->size(); ++i) {
      s.boards.push_back(ParseBoard((*boards)[i], Index("boards", i)));
      CheckBoard(s, i, (*boards)[i]);
    }
  }

  YAML::Node target_name_node;
  if (const YAML::Node* task = Find(e, "task")) {
    s.task = ParseTask(*task, "task", &target_name_node);
  }

  if (const YAML::Node* errors = Find(e, "robot_errors")) {
    s.robot_errors = ParseRobotErrors(*errors, "robot_errors");
  }

  if (const YAML::Node* devices = Find(e, "devices"))
    s.devices = drivers::ParseDevices(*this, *devices);

  // Checks across fields.
  CheckAcrossObjects(s, object_nodes);
  if (s.wall_x) {
    for (std::size_t i = 0; i < s.objects.size(); ++i) {
      for (const Eigen::Vector2d& c : ObjectFootprint(s.objects[i])) {
        if (c.x() >= *s.wall_x) {
          Fail(wall_x_node, "wall.x",
               "a wall beyond every object (" + Index("objects", i) + " '" + s.objects[i].name +
                   "' reaches x = " + Fixed(c.x()) + " m)");
        }
      }
    }
  }
  if (s.task && !s.task->target_name.empty()) {
    bool found = false;
    std::string names;
    for (const ObjectSpec& o : s.objects) {
      found = found || o.name == s.task->target_name;
      names += (names.empty() ? "" : ", ") + o.name;
    }
    if (!found) {
      Fail(target_name_node, "task.target.name",
           names.empty() ? "the name of an object, but the scenario has none"
                         : "the name of an object, one of: " + names);
    }
  }
  return s;
}

}  // namespace

Scenario ParseScenario(const std::string& yaml_text, const std::string& path_for_errors) {
  Parser parser(path_for_errors);
  try {
    return parser.Parse(yaml_text);
  } catch (const YAML::Exception& e) {
    // Anything yaml-cpp throws beyond a syntax error still leaves as an InputError.
    const std::string where =
        e.mark.line < 0 ? path_for_errors : path_for_errors + ":" + std::to_string(e.mark.line + 1);
    throw InputError(where, "", e.msg, "a valid scenario file");
  }
}

std::string ScenarioYaml(const Scenario& s) {
  if (!s.devices.entries.empty()) {
    throw std::invalid_argument("ScenarioYaml: only a scenario whose devices are all simulated");
  }
  // The shortest text that reads back to the same double.
  const auto num = [](double v) {
    char buf[32];
    const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, end);
  };
  const auto list = [&](std::initializer_list<double> v) {
    std::string text = "[";
    for (double x : v) text.append(text.size() > 1 ? ", " : "").append(num(x));
    return text.append("]");
  };
  std::ostringstream y;
  y << "name: " << s.name << "\n"
    << "seed: " << s.seed << "\n"
    << "camera_noise: " << num(s.camera_noise) << "\n"
    << "camera_samples: " << s.camera_samples << "\n"
    << "lighting: {ambient: " << num(s.ambient) << "}\n";
  if (s.wall_x) y << "wall: {x: " << num(*s.wall_x) << "}\n";
  y << "objects:" << (s.objects.empty() ? " []\n" : "\n");
  for (const ObjectSpec& o : s.objects) {
    y << "  - name: " << o.name << "\n"
      << "    shape: " << o.shape << "\n"
      << "    size: " << list({o.size_O.x(), o.size_O.y(), o.size_O.z()}) << "\n"
      << "    position: " << list({o.position_W.x(), o.position_W.y()}) << "\n"
      << "    yaw_deg: " << num(RadToDeg(o.yaw)) << "\n"
      << "    color: " << list({o.color_rgb.x(), o.color_rgb.y(), o.color_rgb.z()}) << "\n";
    if (!o.color_name.empty()) y << "    color_name: " << o.color_name << "\n";
    y << "    mass: " << num(o.mass) << "\n"
      << "    specular: " << (o.specular ? "true" : "false") << "\n";
  }
  if (!s.interference.empty()) y << "interference:\n";
  for (const InterferenceSpec& i : s.interference) {
    y << "  - origin: " << list({i.origin_W.x(), i.origin_W.y(), i.origin_W.z()}) << "\n"
      << "    sweep_deg: " << list({RadToDeg(i.sweep_min), RadToDeg(i.sweep_max)}) << "\n"
      << "    period_s: " << num(i.period_s) << "\n";
  }
  if (!s.boards.empty()) y << "boards:\n";
  for (const BoardSpec& b : s.boards) {
    y << "  - {cols: " << b.cols << ", rows: " << b.rows << ", square_mm: " << num(1e3 * b.square_m)
      << ", position: " << list({b.position_W.x(), b.position_W.y(), b.position_W.z()})
      << ", yaw_deg: " << num(RadToDeg(b.yaw)) << ", tilt_deg: " << num(RadToDeg(b.tilt)) << "}\n";
  }
  if (s.task) {
    y << "task:\n  target: {"
      << (s.task->target_name.empty() ? "color: " + s.task->target_color
                                      : "name: " + s.task->target_name)
      << "}\n  lift: " << num(s.task->lift_m) << "\n";
  }
  const RobotErrorsSpec& r = s.robot_errors;
  y << "robot_errors:\n  enabled: " << (r.enabled ? "true" : "false") << "\n"
    << "  arm_joint_zero_deg: " << num(r.arm_joint_zero_deg) << "\n"
    << "  arm_link_mm: " << num(r.arm_link_mm) << "\n"
    << "  arm_backlash_deg: " << num(r.arm_backlash_deg) << "\n"
    << "  arm_encoder_deg: " << num(r.arm_encoder_deg) << "\n"
    << "  arm_latency_ms: " << num(r.arm_latency_ms) << "\n"
    << "  head_encoder_deg: " << num(r.head_encoder_deg) << "\n"
    << "  head_latency_ms: " << num(r.head_latency_ms) << "\n"
    << "  head_mount_mm: " << num(r.head_mount_mm) << "\n"
    << "  head_mount_deg: " << num(r.head_mount_deg) << "\n"
    << "  camera_focal_pct: " << num(r.camera_focal_pct) << "\n";
  y << "devices: {}\n";
  return y.str();
}

Scenario LoadScenario(const std::string& path) {
  return ParseScenario(yaml::ReadText(path, "a readable scenario file (YAML)"), path);
}

std::array<Eigen::Vector2d, 4> ObjectFootprint(const ObjectSpec& o) {
  const Eigen::Matrix2d R_WO = Eigen::Rotation2Dd(o.yaw).toRotationMatrix();
  const Eigen::Vector2d half = o.size_O.head<2>() / 2.0;
  constexpr double kSx[4] = {1, -1, -1, 1}, kSy[4] = {1, 1, -1, -1};
  std::array<Eigen::Vector2d, 4> corners;
  for (int i = 0; i < 4; ++i) {
    corners[i] = o.position_W + R_WO * Eigen::Vector2d(kSx[i] * half.x(), kSy[i] * half.y());
  }
  return corners;
}

// Separating axis test on two convex quadrilaterals: true when their interiors intersect.
// Footprints that merely touch (within 1 nm) do not overlap.
bool FootprintsOverlap(const std::array<Eigen::Vector2d, 4>& a,
                       const std::array<Eigen::Vector2d, 4>& b) {
  constexpr double kTouch = 1e-9;  // m
  for (const std::array<Eigen::Vector2d, 4>* poly : {&a, &b}) {
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector2d edge = (*poly)[(i + 1) % 4] - (*poly)[i];
      const Eigen::Vector2d axis = Eigen::Vector2d(-edge.y(), edge.x()).normalized();
      double a_min = std::numeric_limits<double>::infinity(), a_max = -a_min;
      double b_min = a_min, b_max = -a_min;
      for (int k = 0; k < 4; ++k) {
        a_min = std::min(a_min, axis.dot(a[k]));
        a_max = std::max(a_max, axis.dot(a[k]));
        b_min = std::min(b_min, axis.dot(b[k]));
        b_max = std::max(b_max, axis.dot(b[k]));
      }
      if (a_max <= b_min + kTouch || b_max <= a_min + kTouch) return false;
    }
  }
  return true;
}

namespace {

double PointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                            const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - p).norm();
}

}  // namespace

double FootprintDistance(const std::array<Eigen::Vector2d, 4>& a,
                         const std::array<Eigen::Vector2d, 4>& b) {
  if (FootprintsOverlap(a, b)) return 0.0;
  double d = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 4; ++i) {
    for (int k = 0; k < 4; ++k) {
      d = std::min(d, PointSegmentDistance(a[i], b[k], b[(k + 1) % 4]));
      d = std::min(d, PointSegmentDistance(b[i], a[k], a[(k + 1) % 4]));
    }
  }
  return d;
}

bool FootprintOnTable(const std::array<Eigen::Vector2d, 4>& f) {
  for (const Eigen::Vector2d& c : f) {
    if (c.x() < kTableMinX || c.x() > kTableMaxX || c.y() < kTableMinY || c.y() > kTableMaxY) {
      return false;
    }
  }
  return true;
}

}  // namespace hgrasp::sim
