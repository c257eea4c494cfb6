#include "config/device_config.h"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <sstream>
#include <system_error>
#include <vector>

#include "common/error.h"

namespace hgrasp::drivers {
namespace {

using yaml::Entries;
using yaml::Join;
using yaml::Keys;
using yaml::OneOf;
using yaml::QuoteHint;
using yaml::Reader;

constexpr double kPi = 3.14159265358979323846;

std::string Number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// ---------------------------------------------------------------------------------------------
// Driver options: each field of a driver's Options struct, by name, with its range.

using Joint6Speeds = std::array<double, 6>;

template <class T>
struct Field {
  std::string_view key;
  std::variant<double T::*, int T::*, bool T::*, Joint6Speeds T::*> member;
  double lo = 0.0, hi = 0.0;  // the allowed range of a number (each element of a list)
  bool lo_open = true;        // true: lo itself is not allowed
  std::string_view what;      // "a time (s)", ...
};

template <class T>
std::string Expected(const Field<T>& f) {
  if (std::holds_alternative<bool T::*>(f.member)) return std::string(f.what) + ": true or false";
  // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "(" + std::string.
  std::string range(f.lo_open ? "(" : "[");
  range.append(Number(f.lo)).append(", ").append(Number(f.hi)).append("]");
  if (std::holds_alternative<Joint6Speeds T::*>(f.member)) {
    return std::string(f.what) + ": a list of 6 numbers, each in " + range;
  }
  const bool integer = std::holds_alternative<int T::*>(f.member);
  return std::string(f.what) + ": " + (integer ? "an integer" : "a number") + " in " + range;
}

template <class T>
bool InRange(const Field<T>& f, double v) {
  return std::isfinite(v) && (f.lo_open ? v > f.lo : v >= f.lo) && v <= f.hi;
}

// Reads `options` (a map of the fields in `table`) into *out; what is not named keeps its
// default.
template <class T>
void ParseOptions(const Reader& r, const YAML::Node& node, const std::string& field,
                  const std::vector<Field<T>>& table, const std::string& what, T* out,
                  const Keys& extra = {}, Entries* extra_entries = nullptr) {
  Keys keys = extra;
  for (const Field<T>& f : table) keys.push_back(f.key);
  const Entries e = r.MapOf(node, field, keys, "the options of " + what + ", " + OneOf(keys));
  for (const Field<T>& f : table) {
    const YAML::Node* v = Reader::Find(e, f.key);
    if (v == nullptr) continue;
    const std::string name = Join(field, f.key);
    const std::string expected = Expected(f);
    if (auto m = std::get_if<bool T::*>(&f.member)) {
      const std::optional<bool> b = yaml::ParseBool(*v);
      if (!b) r.Fail(*v, name, expected + QuoteHint(*v));
      out->**m = *b;
    } else if (auto m = std::get_if<int T::*>(&f.member)) {
      const std::optional<long long> i = yaml::ParseInteger(*v);
      if (!i || !InRange(f, static_cast<double>(*i))) r.Fail(*v, name, expected + QuoteHint(*v));
      out->**m = static_cast<int>(*i);
    } else if (auto m = std::get_if<double T::*>(&f.member)) {
      const double x = r.Number(*v, name, expected);
      if (!InRange(f, x)) r.Fail(*v, name, expected);
      out->**m = x;
    } else if (auto m = std::get_if<Joint6Speeds T::*>(&f.member)) {
      const Eigen::VectorXd x = r.Numbers(*v, name, 6, expected);
      for (int i = 0; i < 6; ++i) {
        if (!InRange(f, x[i])) r.Fail(*v, name, expected);
        (out->**m)[static_cast<std::size_t>(i)] = x[i];
      }
    }
  }
  if (extra_entries != nullptr) {
    for (std::string_view k : extra) {
      if (const auto it = e.find(std::string(k)); it != e.end()) extra_entries->insert(*it);
    }
  }
}

// Times a driver waits (s): a millisecond (a character at 9600 baud) to ten minutes.
constexpr double kMinWait = 0.0, kMaxWait = 600.0;

const std::vector<Field<Val2Options>>& Val2Fields() {
  using O = Val2Options;
  static const std::vector<Field<O>> t = {
      {"echo_timeout_s", &O::echo_timeout_s, kMinWait, kMaxWait, true, "the wait for an echo (s)"},
      {"reply_timeout_s", &O::reply_timeout_s, kMinWait, kMaxWait, true,
       "the wait for an answer's first byte (s)"},
      {"quiet_s", &O::quiet_s, kMinWait, kMaxWait, true, "the silence that ends an answer (s)"},
      {"silence_budget_s", &O::silence_budget_s, kMinWait, kMaxWait, true,
       "the silence after which a call gives up (s)"},
      {"max_call_s", &O::max_call_s, kMinWait, kMaxWait, true, "the longest call (s)"},
      {"link_lost_s", &O::link_lost_s, kMinWait, kMaxWait, true,
       "the silence after which the link counts as lost (s)"},
      {"max_errors", &O::max_errors, 0, 1000, false, "error messages tolerated per command"},
      {"confirm_reads", &O::confirm_reads, 0, 0, false, "whether reads are confirmed twice"},
      {"max_joint_speed_deg_s", &O::max_joint_speed_deg_s, 0, 3600, true,
       "joint speed limits (deg/s)"},
      {"still_deg", &O::still_deg, 0, 10, true,
       "the joint change between reads that counts as motion (deg)"},
      {"motion_start_s", &O::motion_start_s, kMinWait, kMaxWait, true,
       "the time a move's check waits for it to start (s)"},
      {"moved_deg", &O::moved_deg, 0, 10, true,
       "the joints' progress that shows a move ran (deg)"},
      {"moved_mm", &O::moved_mm, 0, 100, true, "the tool's progress that shows a move ran (mm)"},
      {"moved_turn_deg", &O::moved_turn_deg, 0, 10, true,
       "the tool's turn that shows a move ran (deg)"},
  };
  return t;
}

const std::vector<Field<SensorHandOptions>>& SensorHandFields() {
  using O = SensorHandOptions;
  static const std::vector<Field<O>> t = {
      {"max_opening_m", &O::max_opening_m, 0.0, 0.5, true, "the widest opening (m)"},
      {"max_force_n", &O::max_force_n, 0.0, 1000.0, true, "the strongest grip (N)"},
      {"full_speed_m_s", &O::full_speed_m_s, 0.0, 10.0, true,
       "the opening rate at full speed (m/s)"},
      {"full_force_n", &O::full_force_n, 0.0, 1000.0, true, "the stall force at full speed (N)"},
      {"accel_m_s2", &O::accel_m_s2, 0.0, 1000.0, true, "the fingers' acceleration (m/s^2)"},
      {"slow_speed_m_s", &O::slow_speed_m_s, 0.0, 10.0, true,
       "the speed of the last millimetres (m/s)"},
      {"latency_s", &O::latency_s, 0.0, 1.0, false, "the command latency (s)"},
      {"opening_tolerance_m", &O::opening_tolerance_m, 0.0, 0.05, true,
       "the tolerance of Open (m)"},
      {"initial_opening_m", &O::initial_opening_m, 0.0, 0.5, false,
       "the opening assumed at start (m)"},
      {"initial_uncertainty_m", &O::initial_uncertainty_m, 0.0, 0.5, false,
       "how far the opening at start may be off (m)"},
      {"speed_error", &O::speed_error, 0.0, 1.0, false,
       "the estimate's error per metre of travel (share)"},
      {"unresolved_s", &O::unresolved_s, kMinWait, kMaxWait, true,
       "the wait before a command nobody can judge is given up (s)"},
      {"call_timeout_s", &O::call_timeout_s, kMinWait, kMaxWait, true, "the longest call (s)"},
      {"stream_timeout_s", &O::stream_timeout_s, kMinWait, kMaxWait, true,
       "the stream silence before a restart (s)"},
      {"fresh_s", &O::fresh_s, kMinWait, kMaxWait, true, "the oldest sample a read takes (s)"},
      {"transit_s", &O::transit_s, kMinWait, kMaxWait, true, "the worst one-way delay (s)"},
  };
  return t;
}

const std::vector<Field<BiclopsOptions>>& BiclopsFields() {
  using O = BiclopsOptions;
  static const std::vector<Field<O>> t = {
      {"reply_timeout_s", &O::reply_timeout_s, kMinWait, kMaxWait, true,
       "the wait for a complete reply (s)"},
      {"resync_byte_timeout_s", &O::resync_byte_timeout_s, kMinWait, kMaxWait, true,
       "the longest wait per resynchronisation byte (s)"},
      {"silence_timeout_s", &O::silence_timeout_s, kMinWait, kMaxWait, true,
       "the silence after which a call gives up (s)"},
      {"max_resends", &O::max_resends, 0, 1000, false, "re-sends of one command"},
      {"settle_margin_s", &O::settle_margin_s, 0.0, kMaxWait, false,
       "the margin on a profile's end (s)"},
      {"stop_settle_s", &O::stop_settle_s, kMinWait, kMaxWait, true,
       "the longest wait for the axes at rest after a stop (s)"},
      {"home_at_start", &O::home_at_start, 0, 0, false,
       "whether the head is homed when the driver is opened"},
  };
  return t;
}

const std::vector<Field<BiclopsAxisOptions>>& BiclopsAxisFields() {
  using O = BiclopsAxisOptions;
  static const std::vector<Field<O>> t = {
      {"counts_per_rad", &O::counts_per_rad, -1e7, 1e7, false,
       "encoder counts per radian (negative: the encoder runs against the joint)"},
      {"min_rad", &O::min_rad, -2 * kPi, 2 * kPi, false, "the joint's lower limit (rad)"},
      {"max_rad", &O::max_rad, -2 * kPi, 2 * kPi, false, "the joint's upper limit (rad)"},
      {"max_speed_rad_s", &O::max_speed_rad_s, 0.0, 100.0, true, "the profile speed (rad/s)"},
      {"max_accel_rad_s2", &O::max_accel_rad_s2, 0.0, 1000.0, true,
       "the profile acceleration (rad/s^2)"},
      {"homing_speed_rad_s", &O::homing_speed_rad_s, 0.0, 100.0, true,
       "the homing sweeps' speed (rad/s)"},
      {"homing_accel_rad_s2", &O::homing_accel_rad_s2, 0.0, 1000.0, true,
       "the homing sweeps' acceleration (rad/s^2)"},
      {"index_spacing_rad", &O::index_spacing_rad, 0.0, 2 * kPi, true,
       "the angle between index pulses (rad)"},
      {"home_sensor_width_rad", &O::home_sensor_width_rad, 0.0, 2 * kPi, true,
       "the home sensor's width (rad)"},
      {"home_active_low", &O::home_active_low, 0, 0, false,
       "whether the home sensor reads low on the sensor"},
      {"home_offset_rad", &O::home_offset_rad, -2 * kPi, 2 * kPi, false,
       "the joint's zero from the home index (rad)"},
      {"filter_kp", &O::filter_kp, 0, 32767, false, "the servo's proportional gain (chip units)"},
      {"filter_kd", &O::filter_kd, 0, 32767, false, "the servo's derivative gain (chip units)"},
      {"filter_ki", &O::filter_ki, 0, 32767, false, "the servo's integral gain (chip units)"},
      {"filter_kvff", &O::filter_kvff, 0, 32767, false, "the velocity feed-forward (chip units)"},
      {"filter_kaff", &O::filter_kaff, 0, 32767, false,
       "the acceleration feed-forward (chip units)"},
      {"filter_kout", &O::filter_kout, 0, 65535, false, "the output scale (chip units)"},
      {"filter_integration_limit", &O::filter_integration_limit, 0, 2147483647.0, false,
       "the integrator limit (chip units)"},
      {"filter_motor_limit", &O::filter_motor_limit, 0, 32767, false,
       "the motor command limit (chip units)"},
      {"filter_motor_bias", &O::filter_motor_bias, -32768, 32767, false,
       "the motor command bias (chip units)"},
      {"position_error_limit_rad", &O::position_error_limit_rad, 0.0, 2 * kPi, false,
       "the following error that is a motion error (rad)"},
      {"output_mode", &O::output_mode, 0, 2, false,
       "the motor output (0 DAC, 1 PWM sign/magnitude, 2 PWM 50/50)"},
      {"amp_active_low", &O::amp_active_low, 0, 0, false,
       "whether the amplifier's enable is active low"},
  };
  return t;
}

const std::vector<Field<LaserBoardOptions>>& LaserBoardFields() {
  using O = LaserBoardOptions;
  static const std::vector<Field<O>> t = {
      {"leds_per_gripper", &O::leds_per_gripper, 1, 32, false, "LEDs on each gripper"},
      {"max_speed_counts_s", &O::max_speed_counts_s, 0.0, 1e6, true,
       "the motor's fastest speed (counts/s)"},
      {"reply_timeout_s", &O::reply_timeout_s, kMinWait, kMaxWait, true,
       "the wait for a reply (s)"},
      {"call_timeout_s", &O::call_timeout_s, kMinWait, kMaxWait, true, "the longest call (s)"},
  };
  return t;
}

const std::vector<Field<GstCameraConfig>>& GstreamerFields() {
  using O = GstCameraConfig;
  static const std::vector<Field<O>> t = {
      {"width", &O::width, 16, 8192, false, "each frame's width (px)"},
      {"height", &O::height, 16, 8192, false, "each frame's height (px)"},
      {"frame_timeout_s", &O::frame_timeout_s, 0.0, 10.0, true,
       "the longest wait for a camera's next frame (s)"},
      {"frame_offset", &O::frame_offset, -100000, 100000, false,
       "the board's frame number minus the buffer offset (frames)"},
      {"frames_in_flight", &O::frames_in_flight, 0, 25, false,
       "frames that may arrive exposed before a command (frames)"},
  };
  return t;
}

// ---------------------------------------------------------------------------------------------

const DriverKind* KindOf(std::string_view driver, std::string_view key) {
  for (const DriverKind& k : kDrivers) {
    if (k.driver == driver && (k.devices[0] == key || k.devices[1] == key)) return &k;
  }
  return nullptr;
}

SerialConfig ParseSerial(const Reader& r, const Entries& e, const YAML::Node& n,
                         const std::string& field, const DriverKind& kind) {
  SerialConfig c;
  const std::string port_expected = "the serial port's path, e.g. /dev/ttyS0";
  c.port = r.Text(r.Require(e, n, field, "port", port_expected), Join(field, "port"),
                  port_expected);
  c.baud = kind.default_baud;
  if (const YAML::Node* baud = Reader::Find(e, "baud")) {
    static constexpr int kBauds[] = {1200,  2400,   4800,   9600,   19200, 38400,
                                     57600, 115200, 230400, 460800, 921600};
    std::string rates;
    for (int b : kBauds) rates += (rates.empty() ? "" : ", ") + std::to_string(b);
    const std::string baud_expected = "a standard baud rate: " + rates;
    const std::optional<std::uint64_t> v = yaml::ParseUnsigned(*baud);
    if (!v || std::find(std::begin(kBauds), std::end(kBauds), static_cast<int>(*v)) ==
                  std::end(kBauds)) {
      r.Fail(*baud, Join(field, "baud"), baud_expected + QuoteHint(*baud));
    }
    c.baud = static_cast<int>(*v);
  }
  if (const YAML::Node* framing = Reader::Find(e, "framing")) {
    const std::string framing_expected =
        "data bits 5-8, parity N, E or O, stop bits 1 or 2, e.g. 8N1";
    const std::string f = r.Text(*framing, Join(field, "framing"), framing_expected);
    if (f.size() != 3 || f[0] < '5' || f[0] > '8' ||
        std::string("NEO").find(f[1]) == std::string::npos || (f[2] != '1' && f[2] != '2')) {
      r.Fail(*framing, Join(field, "framing"), framing_expected);
    }
    c.data_bits = f[0] - '0';
    c.parity = f[1] == 'E' ? Parity::kEven : f[1] == 'O' ? Parity::kOdd : Parity::kNone;
    c.stop_bits = f[2] - '0';
  }
  return c;
}

BiclopsOptions ParseBiclopsOptions(const Reader& r, const YAML::Node& n, const std::string& field) {
  static constexpr std::array<std::string_view, 3> kAxes = {"pan", "tilt", "verge"};
  BiclopsOptions o = DefaultBiclopsOptions();
  Entries axes;
  ParseOptions(r, n, field, BiclopsFields(), "the Biclops driver", &o,
               Keys(kAxes.begin(), kAxes.end()), &axes);
  for (std::size_t a = 0; a < kAxes.size(); ++a) {
    const auto it = axes.find(std::string(kAxes[a]));
    if (it == axes.end()) continue;
    const std::string axis_field = Join(field, kAxes[a]);
    BiclopsAxisOptions& x = o.axes[a];
    ParseOptions(r, it->second.value, axis_field, BiclopsAxisFields(),
                 "the " + std::string(kAxes[a]) + " axis", &x);
    if (x.counts_per_rad == 0.0) {
      r.Fail(it->second.value, Join(axis_field, "counts_per_rad"),
             "a non-zero number of encoder counts per radian");
    }
    if (x.max_rad <= x.min_rad) {
      r.Fail(it->second.value, Join(axis_field, "max_rad"),
             "an upper limit above min_rad (" + Number(x.min_rad) + " rad)");
    }
  }
  return o;
}

DeviceConfig ParseDevice(const Reader& r, const YAML::Node& n, std::string_view key,
                         const std::string& field) {
  // The drivers this device accepts.
  std::vector<std::string> drivers = {"sim"};
  for (const DriverKind& k : kDrivers) {
    if (k.devices[0] == key || k.devices[1] == key) drivers.emplace_back(k.driver);
  }
  const std::string driver_expected =
      "a driver for " + std::string(key) + ", " + OneOf(Keys(drivers.begin(), drivers.end()));
  if (!n.IsMap()) r.Fail(n, field, "a device backend: a map with driver and its settings");
  const YAML::Node driver_node = n["driver"];
  if (!driver_node) r.Fail(n.Mark(), Join(field, "driver"), "", driver_expected);
  DeviceConfig d;
  d.line = n.Mark().line + 1;
  const std::string driver = r.Text(driver_node, Join(field, "driver"), driver_expected);
  const DriverKind* kind = KindOf(driver, key);
  if (kind == nullptr && driver != "sim") r.Fail(driver_node, Join(field, "driver"), driver_expected);

  if (driver == "sim") {
    r.MapOf(n, field, {"driver"}, "a device backend: driver sim takes no settings");
    d.backend = SimulatedBackend{};
    return d;
  }
  const std::string options_field = Join(field, "options");
  if (driver == "gstreamer") {
    const Entries e = r.MapOf(n, field, {"driver", "left", "right", "options"},
                              "cameras through GStreamer: driver, left and right (the pipelines) "
                              "and optionally options");
    const std::string pipe_expected =
        "a GStreamer pipeline ending in appsink, e.g. v4l2src device=/dev/video0 ! videoconvert "
        "! appsink";
    GstreamerBackend g;
    g.cameras.left = r.Text(r.Require(e, n, field, "left", pipe_expected), Join(field, "left"),
                            pipe_expected);
    g.cameras.right = r.Text(r.Require(e, n, field, "right", pipe_expected),
                             Join(field, "right"), pipe_expected);
    if (const YAML::Node* o = Reader::Find(e, "options")) {
      Entries extra;
      ParseOptions(r, *o, options_field, GstreamerFields(), "the GStreamer cameras", &g.cameras,
                   {"latch_pairing"}, &extra);
      if (const YAML::Node* p = Reader::Find(extra, "latch_pairing")) {
        const std::string pairing_field = Join(options_field, "latch_pairing");
        const std::string pairing_expected =
            "which board latch goes with a frame: latest (the newest at grab time) or offset "
            "(the latch of board frame = the buffer offset + frame_offset)";
        const std::string pairing = r.Text(*p, pairing_field, pairing_expected);
        if (pairing == "latest") {
          g.cameras.latch_pairing = LatchPairing::kLatest;
        } else if (pairing == "offset") {
          g.cameras.latch_pairing = LatchPairing::kOffset;
        } else {
          r.Fail(*p, pairing_field, pairing_expected);
        }
      }
    }
    d.backend = g;
    return d;
  }
  const Entries e = r.MapOf(n, field, {"driver", "port", "baud", "framing", "options"},
                            "a serial device: driver, port and optionally baud, framing, options");
  const SerialConfig serial = ParseSerial(r, e, n, field, *kind);
  const YAML::Node* options = Reader::Find(e, "options");
  if (driver == "val2") {
    Val2Backend b{serial, {}};
    if (options) ParseOptions(r, *options, options_field, Val2Fields(), "the VAL II driver", &b.options);
    d.backend = b;
  } else if (driver == "sensorhand") {
    SensorHandBackend b{serial, {}};
    if (options) {
      ParseOptions(r, *options, options_field, SensorHandFields(), "the SensorHand driver",
                   &b.options);
    }
    d.backend = b;
  } else if (driver == "biclops") {
    BiclopsBackend b{serial, DefaultBiclopsOptions()};
    if (options) b.options = ParseBiclopsOptions(r, *options, options_field);
    d.backend = b;
  } else {
    LaserBoardBackend b{serial, {}};
    if (options) {
      ParseOptions(r, *options, options_field, LaserBoardFields(), "the laser board driver",
                   &b.options);
    }
    d.backend = b;
  }
  return d;
}

bool SameLine(const SerialConfig& a, const SerialConfig& b) {
  return a.baud == b.baud && a.data_bits == b.data_bits && a.parity == b.parity &&
         a.stop_bits == b.stop_bits;
}

void CheckAcrossDevices(const Reader& r, const DevicesConfig& s, const YAML::Node& devices) {
  // The camera driver takes the laser's encoder count latched at each exposure from the board.
  if (s.Backend<GstreamerBackend>("cameras") != nullptr &&
      s.Backend<LaserBoardBackend>("laser") == nullptr) {
    r.Fail(devices["cameras"]["driver"], "devices.cameras.driver",
           "sim, unless devices.laser is the laser_board too: real cameras take the laser's "
           "encoder count latched at each frame from the board");
  }
  // One port, one device; the laser and the LEDs share the laser board. Ports are compared by
  // the device they open, not by how their paths are spelled.
  std::map<std::string, std::string> owner;  // port identity -> device key
  for (const auto& [key, d] : s.entries) {
    const SerialConfig* serial = d.serial();
    if (serial == nullptr) continue;
    const auto [it, fresh] = owner.emplace(PortIdentity(serial->port), key);
    if (fresh) continue;
    const DeviceConfig& other = s.entries.at(it->second);
    const bool board = d.driver() == "laser_board" && other.driver() == "laser_board";
    if (!board) {
      r.Fail(devices[key]["port"], Join(Join("devices", key), "port"),
             "a port of its own (devices." + it->second + " uses it, as " + other.serial()->port +
                 ")");
    }
    if (!SameLine(*serial, *other.serial())) {
      r.Fail(devices[key]["port"], Join(Join("devices", key), "port"),
             "the laser and the LEDs on one board: the same baud and framing as devices." +
                 it->second);
    }
  }
  const auto* laser = s.Backend<LaserBoardBackend>("laser");
  const auto* leds = s.Backend<LaserBoardBackend>("leds");
  if (laser != nullptr && leds != nullptr &&
      PortIdentity(laser->serial.port) != PortIdentity(leds->serial.port)) {
    r.Fail(devices["leds"]["port"], "devices.leds.port",
           "the laser's port, " + laser->serial.port + " (the laser and the LEDs are one board)");
  }
}

}  // namespace

std::string_view DeviceConfig::driver() const {
  return std::visit(
      [](const auto& b) -> std::string_view {
        using B = std::decay_t<decltype(b)>;
        if constexpr (std::is_same_v<B, SimulatedBackend>) return "sim";
        if constexpr (std::is_same_v<B, Val2Backend>) return "val2";
        if constexpr (std::is_same_v<B, SensorHandBackend>) return "sensorhand";
        if constexpr (std::is_same_v<B, BiclopsBackend>) return "biclops";
        if constexpr (std::is_same_v<B, LaserBoardBackend>) return "laser_board";
        if constexpr (std::is_same_v<B, GstreamerBackend>) return "gstreamer";
      },
      backend);
}

const SerialConfig* DeviceConfig::serial() const {
  return std::visit(
      [](const auto& b) -> const SerialConfig* {
        if constexpr (requires { b.serial; }) {
          return &b.serial;
        } else {
          return nullptr;
        }
      },
      backend);
}

const DeviceConfig* DevicesConfig::Find(std::string_view key) const {
  const auto it = entries.find(std::string(key));
  return it == entries.end() ? nullptr : &it->second;
}

bool DevicesConfig::Simulated(std::string_view key) const {
  const DeviceConfig* d = Find(key);
  return d == nullptr || d->simulated();
}

bool DevicesConfig::AllSimulated() const {
  return std::all_of(kDeviceKeys.begin(), kDeviceKeys.end(),
                     [&](std::string_view k) { return Simulated(k); });
}

bool DevicesConfig::AnySimulated() const {
  return std::any_of(kDeviceKeys.begin(), kDeviceKeys.end(),
                     [&](std::string_view k) { return Simulated(k); });
}

DevicesConfig ParseDevices(const Reader& r, const YAML::Node& devices) {
  const Keys keys(kDeviceKeys.begin(), kDeviceKeys.end());
  const Entries de = r.MapOf(devices, "devices", keys,
                             "a map from device to backend, e.g. {head: {driver: sim}}");
  DevicesConfig s;
  for (const auto& [key, entry] : de) {
    s.entries.emplace(key, ParseDevice(r, entry.value, key, Join("devices", key)));
  }
  CheckAcrossDevices(r, s, devices);
  return s;
}

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

std::string Framing(const SerialConfig& c) {
  const char parity = c.parity == Parity::kEven ? 'E' : c.parity == Parity::kOdd ? 'O' : 'N';
  return std::to_string(c.data_bits) + parity + std::to_string(c.stop_bits);
}

}  // namespace hgrasp::drivers
