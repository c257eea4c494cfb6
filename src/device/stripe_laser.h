#pragma once
/// @file The laser stripe generator: a light plane turned about a vertical axis by a DC motor,
/// its angle read by an optical encoder (the "laser board").

#include <cstdint>

#include "device/status.h"

namespace hgrasp::device {

struct StripeLaserState {
  double t_s = 0.0;
  std::int32_t encoder_count = 0;  ///< motor angle in encoder counts (0: straight ahead)
  bool laser_on = false;
  bool moving = false;
};

class StripeLaser {
 public:
  virtual ~StripeLaser() = default;
  virtual Status Read(StripeLaserState* state) = 0;
  virtual Status SetLaser(bool on) = 0;
  /// Turn the motor to an encoder count at `speed_counts_s` (> 0). A scan is a MoveTo across the
  /// scene while frames are grabbed: each frame latches the count at its exposure.
  virtual Status MoveTo(std::int32_t count, double speed_counts_s) = 0;
  /// Stop the motor where it is (the safe stop, DESIGN.md rule 8; the laser stays as it is).
  virtual Status Stop() = 0;
};

}  // namespace hgrasp::device
