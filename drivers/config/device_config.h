#pragma once
/// @file The robot's device configuration, typed per backend (DESIGN.md rule 2): the scenario's
/// `devices` block says for each device whether it is simulated or which real driver serves it,
/// on which port, with which of that driver's options. The composition root (src/app/) opens
/// the devices from it; a device not named is simulated.
///
/// ```yaml
/// devices:
///   arm_right: {driver: val2, port: /dev/ttyS0, options: {reply_timeout_s: 0.2}}
///   head: {driver: biclops, port: /dev/ttyS2, options: {pan: {max_speed_rad_s: 1.5}}}
///   cameras: {driver: gstreamer, left: "v4l2src ... ! appsink", right: "..."}
/// ```
/// Every option of a driver's Options struct can be set under `options`, by the field's name
/// (SI units; angles in rad unless the name ends in _deg).

#include <yaml-cpp/yaml.h>

#include <array>
#include <map>
#include <string>
#include <string_view>
#include <variant>

#include "biclops/biclops_head.h"
#include "camera/gst_stereo_camera.h"
#include "common/yaml_reader.h"
#include "laser_board/laser_board.h"
#include "sensorhand/sensorhand_hand.h"
#include "serial/serial_port.h"
#include "val2/val2_arm.h"

namespace hgrasp::drivers {

/// Device keys accepted under `devices:`.
inline constexpr std::array<std::string_view, 8> kDeviceKeys = {
    "arm_left", "arm_right", "hand_left", "hand_right", "head", "laser", "leds", "cameras"};

/// The device comes from the simulated robot (the twin).
struct SimulatedBackend {};
/// A Puma's controller over VAL II (val2/val2_arm.h).
struct Val2Backend {
  SerialConfig serial;
  Val2Options options;
};
/// An Otto Bock SensorHand Speed (sensorhand/sensorhand_hand.h).
struct SensorHandBackend {
  SerialConfig serial;
  SensorHandOptions options;
};
/// The Biclops head's PMD chip (biclops/biclops_head.h).
struct BiclopsBackend {
  SerialConfig serial;
  BiclopsOptions options = DefaultBiclopsOptions();
};
/// Our laser / motor / encoder / LED board (laser_board/laser_board.h).
struct LaserBoardBackend {
  SerialConfig serial;
  LaserBoardOptions options;
};
/// The stereo cameras through GStreamer (camera/gst_stereo_camera.h).
struct GstreamerBackend {
  GstCameraConfig cameras;
};

using Backend = std::variant<SimulatedBackend, Val2Backend, SensorHandBackend, BiclopsBackend,
                             LaserBoardBackend, GstreamerBackend>;

/// A real driver, the devices it can serve and its default baud rate.
struct DriverKind {
  std::string_view driver;
  std::array<std::string_view, 2> devices;  ///< keys of kDeviceKeys ("" when only one)
  int default_baud;                         ///< serial drivers; 0 for the cameras
};

inline constexpr std::array<DriverKind, 5> kDrivers = {{
    {"val2", {"arm_left", "arm_right"}, 9600},           // Puma controllers, VAL II
    {"sensorhand", {"hand_left", "hand_right"}, 19200},  // Otto Bock SensorHand Speed
    {"biclops", {"head", ""}, 9600},                     // PMD motion chips of the Biclops head
    {"laser_board", {"laser", "leds"}, 115200},          // our laser/LED board
    {"gstreamer", {"cameras", ""}, 0},                   // frame grabber through GStreamer
}};

/// One device's entry.
struct DeviceConfig {
  Backend backend;
  int line = 0;  ///< the entry's line in the file (1-based; 0: not from a file)

  /// "sim", "val2", "sensorhand", "biclops", "laser_board" or "gstreamer".
  std::string_view driver() const;
  bool simulated() const { return std::holds_alternative<SimulatedBackend>(backend); }
  /// The serial settings of a serial driver; nullptr for sim and the cameras.
  const SerialConfig* serial() const;
};

/// The `devices` block.
struct DevicesConfig {
  /// Keys among kDeviceKeys; a device not listed is simulated.
  std::map<std::string, DeviceConfig> entries;

  /// The entry of `key`, or nullptr when the device is simulated by default.
  const DeviceConfig* Find(std::string_view key) const;
  /// The backend of `key` when it is a B; else nullptr.
  template <class B>
  const B* Backend(std::string_view key) const {
    const DeviceConfig* d = Find(key);
    return d == nullptr ? nullptr : std::get_if<B>(&d->backend);
  }
  /// Whether `key` is simulated (listed as sim, or not listed).
  bool Simulated(std::string_view key) const;
  /// Whether every device is simulated (then the simulator's truth describes what they saw).
  bool AllSimulated() const;
  /// Whether any device is simulated (then the twin must be built).
  bool AnySimulated() const;
};

/// Parses and checks a `devices` map read by `reader` (the file's reader, for messages): each
/// key a device, each driver one that serves it, every setting and option of the right type and
/// range, one port per device (the laser and the LEDs share the board's), real cameras only
/// with the laser board (they take its encoder latches). Throws hgrasp::InputError.
DevicesConfig ParseDevices(const yaml::Reader& reader, const YAML::Node& devices);

/// What a serial port's path opens, for telling whether two paths are one port: the device
/// number of a character device (any path to it: a symlink, /dev//ttyS9, a second device node),
/// the inode of another existing file, else the path with its symlinks resolved and "//" and
/// "." taken out.
std::string PortIdentity(const std::string& port);

/// "8N1" of a serial configuration.
std::string Framing(const SerialConfig& serial);

}  // namespace hgrasp::drivers
