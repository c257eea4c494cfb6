#include "sim/scenario.h"

#include <sys/stat.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <system_error>
#include <utility>

#include "common/error.h"
#include "common/yaml_file.h"
#include "common/yaml_util.h"

namespace hgrasp::sim {

Pose3 ObjectSpec::X_WO() const {
  Pose3 X_WO = Pose3::Identity();
  X_WO.linear() = RotZ(yaw);
  X_WO.translation() = Eigen::Vector3d(position_W.x(), position_W.y(), size_O.z() / 2.0);
  return X_WO;
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

// What a serial port's path opens, for telling whether two paths are one port: the device
// number of a character device (any path to it: a symlink, /dev//ttyS9, a second device node),
// the inode of another existing file, else the path with its symlinks resolved and "//" and
// "." taken out.
std::string PortIdentity(const std::string& port) {
  struct stat st {};
  if (::stat(port.c_str(), &st) == 0) {
    if (S_ISCHR(st.st_mode)) return "char " + std::to_string(static_cast<unsigned long>(st.st_rdev));
    return "inode " + std::to_string(static_cast<unsigned long>(st.st_dev)) + ":" +
           std::to_string(static_cast<unsigned long>(st.st_ino));
  }
  std::error_code ec;
  const std::filesystem::path canonical = std::filesystem::weakly_canonical(port, ec);
  return "path " + (ec ? std::filesystem::path(port).lexically_normal() : canonical).string();
}

bool IsIdentifier(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-' || c == '.';
    if (!ok) return false;
  }
  return true;
}

// One key: value pair of a map, by key.
struct Entry {
  YAML::Node key, value;
};
using Entries = std::map<std::string, Entry>;

// An object's nodes needed again for the checks across objects. Assigned once each: assigning
// to a YAML::Node that already refers to a node would overwrite that node, not rebind.
struct ObjectNodes {
  YAML::Node name, position;
};

// ---------------------------------------------------------------------------------------------
// The parser: every check names "FILE:LINE", the field path, the value and what was expected.

class Parser {
 public:
  explicit Parser(std::string path) : path_(std::move(path)) {}

  Scenario Parse(const std::string& text);

 private:
  std::string Where(const YAML::Mark& mark) const { return yaml::Where(path_, mark); }

  [[noreturn]] void Fail(const YAML::Mark& mark, const std::string& field, const std::string& value,
                         const std::string& expected) const {
    throw InputError(Where(mark), field, value, expected);
  }

  [[noreturn]] void Fail(const YAML::Node& at, const std::string& field,
                         const std::string& expected) const {
    Fail(at.Mark(), field, Render(at), expected);
  }

  // Checks that `n` is a map whose keys are all in `allowed`, each once; returns its entries.
  Entries MapOf(const YAML::Node& n, const std::string& field, const Keys& allowed,
                const std::string& expected) const {
    if (!n.IsMap()) Fail(n, field, expected);
    Entries entries;
    for (const auto& kv : n) {
      const YAML::Node& key = kv.first;
      const std::string name = key.IsScalar() ? key.Scalar() : Render(key);
      bool known = false;
      for (std::string_view a : allowed) known = known || name == a;
      if (!key.IsScalar() || !known) {
        Fail(key.Mark(), Join(field, name), name, "a known key here, " + OneOf(allowed));
      }
      if (entries.count(name) != 0) {
        Fail(key.Mark(), Join(field, name), name,
             "each key once (it is also on line " +
                 std::to_string(entries.at(name).key.Mark().line + 1) + ")");
      }
      entries.emplace(name, Entry{key, kv.second});
    }
    return entries;
  }

  static const YAML::Node* Find(const Entries& entries, std::string_view key) {
    const auto it = entries.find(std::string(key));
    return it == entries.end() ? nullptr : &it->second.value;
  }

  const YAML::Node& Require(const Entries& entries, const YAML::Node& map, const std::string& field,
                            std::string_view key, const std::string& expected) const {
    const YAML::Node* n = Find(entries, key);
    if (n == nullptr) Fail(map.Mark(), Join(field, key), "", expected);
    return *n;
  }

  double Number(const YAML::Node& n, const std::string& field, const std::string& expected) const {
    const std::optional<double> v = ParseNumber(n);
    if (!v) Fail(n, field, expected + QuoteHint(n));
    return *v;
  }

  // A sequence of exactly `count` numbers.
  Eigen::VectorXd Numbers(const YAML::Node& n, const std::string& field, std::size_t count,
                          const std::string& expected) const {
    if (!n.IsSequence() || n.size() != count) Fail(n, field, expected);
    Eigen::VectorXd v(count);
    for (std::size_t i = 0; i < count; ++i) {
      const std::optional<double> x = ParseNumber(n[i]);
      if (!x) Fail(n, field, expected + QuoteHint(n));
      v[static_cast<Eigen::Index>(i)] = *x;
    }
    return v;
  }

