#pragma once
/// @file The red LEDs on each gripper, switched by the laser board.

#include <cstdint>

#include "device/status.h"

namespace hgrasp::device {

class Leds {
 public:
  virtual ~Leds() = default;
  /// Number of LEDs on one gripper.
  virtual int Count(Side side) const = 0;
  /// Bit i of `mask` switches LED i of that gripper on.
  virtual Status Set(Side side, std::uint32_t mask) = 0;
};

}  // namespace hgrasp::device
