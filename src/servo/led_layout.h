#pragma once
/// @file Where the LEDs sit on each gripper: their positions in the gripper frame E, read from a
/// calibration file (calibration/sim/leds.yaml for the simulated robot; a real robot's file of
/// the same form overrides it by path).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "device/status.h"

namespace hgrasp::servo {

/// The LEDs of one gripper: p_E[i] is LED i (bit 1 << i of device::Leds::Set) in E (m).
struct LedLayout {
  std::vector<Eigen::Vector3d> p_E;
  int size() const { return static_cast<int>(p_E.size()); }
  /// The LEDs' centroid in E (m).
  Eigen::Vector3d Centroid() const;
};

/// The layouts of both grippers.
struct LedLayouts {
  LedLayout left, right;
  const LedLayout& Of(device::Side side) const {
    return side == device::Side::kLeft ? left : right;
  }
};

/// Maximum number of LEDs per gripper (the width of device::Leds::Set's mask).
inline constexpr int kMaxLeds = 32;
/// Farthest an LED may be from the gripper frame's origin (m): the palm is 14 cm long and the
/// LEDs sit on it.
inline constexpr double kMaxLedDistance = 0.15;

/// Reads an LED layout file:
/// ```yaml
/// frame: gripper
/// left:  [[x, y, z], ...]   # LED i in the left gripper's frame EL, m
/// right: [[x, y, z], ...]   # LED i in the right gripper's frame ER, m
/// ```
/// Each side lists 3 to kMaxLeds finite positions within kMaxLedDistance of the origin, not all
/// on one line, no two closer than 1 mm. Read through yaml::ReadText and yaml::LoadDocument.
/// @throws hgrasp::InputError naming "FILE:LINE", the field (e.g. "left[2]"), the value and what
///         was expected, for a missing or unreadable file, bad YAML, unknown, repeated or missing
///         keys, wrong types, or positions that break the rules above.
LedLayouts LoadLedLayouts(const std::string& path);

/// As LoadLedLayouts, on the text of such a file (`path` names it in errors).
LedLayouts ParseLedLayouts(const std::string& text, const std::string& path);

}  // namespace hgrasp::servo