  std::string Text(const YAML::Node& n, const std::string& field,
                   const std::string& expected) const {
    if (!n.IsScalar() || n.Scalar().empty()) Fail(n, field, expected);
    return n.Scalar();
  }

  std::string Name(const YAML::Node& n, const std::string& field) const {
    const std::string s = Text(n, field, "a name of letters, digits, '_', '-' or '.'");
    if (!IsIdentifier(s)) Fail(n, field, "a name of letters, digits, '_', '-' or '.'");
    return s;
  }

  ObjectSpec ParseObject(const YAML::Node& n, const std::string& field, ObjectNodes* nodes) const;
  InterferenceSpec ParseInterference(const YAML::Node& n, const std::string& field) const;
  TaskSpec ParseTask(const YAML::Node& n, const std::string& field, YAML::Node* name_node) const;
  DeviceSpec ParseDevice(const YAML::Node& n, std::string_view key, const std::string& field) const;
  void CheckAcrossDevices(const Scenario& s, const YAML::Node& devices) const;
  void CheckAcrossObjects(const Scenario& s, const std::vector<ObjectNodes>& nodes) const;

  std::string path_;
};

ObjectSpec Parser::ParseObject(const YAML::Node& n, const std::string& field,
                               ObjectNodes* nodes) const {
  const Entries e = MapOf(
      n, field, {"name", "shape", "size", "position", "yaw_deg", "color", "mass", "specular"},
      "an object: a map with name, shape, size, position, color and optionally yaw_deg, mass, "
      "specular");
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
    const std::string yaw_expected = "a yaw about W z of -" + Fixed(kMaxYawDeg, 0) + " to " +
                                     Fixed(kMaxYawDeg, 0) + " deg";
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

  if (const YAML::Node* mass = Find(e, "mass")) {
    const std::string mass_expected = "a mass of " + Fixed(kMinMass, 2) + "-" +
                                      Fixed(kMaxMass, 2) +
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
      Fixed(kMaxInterferenceReach, 0) + " m) above the table top (0 < z <= " +
      Fixed(kMaxInterferenceHeight, 0) + " m)";
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

DeviceSpec Parser::ParseDevice(const YAML::Node& n, std::string_view key,
                               const std::string& field) const {
  // The drivers this device accepts.
  std::vector<std::string> drivers = {"sim"};
  const DriverKind* kind = nullptr;
  for (const DriverKind& k : kDrivers) {
    if (k.devices[0] == key || k.devices[1] == key) drivers.emplace_back(k.driver);
  }
  const std::string driver_expected =
      "a driver for " + std::string(key) + ", " + OneOf(Keys(drivers.begin(), drivers.end()));
  if (!n.IsMap()) Fail(n, field, "a device backend: a map with driver and its settings");
  const YAML::Node driver = n["driver"];
  if (!driver) Fail(n.Mark(), Join(field, "driver"), "", driver_expected);
  DeviceSpec d;
  d.line = n.Mark().line + 1;
  d.driver = Text(driver, Join(field, "driver"), driver_expected);
  for (const DriverKind& k : kDrivers) {
    if (k.driver == d.driver && (k.devices[0] == key || k.devices[1] == key)) kind = &k;
  }
  if (kind == nullptr && d.driver != "sim") Fail(driver, Join(field, "driver"), driver_expected);

  Keys allowed = {"driver"};
  std::string expected = "a device backend: driver " + d.driver + " takes no settings";
  if (d.serial()) {
    allowed = {"driver", "port", "baud", "framing"};
    expected = "a serial device: driver, port and optionally baud, framing";
  } else if (d.driver == "gstreamer") {
    allowed = {"driver", "left", "right"};
    expected = "cameras through GStreamer: driver, left and right (the pipelines)";
  }
  const Entries e = MapOf(n, field, allowed, expected);
  if (d.serial()) {
    const std::string port_expected = "the serial port's path, e.g. /dev/ttyS0";
    d.port = Text(Require(e, n, field, "port", port_expected), Join(field, "port"), port_expected);
    d.baud = kind->default_baud;
    if (const YAML::Node* baud = Find(e, "baud")) {
      static constexpr int kBauds[] = {1200,  2400,   4800,   9600,   19200, 38400,
                                       57600, 115200, 230400, 460800, 921600};
      std::string rates;
      for (int b : kBauds) rates += (rates.empty() ? "" : ", ") + std::to_string(b);
      const std::string baud_expected = "a standard baud rate: " + rates;
      const std::optional<std::uint64_t> v = ParseUnsigned(*baud);
      if (!v || std::find(std::begin(kBauds), std::end(kBauds), static_cast<int>(*v)) ==
                    std::end(kBauds)) {
        Fail(*baud, Join(field, "baud"), baud_expected + QuoteHint(*baud));
      }
      d.baud = static_cast<int>(*v);
    }
    if (const YAML::Node* framing = Find(e, "framing")) {
      const std::string framing_expected =
          "data bits 5-8, parity N, E or O, stop bits 1 or 2, e.g. 8N1";
      d.framing = Text(*framing, Join(field, "framing"), framing_expected);
      const std::string& f = d.framing;
      if (f.size() != 3 || f[0] < '5' || f[0] > '8' ||
          std::string("NEO").find(f[1]) == std::string::npos || (f[2] != '1' && f[2] != '2')) {
        Fail(*framing, Join(field, "framing"), framing_expected);
      }
    }
  } else if (d.driver == "gstreamer") {
    const std::string pipe_expected =
        "a GStreamer pipeline ending in appsink, e.g. v4l2src device=/dev/video0 ! videoconvert "
        "! appsink";
    d.left = Text(Require(e, n, field, "left", pipe_expected), Join(field, "left"), pipe_expected);
    d.right =
        Text(Require(e, n, field, "right", pipe_expected), Join(field, "right"), pipe_expected);
  }
  return d;
}

void Parser::CheckAcrossDevices(const Scenario& s, const YAML::Node& devices) const {
  const auto spec = [&](const char* key) -> const DeviceSpec* {
    const auto it = s.devices.find(key);
    return it == s.devices.end() ? nullptr : &it->second;
  };
  // The camera driver takes the laser's encoder count latched at each exposure from the board.
  const DeviceSpec* cameras = spec("cameras");
  const DeviceSpec* laser = spec("laser");
  if (cameras != nullptr && cameras->driver == "gstreamer" &&
      (laser == nullptr || laser->driver != "laser_board")) {
    Fail(devices["cameras"]["driver"], "devices.cameras.driver",
         "sim, unless devices.laser is the laser_board too: real cameras take the laser's encoder "
         "count latched at each frame from the board");
  }
  // One port, one device; the laser and the LEDs share the laser board. Ports are compared by
  // the device they open, not by how their paths are spelled.
  std::map<std::string, std::string> owner;  // port identity -> device key
  for (const auto& [key, d] : s.devices) {
    if (!d.serial()) continue;
    const auto [it, fresh] = owner.emplace(PortIdentity(d.port), key);
    if (fresh) continue;
    const DeviceSpec& other = s.devices.at(it->second);
    const bool board = d.driver == "laser_board" && other.driver == "laser_board";
    if (!board) {
      Fail(devices[key]["port"], Join(Join("devices", key), "port"),
           "a port of its own (devices." + it->second + " uses it, as " + other.port + ")");
    }
    if (d.baud != other.baud || d.framing != other.framing) {
      Fail(devices[key]["port"], Join(Join("devices", key), "port"),
           "the laser and the LEDs on one board: the same baud and framing as devices." +
               it->second);
    }
  }
  const DeviceSpec* leds = spec("leds");
  if (laser != nullptr && leds != nullptr && laser->driver == "laser_board" &&
      leds->driver == "laser_board" && PortIdentity(laser->port) != PortIdentity(leds->port)) {
    Fail(devices["leds"]["port"], "devices.leds.port",
         "the laser's port, " + laser->port + " (the laser and the LEDs are one board)");
  }
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
      "a map of scenario fields: name, seed, camera_noise, lighting, wall, objects, "
      "interference, task, devices";
  const YAML::Node root = yaml::LoadDocument(text, path_, top_expected);
  if (!root.IsMap()) Fail(root, "top level", top_expected);
  const Entries e = MapOf(root, "",
                          {"name", "seed", "camera_noise", "lighting", "wall", "objects",
                           "interference", "task", "devices"},
                          top_expected);

  Scenario s;
  s.path = path_;
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
    const std::string wall_expected = "a wall plane x in m, > " + Fixed(kMinWallX, 2) +
                                      " and at most " + Fixed(kMaxWallX, 1);
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

  YAML::Node target_name_node;
  if (const YAML::Node* task = Find(e, "task")) {
    s.task = ParseTask(*task, "task", &target_name_node);
  }

  if (const YAML::Node* devices = Find(e, "devices")) {
    const Keys keys(kDeviceKeys.begin(), kDeviceKeys.end());
    const Entries de = MapOf(*devices, "devices", keys,
                             "a map from device to backend, e.g. {head: {driver: sim}}");
    for (const auto& [key, entry] : de) {
      s.devices.emplace(key, ParseDevice(entry.value, key, Join("devices", key)));
    }
    CheckAcrossDevices(s, *devices);
  }

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

}  // namespace hgrasp::sim
